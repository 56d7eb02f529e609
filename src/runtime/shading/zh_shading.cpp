#include "shtool/zh_shading.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "precondition.h"

namespace shtool {
namespace {

// Orders up to this use a small stack buffer for the SH values; larger ones go through a
// separate function with a kMaxOrder^2 buffer, so the common case does not move the
// stack pointer by 128 KB (and touch its guard pages) on every call.
constexpr int kSmallOrder = 16;

// Table size limit (2^28 values: 2 GiB in double), so an extreme resolution and order is
// an error message rather than an allocation failure.
constexpr double kMaxTableValues = 268435456.0;

// order with order^2 == size, or 0 when size is not the square of a supported order.
int order_of_size(std::size_t size) noexcept {
  const auto n = static_cast<std::size_t>(std::llround(std::sqrt(static_cast<double>(size))));
  if (n < 1 || n > static_cast<std::size_t>(kMaxOrder) || n * n != size) return 0;
  return static_cast<int>(n);
}

// Eq. 24 from precomputed SH values y (order^2 of them).
template <class T>
void band_sums(int order, const T* y, const T* light, T* out) noexcept {
  for (int l = 0; l < order; ++l) {
    T sum = 0;
    for (int m = -l; m <= l; ++m) sum += y[sh_index(l, m)] * light[sh_index(l, m)];
    out[l] = sum;
  }
}

// Eq. 25 with the exact band sums, for orders up to Capacity (the stack buffer's size).
template <class T, int Capacity>
T shade_with_buffer(int order, const T* light, std::span<const Vec3<T>> axes, const T* coeffs) noexcept {
  T y[Capacity * Capacity];
  T bands[Capacity];
  T r = 0;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    eval_sh<T>(order, axes[i], std::span<T>(y, sh_count(order)));
    band_sums(order, y, light, bands);
    for (int l = 0; l < order; ++l) r += bands[l] * coeffs[i * order + l];
  }
  return r;
}

template <class T, int Capacity>
void bands_with_buffer(int order, const T* light, const Vec3<T>& axis, T* out) noexcept {
  T y[Capacity * Capacity];
  eval_sh<T>(order, axis, std::span<T>(y, sh_count(order)));
  band_sums(order, y, light, out);
}

// Out of line so only calls with order > kSmallOrder pay for the large frame.
template <class T>
[[gnu::noinline]] T shade_large(int order, const T* light, std::span<const Vec3<T>> axes, const T* coeffs) noexcept {
  return shade_with_buffer<T, kMaxOrder>(order, light, axes, coeffs);
}

template <class T>
[[gnu::noinline]] void bands_large(int order, const T* light, const Vec3<T>& axis, T* out) noexcept {
  bands_with_buffer<T, kMaxOrder>(order, light, axis, out);
}

}  // namespace

template <class T>
void zh_light_bands(std::span<const T> light, const Vec3<T>& axis, std::span<T> out) noexcept {
  const int order = order_of_size(light.size());
  if (order == 0) {
    for (T& v : out) v = std::numeric_limits<T>::quiet_NaN();
    return;
  }
  if (order <= kSmallOrder)
    bands_with_buffer<T, kSmallOrder>(order, light.data(), axis, out.data());
  else
    bands_large(order, light.data(), axis, out.data());
}

template <class T>
T zh_shade_exact(std::span<const T> light, std::span<const Vec3<T>> axes, std::span<const T> coeffs) noexcept {
  const int order = order_of_size(light.size());
  if (order == 0 || coeffs.size() != axes.size() * static_cast<std::size_t>(order))
    return std::numeric_limits<T>::quiet_NaN();
  return order <= kSmallOrder ? shade_with_buffer<T, kSmallOrder>(order, light.data(), axes, coeffs.data())
                              : shade_large(order, light.data(), axes, coeffs.data());
}

template <class T>
ZhLightTable<T>::ZhLightTable(int order, std::span<const float> light, int resolution)
    : ZhLightTable(order, std::span<const double>(std::vector<double>(light.begin(), light.end())), resolution) {}

