// Compact encodings of an irradiance probe: Geomerics' non-linear L1 and ZH3
// (docs/probe-encodings.md). Input: a probe's radiance coefficients in shtool's basis
// (real orthonormal, Condon-Shortley phase, index l(l+1)+m, z up), RGB interleaved as
// radiance[3 i + c]. Output irradiance E(n) = integral L(w) max(n . w, 0) dw, with no
// 1/pi folded in (shtool/irradiance.h).
//
// Notation, per colour channel: c00 = radiance[c], and the L1 vector d = (-c_11, -c_1-1,
// c_10), so that the band-1 part of L is k1 d . w with k1 = sqrt(3 / (4 pi)).
//
// - Non-linear L1 (Hazel, "Converting SH radiance to irradiance", 2017): with the mean
//   radiance R0 = c00 / sqrt(4 pi) and R1 = d / sqrt(12 pi), r = |R1| / R0,
//   q = (1 + n . R1 / |R1|) / 2, p = 1 + 2 r, a = (1 - r) / (1 + r):
//     E(n) = pi R0 (a + (1 - a) (p + 1) q^p).
//   Exact for a constant light (r = 0) and, at n = s, for a single directional light along s.
// - ZH3 (Roughton, Sloan, Silvennoinen, Iwanicki, Shirley, "ZH3: Quadratic Zonal
//   Harmonics", i3D 2024): L1 plus one zonal band-2 coefficient f per channel along an
//   axis a derived from the stored L1 band, so a probe stores 4 + 1 numbers per channel:
//     L(w) ~ c00 y00 + k1 d . w + f sqrt(5 / (16 pi)) (3 (a . w)^2 - 1),
//     E(n) = pi c00 y00 + (2 pi / 3) k1 d . n + (pi / 4) f sqrt(5 / (16 pi)) (3 (a . n)^2 - 1).
//   The axis is the luminance-weighted one, a = normalise(sum_c w_c d_c) with
//   w = (0.2126, 0.7152, 0.0722) (the default, shared by the three channels), or each
//   channel's own d_c / |d_c|. A zero L1 vector (the channel's, or the weighted sum) has
//   no direction: +z is taken.
//   Explicit f: the least-squares fit of the band-2 coefficients c_2m by a zonal function
//   along a, f = sqrt(4 pi / 5) sum_m c_2m y_2^m(a).
//   Hallucinated f (no band 2 needed, nothing extra stored): with r = |d . a| / c00,
//   f = c00 r (0.08 + 0.6 r) (the paper's curve fit to production probes).
//
// Allocation-free, exception-free; float and double, each computing in its own precision.
// Normals must be unit vectors (precondition, not checked).
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string_view>

#include "shtool/sh.h"

namespace shtool {

// Rec. 709 / sRGB luminance weights of the shared ZH3 axis.
inline constexpr std::array<double, 3> kZh3LuminanceWeights = {0.2126, 0.7152, 0.0722};

enum class Zh3Axis { luminance, per_channel };
enum class Zh3Fit { explicit_fit, hallucinated };

// What a probe stores: l2, its radiance coefficients of the grid's order (linear
// reconstruction with the clamped-cosine kernel); l1, bands 0 and 1 (non-linear L1
// reconstruction); zh3, bands 0 and 1 and one zonal coefficient per channel.
enum class ProbeEncoding { l2, l1, zh3 };

// "l2", "l1", "zh3" (bake-probes --encoding, the probe-grid table's meta.encoding).
std::string_view probe_encoding_name(ProbeEncoding encoding) noexcept;
std::optional<ProbeEncoding> parse_probe_encoding(std::string_view name) noexcept;
// "luminance", "per-channel".
std::string_view zh3_axis_name(Zh3Axis axis) noexcept;
std::optional<Zh3Axis> parse_zh3_axis(std::string_view name) noexcept;
// "explicit", "hallucinated" (bake-probes --zh3-fit, the probe-grid table's meta.zh3_fit).
std::string_view zh3_fit_name(Zh3Fit fit) noexcept;
std::optional<Zh3Fit> parse_zh3_fit(std::string_view name) noexcept;

// Bands 0 and 1 of an RGB probe: coefficients[3 i + c], i = 0..3 (shtool's basis).
template <class T>
struct L1Probe {
  std::array<T, 12> coefficients{};
};

// ZH3 storage: the L1 band and one zonal coefficient per channel (the axis comes back
// from the L1 band and the Zh3Axis the probe was encoded with).
template <class T>
struct Zh3Probe {
  L1Probe<T> l1;
  std::array<T, 3> zonal{};
};

// Bands 0 and 1 of RGB radiance coefficients of any order >= 2 (radiance.size() >= 12).
template <class T>
L1Probe<T> encode_l1(std::span<const T> radiance);

// Non-linear L1 irradiance of one channel from c00 and d (above); 0 when c00 <= 0 (no
// light with a non-positive mean is non-negative).
template <class T>
T l1_nonlinear_irradiance(T c00, const Vec3<T>& d, const Vec3<T>& n);
// The three channels of a probe.
template <class T>
Vec3<T> l1_nonlinear_irradiance(const L1Probe<T>& probe, const Vec3<T>& n);

// The L1 vector d of channel c.
template <class T>
Vec3<T> l1_vector(const L1Probe<T>& probe, int channel);

// The ZH3 axis of channel c (unit; the same for every channel with Zh3Axis::luminance).
template <class T>
Vec3<T> zh3_axis(const L1Probe<T>& probe, Zh3Axis axis, int channel);

// f of the explicit fit from band-2 coefficients c_2m (band2[3 m' + c], m' = m + 2) of
// one channel along a unit axis.
template <class T>
T zh3_explicit_zonal(std::span<const T> band2, int channel, const Vec3<T>& axis);
// f of the hallucinated variant of one channel from the L1 band alone.
template <class T>
T zh3_hallucinated_zonal(const L1Probe<T>& probe, Zh3Axis axis, int channel);

// Encoding of RGB radiance coefficients: explicit_fit needs order >= 3
// (radiance.size() >= 27), hallucinated order >= 2 (>= 12).
template <class T>
Zh3Probe<T> encode_zh3(std::span<const T> radiance, Zh3Axis axis, Zh3Fit fit);

// E(n) of a stored ZH3 probe.
template <class T>
Vec3<T> zh3_irradiance(const Zh3Probe<T>& probe, Zh3Axis axis, const Vec3<T>& n);

// Band-2 radiance coefficients the zonal term stands for: sqrt(4 pi / 5) f y_2^m(a), as
// band2[3 m' + c] (15 values), for a renderer that takes plain order-3 SH.
template <class T>
std::array<T, 15> zh3_band2(const Zh3Probe<T>& probe, Zh3Axis axis);

}  // namespace shtool
