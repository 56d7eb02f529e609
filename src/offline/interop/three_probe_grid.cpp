#include "interop/three_probe_grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <nlohmann/json.hpp>

#include "common/finite.h"
#include "common/input_error.h"
#include "interop/engine_light.h"
#include "shtool/sh.h"

namespace shtool::interop {
namespace {

// The slot count of three's atlas (27 floats and one 0 in RGBA texels) and its padding.
constexpr int kSlots = 7;
constexpr int kPadding = 1;

void put_float(std::string& bytes, std::size_t at, float v) {
  const std::uint32_t u = std::bit_cast<std::uint32_t>(v);
  for (int b = 0; b < 4; ++b) bytes[at + b] = static_cast<char>((u >> (8 * b)) & 0xff);
}

std::string json_name(const std::string& option) { return option + " probes.json"; }
std::string atlas_name(const std::string& option) { return option + " probes.bin"; }

}  // namespace

std::array<double, 27> zh3_as_order3_sh(std::span<const double, 12> l1, const double* zonal, Zh3Axis axis) {
  Zh3Probe<double> zh3;
  std::copy(l1.begin(), l1.end(), zh3.l1.coefficients.begin());
  for (int c = 0; c < 3; ++c) zh3.zonal[c] = zonal ? zonal[c] : zh3_hallucinated_zonal(zh3.l1, axis, c);
  const std::array<double, 15> band2 = zh3_band2(zh3, axis);
  std::array<double, 27> out{};
  std::copy(l1.begin(), l1.end(), out.begin());
  std::copy(band2.begin(), band2.end(), out.begin() + 12);
  return out;
}

ThreeProbeGridFiles three_probe_grid_files(const ThreeProbeGridInput& g) {
  const auto [nx, ny, nz] = g.resolution;
  for (int n : g.resolution)
    if (n < 1 || n > 4096)
      throw InputError("three.js probe grid: resolution " + std::to_string(n) + " is outside 1..4096");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(g.min[a]) || !std::isfinite(g.max[a]) || !(g.min[a] < g.max[a]))
      throw InputError("three.js probe grid: the bounds must be finite with min < max on every axis");
  if (g.order < 1 || g.order > kMaxOrder) throw InputError("three.js probe grid: order " + std::to_string(g.order) + " is not supported");
  const std::size_t per_probe = static_cast<std::size_t>(sh_count(g.order)) * 3;
  const std::size_t probes = static_cast<std::size_t>(nx) * ny * nz;
  if (g.coefficients.size() != probes * per_probe)
    throw InputError("three.js probe grid: " + std::to_string(g.coefficients.size()) + " coefficients for " +
                     std::to_string(probes) + " probes of order " + std::to_string(g.order) + " (expected " +
                     std::to_string(probes * per_probe) + ")");
  // three's resolution, (NX, NZ, NY).
  const int tx = nx, ty = nz, tz = ny;
  const std::size_t depth = static_cast<std::size_t>(kSlots) * (tz + 2 * kPadding);
  std::string atlas(static_cast<std::size_t>(tx) * ty * depth * 4 * sizeof(float), '\0');
  auto texel = [&](int x, int y, std::size_t s) { return ((s * ty + y) * tx + x) * 4 * sizeof(float); };
  for (int iz = 0; iz < nz; ++iz)
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix) {
        const std::size_t probe = (static_cast<std::size_t>(iz) * ny + iy) * nx + ix;
        std::array<double, 27> c{};
        for (std::size_t k = 0; k < std::min<std::size_t>(27, per_probe); ++k)
          c[k] = g.coefficients[probe * per_probe + k];
        const std::array<double, 27> t = threejs_sh3(c);
        for (int k = 0; k < 27; ++k)
          if (!finite_as_float(t[k]))
            throw InputError("three.js probe grid: probe (" + std::to_string(ix) + ", " + std::to_string(iy) + ", " +
                             std::to_string(iz) + ") has a coefficient that is not finite as float32");
        // three's (x, y, z) = (ix, iz, NY - 1 - iy).
        const int x = ix, y = iz, z = ny - 1 - iy;
        for (int slot = 0; slot < kSlots; ++slot) {
          const std::size_t base = static_cast<std::size_t>(slot) * (tz + 2 * kPadding);
          std::vector<std::size_t> slices = {base + kPadding + z};
          if (z == 0) slices.push_back(base);
          if (z == tz - 1) slices.push_back(base + kPadding + tz);
          for (std::size_t s : slices)
            for (int k = 0; k < 4; ++k) {
              const int i = 4 * slot + k;
              put_float(atlas, texel(x, y, s) + k * sizeof(float), i < 27 ? static_cast<float>(t[i]) : 0.0f);
            }
        }
      }
  const nlohmann::json doc = {
      {"three", kThreeVersion},
      {"resolution", {tx, ty, tz}},
      {"boundingBox",
       {{"min", {g.min.x(), g.min.z(), -g.max.y()}}, {"max", {g.max.x(), g.max.z(), -g.min.y()}}}},
      {"atlas", "probes.bin"}};
  return {dump_finite(doc, "probes.json", 2) + "\n", std::move(atlas)};
}

void declare_three_probe_grid(JobOutputs& io, const std::filesystem::path& dir, const std::string& option) {
  if (dir.empty()) return;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(option + " " + dir.string() + ": not an existing folder");
  io.output(dir / "probes.json", json_name(option));
  io.output(dir / "probes.bin", atlas_name(option));
}

void set_three_probe_grid(JobOutputs& io, const std::string& option, ThreeProbeGridFiles files) {
  io.set(json_name(option), std::move(files.json));
  io.set(atlas_name(option), std::move(files.atlas));
}

void write_three_probe_grid(const std::filesystem::path& dir, const ThreeProbeGridInput& grid) {
  JobOutputs io;
  declare_three_probe_grid(io, dir, "--threejs");
  set_three_probe_grid(io, "--threejs", three_probe_grid_files(grid));
  io.commit();
}

}  // namespace shtool::interop