template <class T>
ZhLightTable<T>::ZhLightTable(int order, std::span<const double> light, int resolution)
    : order_(order), resolution_(resolution) {
  if (order < 1 || order > kMaxOrder)
    detail::precondition_failed("ZH light table: order " + std::to_string(order) + " is outside 1.." +
                                std::to_string(kMaxOrder));
  if (light.size() != static_cast<std::size_t>(sh_count(order)))
    detail::precondition_failed("ZH light table: order mismatch: the lighting has " + std::to_string(light.size()) +
                                " coefficients, order " + std::to_string(order) + " needs " +
                                std::to_string(sh_count(order)));
  for (std::size_t i = 0; i < light.size(); ++i)
    if (!std::isfinite(light[i]))
      detail::precondition_failed("ZH light table: lighting coefficient " + std::to_string(i) + " is not finite");
  if (resolution < 1 || resolution > kMaxZhLightResolution)
    detail::precondition_failed("ZH light table: resolution " + std::to_string(resolution) + " is outside 1.." +
                                std::to_string(kMaxZhLightResolution));

  const int r = resolution;
  const double values = 6.0 * (r + 1.0) * (r + 1.0) * order;
  if (values > kMaxTableValues)
    detail::precondition_failed("ZH light table: resolution " + std::to_string(r) + " at order " +
                                std::to_string(order) + " needs " + std::to_string(static_cast<long long>(values)) +
                                " values, more than the limit of " +
                                std::to_string(static_cast<long long>(kMaxTableValues)));
  row_ = static_cast<std::size_t>(r + 1) * order;
  nodes_.resize(6 * static_cast<std::size_t>(r + 1) * row_);
  std::vector<double> y(sh_count(order)), bands(order);
  for (int face = 0; face < 6; ++face) {
    const int k = face / 2;
    const double major = face % 2 ? -1.0 : 1.0;
    for (int j = 0; j <= r; ++j) {
      for (int i = 0; i <= r; ++i) {
        // (2i - R) / R is exact at the face edges (+-1) and is the same expression on
        // every face, so a node on a shared edge gets bit-identical values on both faces.
        Vec3<double> c;
        c[k] = major;
        c[(k + 1) % 3] = (2.0 * i - r) / r;
        c[(k + 2) % 3] = (2.0 * j - r) / r;
        eval_sh<double>(order, c.normalized(), std::span<double>(y));
        band_sums(order, y.data(), light.data(), bands.data());
        T* node = nodes_.data() + (static_cast<std::size_t>(face) * (r + 1) + j) * row_ +
                  static_cast<std::size_t>(i) * order;
        for (int l = 0; l < order; ++l) node[l] = static_cast<T>(bands[l]);
      }
    }
  }
}

template <class T>
typename ZhLightTable<T>::Cell ZhLightTable<T>::locate(const Vec3<T>& s) const noexcept {
  // Major axis k picks the face; the other two coordinates divided by |s_k| are the
  // gnomonic face coordinates (a, b) in [-1, 1]. Ties go to the lower k: the two faces
  // agree on their shared edge, so the choice does not matter.
  // Selects rather than branches: with incoherent axes the branches mispredict.
  const T ax = std::abs(s.x()), ay = std::abs(s.y()), az = std::abs(s.z());
  const bool on_x = (ax >= ay) & (ax >= az);
  const bool on_y = !on_x & (ay >= az);
  const int k = on_x ? 0 : (on_y ? 1 : 2);
  const T major = on_x ? s.x() : (on_y ? s.y() : s.z());
  const T a = on_x ? s.y() : (on_y ? s.z() : s.x());
  const T b = on_x ? s.z() : (on_y ? s.x() : s.y());
  const int face = 2 * k + (major < 0);
  const T half = static_cast<T>(resolution_) / 2;
  // Node coordinates: a = -1 + 2i/R  <=>  i = (a + 1) R/2. Divided before scaling: half
  // / |major| overflows for a tiny (subnormal) axis, and 0 times that is NaN.
  const T fu = a / std::abs(major) * half + half, fv = b / std::abs(major) * half + half;
  // Clamp for the cell index only, written so that NaN selects cell 0 (never an
  // out-of-range read); the fractions keep fu, fv, so NaN input gives NaN output and the
  // last cell is entered at fraction 1 rather than past the table.
  const T rmax = static_cast<T>(resolution_ - 1);
  const T cu = fu > 0 ? (fu < rmax ? fu : rmax) : 0;
  const T cv = fv > 0 ? (fv < rmax ? fv : rmax) : 0;
  const int i = static_cast<int>(cu), j = static_cast<int>(cv);
  const T* n00 = nodes_.data() + (static_cast<std::size_t>(face) * (resolution_ + 1) + j) * row_ +
                 static_cast<std::size_t>(i) * order_;
  return {n00, fu - static_cast<T>(i), fv - static_cast<T>(j)};
}

