#include "interop/splat_scene.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>

#include <Eigen/Geometry>

#include "common/input_file.h"
#include "common/input_error.h"
#include "common/parallel_for.h"
#include "shtool/orthogonal_map.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool::interop {

void SplatScene::set_degree(int deg) {
  if (deg == degree) return;
  const std::size_t from = sh_stride();
  const std::size_t to = 3 * static_cast<std::size_t>((deg + 1) * (deg + 1));
  std::vector<float> out(to * count, 0.0f);
  const std::size_t keep = std::min(from, to);
  for (std::size_t i = 0; i < count; ++i)
    std::copy_n(sh.begin() + static_cast<std::ptrdiff_t>(i * from), keep, out.begin() + static_cast<std::ptrdiff_t>(i * to));
  sh = std::move(out);
  degree = deg;
}

SplatFormat splat_format_of(const std::filesystem::path& path, const std::string& what) {
  const std::string ext = lowercase_extension(path);
  if (ext == ".ply") return SplatFormat::ply;
  if (ext == ".spz") return SplatFormat::spz;
  if (ext == ".gltf") return SplatFormat::gltf;
  if (ext == ".glb") return SplatFormat::glb;
  throw InputError(what + " " + path.string() + ": unknown splat format '" + ext +
                   "' (.ply, .spz, .gltf or .glb by extension)");
}

const char* splat_colour_space_name(SplatColourSpace space) {
  return space == SplatColourSpace::lin_rec709_display ? "lin_rec709_display" : "srgb_rec709_display";
}

std::optional<SplatColourSpace> parse_splat_colour_space(std::string_view name) {
  if (name == "srgb_rec709_display") return SplatColourSpace::srgb_rec709_display;
  if (name == "lin_rec709_display") return SplatColourSpace::lin_rec709_display;
  return std::nullopt;
}

const char* splat_format_name(SplatFormat format) {
  switch (format) {
    case SplatFormat::ply: return "PLY";
    case SplatFormat::spz: return "spz";
    case SplatFormat::gltf: return "glTF";
    case SplatFormat::glb: return "glb";
  }
  return "?";
}

std::optional<NonFiniteValue> first_non_finite(const SplatScene& s) {
  const std::size_t stride = s.sh_stride();
  for (std::size_t i = 0; i < s.count; ++i) {
    auto finite = [&](const std::vector<float>& v, std::size_t per) {
      for (std::size_t k = 0; k < per; ++k)
        if (!std::isfinite(v[i * per + k])) return false;
      return true;
    };
    if (!finite(s.position, 3)) return NonFiniteValue{i, "position"};
    if (!finite(s.log_scale, 3)) return NonFiniteValue{i, "scale"};
    if (!finite(s.rotation, 4)) return NonFiniteValue{i, "rotation"};
    if (!finite(s.opacity, 1)) return NonFiniteValue{i, "opacity"};
    if (!finite(s.sh, stride)) return NonFiniteValue{i, "SH colour"};
  }
  return std::nullopt;
}

void check_scene_finite(const SplatScene& s, const std::string& name) {
  if (const auto bad = first_non_finite(s))
    throw InputError(name + ": splat " + std::to_string(bad->splat) + ": its " + bad->what + " is not finite");
}

std::array<float, 4> unit_rotation(const float* wxyz) {
  const double q[4] = {wxyz[0], wxyz[1], wxyz[2], wxyz[3]};
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 0)) return {1.0f, 0.0f, 0.0f, 0.0f};
  return {static_cast<float>(q[0] / norm), static_cast<float>(q[1] / norm), static_cast<float>(q[2] / norm),
          static_cast<float>(q[3] / norm)};
}

SplatShLanes::SplatShLanes(const OrthogonalMap& map) : order_(map.order()), reflects_(map.reflects()) {
  // The rotation OrthogonalMap applies (its proper part, the reference method).
  ShRotation<double> rotation(order_, nullptr);
  rotation.set(map.proper(), RotationMethod::reference);
  const std::span<const double> blocks = rotation.reference_blocks();
  blocks_.assign(blocks.begin(), blocks.end());
}

