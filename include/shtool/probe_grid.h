// The irradiance probe volume that `shtool bake-probes` writes (table kind "probe-grid",
// schemas/probe-grid.schema.json; docs/probes.md): an NX x NY x NZ grid of probes over a
// box [min, max] of shtool's frame, probe (ix, iy, iz) at the centre of its cell,
//   p = min + (i + 1/2) (max - min) / n  per axis,
// numbered ix fastest, then iy, then iz. Each probe holds the incident radiance at p as
// RGB SH coefficients of `order` (c_k = integral L(w) y_k(w) dw, index l(l+1)+m), and a
// valid flag: an invalid probe (inside geometry) holds values filled in from its valid
// neighbours.
//
// The grid's encoding (shtool/probe_encoding.h; bake-probes --encoding, --zh3-fit,
// --zh3-axis) says what a probe stores and how its irradiance is reconstructed: l2, the
// coefficients of `order`, linear; l1, bands 0 and 1 (order 2), Geomerics' non-linear L1;
// zh3, bands 0 and 1 (order 2) and a zonal band-2 coefficient per channel along the axis
// `zh3_axis` derives from the L1 band. With the explicit fit that coefficient is stored
// (fitted to band 2 at bake time); hallucinated, nothing is stored beyond L1 and the
// coefficient is reconstructed from the L1 band being evaluated (zh3_hallucinated_zonal),
// as a shader does after filtering the L1 texture.
//
// Table versions: kind_version 1.0 tables (written before meta.zh3_fit) are read with the
// explicit fit for zh3 and l2 when meta.encoding is absent; 1.1 tables name zh3_fit; a
// newer minor is read by the same rules; another major is refused.
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

#include "shtool/probe_encoding.h"
#include "shtool/result.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kProbeGridKind = "probe-grid";
// The layout bake-probes writes: 1.1 added meta.zh3_fit to every zh3 table, the
// hallucinated variant (no 'zonal' array) and the per-channel axis.
inline constexpr std::string_view kProbeGridKindVersion = "1.1";
// The highest order a probe grid holds (bake-probes' limit): the per-point calls keep
// their work in fixed-size arrays.
inline constexpr int kMaxProbeOrder = 8;

// The most values one probe stores (order kMaxProbeOrder, l2).
inline constexpr std::size_t kMaxProbeValues = std::size_t(kMaxProbeOrder) * kMaxProbeOrder * 3;

template <class T>
struct ProbeGrid {
  int order = 0;
  ProbeEncoding encoding = ProbeEncoding::l2;
  Zh3Axis zh3_axis = Zh3Axis::luminance;   // zh3 only
  Zh3Fit zh3_fit = Zh3Fit::explicit_fit;   // zh3 only: hallucinated stores no zonal values
  std::array<int, 3> resolution{0, 0, 0};  // NX, NY, NZ
  Vec3<T> min = Vec3<T>::Zero(), max = Vec3<T>::Zero();
  // Probe-major, values_per_probe() each: the N^2 x 3 coefficients [k * 3 + c], then for
  // explicit zh3 the zonal coefficient of r, g, b.
  std::vector<T> coefficients;
  std::vector<std::uint8_t> valid;    // one per probe: 1 valid, 0 filled in

  std::size_t probe_count() const { return valid.size(); }
  bool stores_zonal() const { return encoding == ProbeEncoding::zh3 && zh3_fit == Zh3Fit::explicit_fit; }
  std::size_t values_per_probe() const {
    return static_cast<std::size_t>(order) * order * 3 + (stores_zonal() ? 3 : 0);
  }
  std::size_t probe_index(int ix, int iy, int iz) const {
    return (static_cast<std::size_t>(iz) * resolution[1] + iy) * resolution[0] + ix;
  }
  std::array<int, 3> grid_index(std::size_t probe) const;
  Vec3<T> position(std::size_t probe) const;
  bool is_valid(std::size_t probe) const { return valid[probe] != 0; }
  // The probe's stored values: N^2 x 3 coefficients [k * 3 + c] (then 3 zonal ones for
  // explicit zh3).
  std::span<const T> coefficients_of(std::size_t probe) const {
    const std::size_t n = values_per_probe();
    return {coefficients.data() + probe * n, n};
  }

  // Irradiance E(n) = integral L(w) max(n.w, 0) dw (no 1/pi), RGB, of stored values (a
  // probe's, or sample's output) by the grid's encoding: l2, the clamped-cosine kernel A_l
  // applied to the radiance coefficients; l1, l1_nonlinear_irradiance; zh3, zh3_irradiance
  // (hallucinated: of the zonal coefficients zh3_hallucinated_zonal gives for these values).
  // n: unit normal; values: values_per_probe() of them.
  Vec3<T> irradiance_of(std::span<const T> values, const Vec3<T>& normal) const noexcept;
  // irradiance_of one probe.
  Vec3<T> irradiance(std::size_t probe, const Vec3<T>& normal) const noexcept;
  // The stored values at x by trilinear interpolation between the eight probes around it
  // (x clamped to the box of probe centres), into out[values_per_probe()] (as a GPU's
  // filtering of the stored values does, also for l1 and zh3; hallucinated zh3 then
  // reconstructs its zonal coefficient from the interpolated L1 band).
  void sample(const Vec3<T>& x, std::span<T> out) const noexcept;
  // irradiance_of the values sample gives at x.
  Vec3<T> irradiance_at(const Vec3<T>& x, const Vec3<T>& normal) const noexcept;

  // Checks kind, kind_version (major 1), order (1..kMaxProbeOrder; 2 for l1 and zh3),
  // meta.encoding (absent: l2), meta.zh3_axis and meta.zh3_fit (required from 1.1; absent
  // in 1.0: explicit), shapes, bounds (finite, min < max), finite coefficients (explicit
  // zh3's array 'zonal' [NZ, NY, NX, 3], absent for hallucinated) and flags 0 or 1;
  // refuses a partial table.
  static Result<ProbeGrid> from_table(const Table& table);
  // read_table + from_table, the path prefixed to any message.
  static Result<ProbeGrid> load(const std::filesystem::path& path);
};

extern template struct ProbeGrid<float>;
extern template struct ProbeGrid<double>;

}  // namespace shtool