template <class T>
void ZhLightTable<T>::lookup(const Vec3<T>& axis, std::span<T> out) const noexcept {
  const Cell c = locate(axis);
  const T* p00 = c.n00;
  const T* p10 = p00 + order_;
  const T* p01 = p00 + row_;
  const T* p11 = p01 + order_;
  const T w00 = (1 - c.u) * (1 - c.v), w10 = c.u * (1 - c.v), w01 = (1 - c.u) * c.v, w11 = c.u * c.v;
  for (int l = 0; l < order_; ++l) out[l] = w00 * p00[l] + w10 * p10[l] + w01 * p01[l] + w11 * p11[l];
}

namespace {

// Dot the lobe with each of the four corner nodes, then blend: 4n + 4 multiplies instead
// of 5n, in four independent sums. kOrder > 0 fixes the trip count at compile time (the
// common orders), 0 loops over `order`.
template <class T, int kOrder>
inline T blend_dots(const T* p00, const T* p10, const T* p01, const T* p11, const T* g, T u, T v,
                    int order) noexcept {
  const int n = kOrder > 0 ? kOrder : order;
  T d00 = 0, d10 = 0, d01 = 0, d11 = 0;
  for (int l = 0; l < n; ++l) {
    d00 += p00[l] * g[l];
    d10 += p10[l] * g[l];
    d01 += p01[l] * g[l];
    d11 += p11[l] * g[l];
  }
  return (1 - v) * ((1 - u) * d00 + u * d10) + v * ((1 - u) * d01 + u * d11);
}

}  // namespace

template <class T>
T ZhLightTable<T>::blend(const Cell& c, const T* g) const noexcept {
  const T* p00 = c.n00;
  const T* p10 = p00 + order_;
  const T* p01 = p00 + row_;
  const T* p11 = p01 + order_;
  switch (order_) {
    case 3: return blend_dots<T, 3>(p00, p10, p01, p11, g, c.u, c.v, 3);
    case 4: return blend_dots<T, 4>(p00, p10, p01, p11, g, c.u, c.v, 4);
    case 5: return blend_dots<T, 5>(p00, p10, p01, p11, g, c.u, c.v, 5);
    case 6: return blend_dots<T, 6>(p00, p10, p01, p11, g, c.u, c.v, 6);
    case 8: return blend_dots<T, 8>(p00, p10, p01, p11, g, c.u, c.v, 8);
    default: return blend_dots<T, 0>(p00, p10, p01, p11, g, c.u, c.v, order_);
  }
}

template <class T>
T ZhLightTable<T>::shade_lobe(const Vec3<T>& axis, std::span<const T> coeffs) const noexcept {
  if (coeffs.size() != static_cast<std::size_t>(order_)) return std::numeric_limits<T>::quiet_NaN();
  return blend(locate(axis), coeffs.data());
}

template <class T>
T ZhLightTable<T>::shade(std::span<const Vec3<T>> axes, std::span<const T> coeffs) const noexcept {
  const std::size_t n = static_cast<std::size_t>(order_);
  if (coeffs.size() != axes.size() * n) return std::numeric_limits<T>::quiet_NaN();
  // Locate a batch of lobes first, then blend: the cells' node reads of different lobes
  // are independent, so their cache misses overlap instead of queueing one per lobe.
  constexpr std::size_t kBatch = 8;
  Cell cells[kBatch];
  T r = 0;
  for (std::size_t first = 0; first < axes.size(); first += kBatch) {
    const std::size_t count = std::min(kBatch, axes.size() - first);
    for (std::size_t i = 0; i < count; ++i) cells[i] = locate(axes[first + i]);
    for (std::size_t i = 0; i < count; ++i) r += blend(cells[i], coeffs.data() + (first + i) * n);
  }
  return r;
}

template class ZhLightTable<float>;
template class ZhLightTable<double>;
template void zh_light_bands<float>(std::span<const float>, const Vec3<float>&, std::span<float>) noexcept;
template void zh_light_bands<double>(std::span<const double>, const Vec3<double>&, std::span<double>) noexcept;
template float zh_shade_exact<float>(std::span<const float>, std::span<const Vec3<float>>,
                                     std::span<const float>) noexcept;
template double zh_shade_exact<double>(std::span<const double>, std::span<const Vec3<double>>,
                                       std::span<const double>) noexcept;

}  // namespace shtool