// Also compiled for x86-64-v3 (AVX2: four lanes a vector, not two) and chosen at load
// time where the CPU has it; products and sums stay separate roundings (the offline code
// is built with -ffp-contract=off), so both copies give the same bits.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void SplatShLanes::apply(const double* in, double* out) const {
  // Two vectors of four lanes (one register each under AVX2, two SSE2 registers
  // otherwise), written out: left to itself GCC vectorised along the rows, with shuffles.
  using V = double __attribute__((vector_size(4 * sizeof(double))));
  static_assert(kLanes == 8);
  // By reference: a vector passed by value would change the baseline copy's ABI (-Wpsabi).
  auto load = [](V& v, const double* p) { std::memcpy(&v, p, sizeof v); };
  auto store = [](double* p, const V& v) { std::memcpy(p, &v, sizeof v); };
  const int rest = sh_count(order_) - 1;
  for (int c = 0; c < 3; ++c) {
    const double* x = in + c * rest * kLanes;
    double* y = out + c * rest * kLanes;
    for (int l = 1; l < order_; ++l) {
      const int size = 2 * l + 1, first = l * l - 1;
      const double* block = blocks_.data() + l * (4 * l * l - 1) / 3;
      const double* xl = x + first * kLanes;
      double* yl = y + first * kLanes;
      const bool negate = reflects_ && (l & 1);
      for (int r = 0; r < size; ++r) {
        // As ShRotation's reference apply: the first product, then each next one added.
        const double* row = block + r * size;
        V a, b;
        load(a, xl);
        load(b, xl + 4);
        V lo = row[0] * a, hi = row[0] * b;
        for (int k = 1; k < size; ++k) {
          load(a, xl + k * kLanes);
          load(b, xl + k * kLanes + 4);
          lo += row[k] * a;
          hi += row[k] * b;
        }
        if (negate) lo = -lo, hi = -hi;
        store(yl + r * kLanes, lo);
        store(yl + r * kLanes + 4, hi);
      }
    }
  }
}

SplatMotion::SplatMotion(const Eigen::Matrix3d& m, double scale, const Eigen::Vector3d& t,
                         const std::optional<std::array<double, 4>>& quaternion)
    : m(m),
      scale(scale),
      t(t),
      turn(quaternion
               ? Eigen::Quaterniond((*quaternion)[0], (*quaternion)[1], (*quaternion)[2], (*quaternion)[3]).normalized()
               : Eigen::Quaterniond(m.determinant() < 0 ? Eigen::Matrix3d(-m) : m)),
      log_s(std::log(scale)),
      moves(!m.isIdentity(0) || scale != 1 || !t.isZero(0)) {}

void transform_splat_scene(SplatScene& s, const Eigen::Matrix3d& m, double scale, const Eigen::Vector3d& t,
                           int threads) {
  if (m.isIdentity(0) && scale == 1 && t.isZero(0)) return;
  Result<OrthogonalMap> made = OrthogonalMap::make(m, s.degree + 1, 1e-6);
  if (!made) throw InputError("a splat transform: " + made.error().message);
  const SplatShLanes lanes(made.value());
  const SplatMotion motion(m, scale, t);
  const std::size_t rest = static_cast<std::size_t>((s.degree + 1) * (s.degree + 1)) - 1;
  const std::size_t stride = s.sh_stride();
  constexpr std::size_t kChunk = 4096;
  parallel_for((s.count + kChunk - 1) / kChunk, threads, [&](std::size_t chunk) {
    const std::size_t begin = chunk * kChunk, end = std::min(s.count, (chunk + 1) * kChunk);
    for (std::size_t i = begin; i < end; ++i) {
      float* p = &s.position[3 * i];
      const Eigen::Vector3d moved = motion.position(Eigen::Vector3d(p[0], p[1], p[2]));
      for (int k = 0; k < 3; ++k) p[k] = static_cast<float>(moved[k]);
      float* q = &s.rotation[4 * i];
      const Eigen::Quaterniond out = motion.orientation(Eigen::Quaterniond(q[0], q[1], q[2], q[3]));
      q[0] = static_cast<float>(out.w()), q[1] = static_cast<float>(out.x()), q[2] = static_cast<float>(out.y()),
      q[3] = static_cast<float>(out.z());
      for (int k = 0; k < 3; ++k) s.log_scale[3 * i + k] = static_cast<float>(motion.log_scale(s.log_scale[3 * i + k]));
    }
    if (rest == 0) return;
    // The SH of SplatShLanes::kLanes splats at once, channel-major in the lanes.
    constexpr std::size_t L = SplatShLanes::kLanes;
    double in[45 * L], out[45 * L];
    for (std::size_t b = begin; b < end; b += L) {
      const std::size_t n = std::min(L, end - b);
      for (int c = 0; c < 3; ++c)
        for (std::size_t k = 1; k <= rest; ++k) {
          double* x = in + (c * rest + k - 1) * L;
          for (std::size_t j = 0; j < n; ++j) x[j] = s.sh[(b + j) * stride + 3 * k + c];
          for (std::size_t j = n; j < L; ++j) x[j] = 0;
        }
      lanes.apply(in, out);
      for (int c = 0; c < 3; ++c)
        for (std::size_t k = 1; k <= rest; ++k)
          for (std::size_t j = 0; j < n; ++j)
            s.sh[(b + j) * stride + 3 * k + c] = static_cast<float>(out[(c * rest + k - 1) * L + j]);
    }
  });
}

}  // namespace shtool::interop
