#include "shtool/probe_encoding.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <numbers>

#include "precondition.h"

namespace shtool {
namespace {

template <class T>
struct Constants {
  static constexpr long double pi = std::numbers::pi_v<long double>;
  // y00 = 1 / sqrt(4 pi); k1 = sqrt(3 / (4 pi)); the l = 2 zonal constant sqrt(5 / (16 pi)).
  static constexpr T y00 = static_cast<T>(0.28209479177387814347403972578038629L);
  static constexpr T k1 = static_cast<T>(0.48860251190291992158638462283834700L);
  static constexpr T k20 = static_cast<T>(0.31539156525252000603089369029571050L);
  // Hazel's R0 = c00 / sqrt(4 pi) (= y00 c00) and R1 = d / sqrt(12 pi).
  static constexpr T r1_scale = static_cast<T>(0.16286750396763997386212820761278233L);
  // sqrt(4 pi / 5): the zonal function of unit coefficient along a has band-2 SH
  // coefficients sqrt(4 pi / 5) y_2^m(a) (addition theorem).
  static constexpr T zonal_to_sh = static_cast<T>(1.5853309190424044053380115060480732L);
  static constexpr T a0 = static_cast<T>(pi);
  static constexpr T a1 = static_cast<T>(2 * pi / 3);
  static constexpr T a2 = static_cast<T>(pi / 4);
};

template <class T>
Vec3<T> unit_or_z(const Vec3<T>& v) {
  const T length = v.norm();
  // A zero L1 band has no direction; any axis serves (docs in the header).
  if (!(length > 0)) return Vec3<T>(0, 0, 1);
  return v / length;
}

// The value among `values` that name_of names `name`: the inverse of the *_name functions.
template <class E, class NameOf>
std::optional<E> parse_name(std::string_view name, std::initializer_list<E> values, NameOf name_of) noexcept {
  for (const E e : values)
    if (name_of(e) == name) return e;
  return std::nullopt;
}

}  // namespace

std::string_view probe_encoding_name(ProbeEncoding encoding) noexcept {
  switch (encoding) {
    case ProbeEncoding::l1: return "l1";
    case ProbeEncoding::zh3: return "zh3";
    case ProbeEncoding::l2: break;
  }
  return "l2";
}

std::optional<ProbeEncoding> parse_probe_encoding(std::string_view name) noexcept {
  return parse_name(name, {ProbeEncoding::l2, ProbeEncoding::l1, ProbeEncoding::zh3}, probe_encoding_name);
}

std::string_view zh3_axis_name(Zh3Axis axis) noexcept {
  return axis == Zh3Axis::per_channel ? "per-channel" : "luminance";
}

std::optional<Zh3Axis> parse_zh3_axis(std::string_view name) noexcept {
  return parse_name(name, {Zh3Axis::luminance, Zh3Axis::per_channel}, zh3_axis_name);
}

std::string_view zh3_fit_name(Zh3Fit fit) noexcept {
  return fit == Zh3Fit::hallucinated ? "hallucinated" : "explicit";
}

std::optional<Zh3Fit> parse_zh3_fit(std::string_view name) noexcept {
  return parse_name(name, {Zh3Fit::explicit_fit, Zh3Fit::hallucinated}, zh3_fit_name);
}

template <class T>
L1Probe<T> encode_l1(std::span<const T> radiance) {
  if (radiance.size() < 12) detail::precondition_failed("encode_l1: fewer than 4 RGB coefficients");
  L1Probe<T> p;
  for (int k = 0; k < 12; ++k) p.coefficients[k] = radiance[k];
  return p;
}

template <class T>
Vec3<T> l1_vector(const L1Probe<T>& p, int c) {
  const auto& x = p.coefficients;
  return Vec3<T>(-x[3 * 3 + c], -x[3 * 1 + c], x[3 * 2 + c]);
}

template <class T>
T l1_nonlinear_irradiance(T c00, const Vec3<T>& d, const Vec3<T>& n) {
  using K = Constants<T>;
  const T r0 = K::y00 * c00;
  if (!(r0 > 0)) return 0;
  const Vec3<T> r1 = K::r1_scale * d;
  const T length = r1.norm();
  const T r = length / r0;
  // At r = 0 the weight (1 - a) of the directional term is 0: q is not needed.
  // (clamped at 0: rounding must not hand pow a negative base)
  const T q = length > 0 ? std::max(T(0), (1 + n.dot(r1) / length) / 2) : T(1) / 2;
  const T p = 1 + 2 * r;
  const T a = (1 - r) / (1 + r);
  return K::a0 * r0 * (a + (1 - a) * (p + 1) * std::pow(q, p));
}

template <class T>
Vec3<T> l1_nonlinear_irradiance(const L1Probe<T>& probe, const Vec3<T>& n) {
  Vec3<T> e;
  for (int c = 0; c < 3; ++c) e[c] = l1_nonlinear_irradiance(probe.coefficients[c], l1_vector(probe, c), n);
  return e;
}

template <class T>
Vec3<T> zh3_axis(const L1Probe<T>& probe, Zh3Axis axis, int channel) {
  if (axis == Zh3Axis::per_channel) return unit_or_z(l1_vector(probe, channel));
  Vec3<T> sum = Vec3<T>::Zero();
  for (int c = 0; c < 3; ++c) sum += static_cast<T>(kZh3LuminanceWeights[c]) * l1_vector(probe, c);
  return unit_or_z(sum);
}

template <class T>
T zh3_explicit_zonal(std::span<const T> band2, int channel, const Vec3<T>& axis) {
  if (band2.size() < 15) detail::precondition_failed("zh3_explicit_zonal: band 2 needs 15 RGB values");
  T y[9];
  eval_sh<T>(3, axis, std::span<T>(y, 9));
  T dot = 0;
  for (int m = 0; m < 5; ++m) dot += band2[3 * m + channel] * y[4 + m];
  return Constants<T>::zonal_to_sh * dot;
}

template <class T>
T zh3_hallucinated_zonal(const L1Probe<T>& probe, Zh3Axis axis, int channel) {
  const T c00 = probe.coefficients[channel];
  if (!(c00 > 0)) return 0;
  const T r = std::abs(l1_vector(probe, channel).dot(zh3_axis(probe, axis, channel))) / c00;
  return c00 * r * (T(0.08) + T(0.6) * r);
}

template <class T>
Zh3Probe<T> encode_zh3(std::span<const T> radiance, Zh3Axis axis, Zh3Fit fit) {
  Zh3Probe<T> p;
  p.l1 = encode_l1(radiance);
  if (fit == Zh3Fit::explicit_fit && radiance.size() < 27)
    detail::precondition_failed("encode_zh3: the explicit fit needs 9 RGB coefficients");
  for (int c = 0; c < 3; ++c)
    p.zonal[c] = fit == Zh3Fit::explicit_fit ? zh3_explicit_zonal(radiance.subspan(12, 15), c, zh3_axis(p.l1, axis, c))
                                             : zh3_hallucinated_zonal(p.l1, axis, c);
  return p;
}

template <class T>
Vec3<T> zh3_irradiance(const Zh3Probe<T>& probe, Zh3Axis axis, const Vec3<T>& n) {
  using K = Constants<T>;
  Vec3<T> e;
  for (int c = 0; c < 3; ++c) {
    const T t = zh3_axis(probe.l1, axis, c).dot(n);
    e[c] = K::a0 * K::y00 * probe.l1.coefficients[c] + K::a1 * K::k1 * l1_vector(probe.l1, c).dot(n) +
           K::a2 * K::k20 * probe.zonal[c] * (3 * t * t - 1);
  }
  return e;
}

template <class T>
std::array<T, 15> zh3_band2(const Zh3Probe<T>& probe, Zh3Axis axis) {
  std::array<T, 15> out{};
  for (int c = 0; c < 3; ++c) {
    T y[9];
    eval_sh<T>(3, zh3_axis(probe.l1, axis, c), std::span<T>(y, 9));
    for (int m = 0; m < 5; ++m) out[3 * m + c] = Constants<T>::zonal_to_sh * probe.zonal[c] * y[4 + m];
  }
  return out;
}

#define SHTOOL_PROBE_ENCODING(T)                                                                \
  template L1Probe<T> encode_l1<T>(std::span<const T>);                                         \
  template T l1_nonlinear_irradiance<T>(T, const Vec3<T>&, const Vec3<T>&);                     \
  template Vec3<T> l1_nonlinear_irradiance<T>(const L1Probe<T>&, const Vec3<T>&);               \
  template Vec3<T> l1_vector<T>(const L1Probe<T>&, int);                                        \
  template Vec3<T> zh3_axis<T>(const L1Probe<T>&, Zh3Axis, int);                                \
  template T zh3_explicit_zonal<T>(std::span<const T>, int, const Vec3<T>&);                    \
  template T zh3_hallucinated_zonal<T>(const L1Probe<T>&, Zh3Axis, int);                        \
  template Zh3Probe<T> encode_zh3<T>(std::span<const T>, Zh3Axis, Zh3Fit);                      \
  template Vec3<T> zh3_irradiance<T>(const Zh3Probe<T>&, Zh3Axis, const Vec3<T>&);              \
  template std::array<T, 15> zh3_band2<T>(const Zh3Probe<T>&, Zh3Axis);

SHTOOL_PROBE_ENCODING(float)
SHTOOL_PROBE_ENCODING(double)

}  // namespace shtool
