// The irradiance probe volume that `shtool bake-probes` writes (table kind "probe-grid",
// schemas/probe-grid.schema.json; docs/probes.md): an NX x NY x NZ grid of probes over a
// box [min, max] of shtool's frame, probe (ix, iy, iz) at the centre of its cell,
//   p = min + (i + 1/2) (max - min) / n  per axis,
// numbered ix fastest, then iy, then iz. Each probe holds the incident radiance at p as
// RGB SH coefficients of `order` (c_k = integral L(w) y_k(w) dw, index l(l+1)+m), and a
// valid flag: an invalid probe (inside geometry) holds values filled in from its valid
// neighbours.
//
// The per-point calls allocate nothing and throw nothing.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "shtool/result.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kProbeGridKind = "probe-grid";
// The highest order a probe grid holds (bake-probes' limit): the per-point calls keep
// their work in fixed-size arrays.
inline constexpr int kMaxProbeOrder = 8;

template <class T>
struct ProbeGrid {
  int order = 0;
  std::array<int, 3> resolution{0, 0, 0};  // NX, NY, NZ
  Vec3<T> min = Vec3<T>::Zero(), max = Vec3<T>::Zero();
  std::vector<T> coefficients;        // probe-major, then SH index, then r, g, b
  std::vector<std::uint8_t> valid;    // one per probe: 1 valid, 0 filled in

  std::size_t probe_count() const { return valid.size(); }
  std::size_t probe_index(int ix, int iy, int iz) const {
    return (static_cast<std::size_t>(iz) * resolution[1] + iy) * resolution[0] + ix;
  }
  std::array<int, 3> grid_index(std::size_t probe) const;
  Vec3<T> position(std::size_t probe) const;
  bool is_valid(std::size_t probe) const { return valid[probe] != 0; }
  // The probe's N^2 x 3 coefficients, [k * 3 + c].
  std::span<const T> coefficients_of(std::size_t probe) const {
    const std::size_t n = static_cast<std::size_t>(order) * order * 3;
    return {coefficients.data() + probe * n, n};
  }

  // Irradiance E(n) = integral L(w) max(n.w, 0) dw (no 1/pi) of one probe, RGB: the
  // clamped-cosine kernel A_l applied to its radiance coefficients. n: unit normal.
  Vec3<T> irradiance(std::size_t probe, const Vec3<T>& normal) const noexcept;
  // Radiance coefficients at x by trilinear interpolation between the eight probes
  // around it (x clamped to the box of probe centres), into out[N^2 * 3].
  void sample(const Vec3<T>& x, std::span<T> out) const noexcept;

  // Checks kind, order (1..kMaxProbeOrder), shapes, bounds (finite, min < max), finite
  // coefficients and flags 0 or 1; refuses a partial table.
  static Result<ProbeGrid> from_table(const Table& table);
  // read_table + from_table, the path prefixed to any message.
  static Result<ProbeGrid> load(const std::filesystem::path& path);
};

extern template struct ProbeGrid<float>;
extern template struct ProbeGrid<double>;

}  // namespace shtool
