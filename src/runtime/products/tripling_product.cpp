#include "shtool/tripling_product.h"

#include <algorithm>
#include <functional>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "io/load_kind.h"
#include "kernels/tripling_kernels.h"
#include "precondition.h"
#include "shtool/legendre.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

// Entries below this magnitude are dropped. The structural zeros never reach the
// tensor (the enumeration applies the selection rules); what remains are the rare
// "non-trivial" zeros of the Wigner 3j symbols, which the quadrature returns as ~1e-18
// rounding noise, while the smallest true non-zero is 1.8e-6 at N = 20 and 5.4e-10 at
// N = 32 (docs/products.md), so the threshold cannot drop a real coefficient.
constexpr double kTriplingZero = 1e-12;

struct Lm {
  int l, m;
};
Lm band_of(int i) {
  const int l = sh_band(i);
  return {l, i - l * (l + 1)};
}

// Theta_l^m(x) = sqrt(2 pi) K_l^m P_l^m(x) at Gauss nodes, for 0 <= m <= l < order;
// normalised so that the integral over [-1, 1] of its square is 1 (normalized_legendre_all).
class PolarTable {
 public:
  PolarTable(int order, const std::vector<double>& x) : nq_(static_cast<int>(x.size())) {
    values_.assign(static_cast<std::size_t>(order * (order + 1) / 2) * nq_, 0.0L);
    std::vector<long double> point(static_cast<std::size_t>(order * (order + 1) / 2));
    for (int q = 0; q < nq_; ++q) {
      const long double z = x[q];
      // sqrt(2 pi) / sqrt(4 pi) = 1/sqrt(2) for (l, m) = (0, 0).
      normalized_legendre_all(order, z, std::sqrt((1.0L - z) * (1.0L + z)), 1.0L / std::sqrt(2.0L), point);
      for (std::size_t k = 0; k < point.size(); ++k) values_[k * nq_ + q] = point[k];
    }
  }
  const long double* row(int l, int m) const {
    return values_.data() + static_cast<std::size_t>(l * (l + 1) / 2 + m) * nq_;
  }

 private:
  int nq_;
  std::vector<long double> values_;
};

Error tripling_error(const std::string& what) {
  return Error{"tripling-tensor table: " + what};
}

}  // namespace

double tripling_azimuthal_factor(int m1, int m2, int m3) {
  const int sines = (m1 < 0) + (m2 < 0) + (m3 < 0);
  // An odd number of sines makes the integrand odd under p -> -p.
  if (sines % 2 == 1) return 0.0;
  auto delta = [](int v) { return v == 0 ? 1 : 0; };
  int count = 0;  // the integral in units of pi/2 (product-to-sum formulas)
  if (sines == 0) {
    const int a = std::abs(m1), b = std::abs(m2), c = std::abs(m3);
    count = delta(a + b + c) + delta(a + b - c) + delta(a - b + c) + delta(-a + b + c);
  } else {
    // Two sines p, q and one cosine r: sin p sin q cos r = 1/4 [cos(p-q+r) + cos(p-q-r)
    // - cos(p+q+r) - cos(p+q-r)].
    std::array<int, 3> m = {m1, m2, m3};
    std::sort(m.begin(), m.end());  // the two negatives first
    const int p = -m[0], q = -m[1], r = m[2];
    count = delta(p - q + r) + delta(p - q - r) - delta(p + q + r) - delta(p + q - r);
  }
  if (count == 0) return 0.0;
  const long double pi = std::numbers::pi_v<long double>;
  long double v = count * pi / 2;
  for (int m : {m1, m2, m3}) v /= (m == 0 ? std::sqrt(2 * pi) : std::sqrt(pi));
  return static_cast<double>(v);
}

TriplingTensor TriplingTensor::from_candidates(int order,
                                               const std::function<double(int, int, int)>& coefficient) {
  TriplingTensor t;
  t.order = order;
  const int nmax = order - 1;
  const int count = sh_count(order);
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, double>> entries;
  // Selection rules of real SH: for each pair i <= j at most two m3 (|m3| = |m1| + |m2|
  // or ||m1| - |m2||, with the sign rule of the azimuthal factor), and the bands l3 of
  // the right parity inside the triangle.
  for (int i = 0; i < count; ++i) {
    const Lm a = band_of(i);
    for (int j = i; j < count; ++j) {
      const Lm b = band_of(j);
      const int am = std::abs(a.m), bm = std::abs(b.m);
      const int sign = ((a.m < 0) != (b.m < 0)) ? -1 : 1;
      const int cs[2] = {am + bm, std::abs(am - bm)};
      for (int ci = 0; ci < 2; ++ci) {
        const int c = cs[ci];
        if (ci == 1 && cs[1] == cs[0]) break;
        if (sign < 0 && c == 0) continue;
        const int m3 = sign * c;
        if (tripling_azimuthal_factor(a.m, b.m, m3) == 0.0) continue;
        for (int l3 = std::max(std::abs(a.l - b.l), c); l3 <= std::min(a.l + b.l, nmax); ++l3) {
          if ((a.l + b.l + l3) % 2 != 0) continue;
          const int k = sh_index(l3, m3);
          if (k < j) continue;
          const double v = coefficient(i, j, k);
          if (std::abs(v) < kTriplingZero) continue;  // a non-trivial zero (e.g. of a 3j symbol)
          entries.emplace_back(i, j, k, v);
        }
      }
    }
  }
  std::sort(entries.begin(), entries.end());
  t.index.reserve(3 * entries.size());
  t.value.reserve(entries.size());
  for (const auto& [i, j, k, v] : entries) {
    t.index.insert(t.index.end(), {i, j, k});
    t.value.push_back(v);
  }
  return t;
}

TriplingTensor TriplingTensor::compute(int order) {
  // The polar integrand is a polynomial of degree l1 + l2 + l3 <= 3 (N - 1): the largest
  // |m| is the sum of the other two, so the sin^|m| factors multiply to an even power.
  const int nq = (3 * (order - 1)) / 2 + 1;
  const GaussLegendre gl = gauss_legendre(nq);
  const PolarTable polar(order, gl.nodes);
  return from_candidates(order, [&](int i, int j, int k) {
    const Lm a = band_of(i), b = band_of(j), c = band_of(k);
    const long double* pa = polar.row(a.l, std::abs(a.m));
    const long double* pb = polar.row(b.l, std::abs(b.m));
    const long double* pc = polar.row(c.l, std::abs(c.m));
    long double sum = 0;
    for (int q = 0; q < nq; ++q) sum += gl.weights[q] * pa[q] * pb[q] * pc[q];
    return static_cast<double>(tripling_azimuthal_factor(a.m, b.m, c.m) * sum);
  });
}

Result<TriplingTensor> TriplingTensor::load(const std::filesystem::path& path) {
  return detail::load_kind<TriplingTensor>(path, kTriplingTensorKind);
}

Result<TriplingTensor> TriplingTensor::from_table(const Table& table) {
  if (table.kind != kTriplingTensorKind) return tripling_error("wrong kind '" + table.kind + "'");
  if (const auto problem = detail::array_sizes_problem(table)) return tripling_error(*problem);
  if (table.order < 1 || table.order > kMaxTriplingOrder)
    return tripling_error("unsupported order " + std::to_string(table.order) + " (1.." +
                          std::to_string(kMaxTriplingOrder) + ")");
  const TableArray* idx = table.find("index");
  const TableArray* val = table.find("value");
  if (!idx || !val || idx->dtype != DType::u32 || val->dtype != DType::f64)
    return tripling_error("missing array or wrong dtype (need u32 'index', f64 'value')");
  if (idx->shape.size() != 2 || idx->shape[1] != 3 || val->shape.size() != 1 ||
      idx->shape[0] != val->shape[0])
    return tripling_error("shapes must be index [nnz, 3] and value [nnz]");
  TriplingTensor t;
  t.order = table.order;
  t.index = idx->values<std::uint32_t>();
  t.value = val->values<double>();
  if (t.index.size() != 3 * t.value.size()) return tripling_error("array sizes disagree");
  const std::uint32_t count = static_cast<std::uint32_t>(sh_count(t.order));
  const double gaunt_bound = std::sqrt((2.0 * t.order - 1) / (4 * std::numbers::pi)) * (1 + 1e-9);
  for (std::size_t e = 0; e < t.value.size(); ++e) {
    const std::uint32_t i = t.index[3 * e], j = t.index[3 * e + 1], k = t.index[3 * e + 2];
    const std::string where = "entry " + std::to_string(e) + " (" + std::to_string(i) + ", " +
                              std::to_string(j) + ", " + std::to_string(k) + ")";
    if (!(i <= j && j <= k && k < count))
      return tripling_error(where + ": indices must satisfy i <= j <= k < N^2");
    if (e > 0 && !(std::tie(t.index[3 * e - 3], t.index[3 * e - 2], t.index[3 * e - 1]) <
                   std::tie(t.index[3 * e], t.index[3 * e + 1], t.index[3 * e + 2])))
      return tripling_error(where + ": entries must be sorted by (i, j, k) without repeats");
    const Lm a = band_of(static_cast<int>(i)), b = band_of(static_cast<int>(j)),
             c = band_of(static_cast<int>(k));
    if (c.l > a.l + b.l || c.l < std::abs(a.l - b.l) || (a.l + b.l + c.l) % 2 != 0 ||
        tripling_azimuthal_factor(a.m, b.m, c.m) == 0.0)
      return tripling_error(where + ": violates the selection rules (a structural zero)");
    if (!std::isfinite(t.value[e])) return tripling_error(where + ": value is not finite");
    // |integral of y_i y_j y_k| <= max |y_i| = sqrt((2l + 1) / (4 pi)) <= sqrt((2N - 1) / (4 pi)).
    if (!(std::abs(t.value[e]) <= gaunt_bound))
      return tripling_error(where + ": value exceeds the bound of any SH triple integral");
  }
  // The table holds every band of its order: integral y_0^0 y_j y_j = 1 / sqrt(4 pi) for
  // every j < N^2, so each (0, j, j) is an entry of that value. A header whose order was
  // raised by hand (entries of a lower order, checksums intact) fails here instead of
  // dropping the couplings of the missing bands from every product.
  const double y00 = 0.5 / std::sqrt(std::numbers::pi);
  std::uint32_t next = 0;  // the j of the next (0, j, j) expected
  for (std::size_t e = 0; e < t.value.size() && t.index[3 * e] == 0 && next < count; ++e) {
    if (t.index[3 * e + 1] != next || t.index[3 * e + 2] != next) continue;
    if (!(std::abs(t.value[e] - y00) <= 1e-12 * y00))
      return tripling_error("entry " + std::to_string(e) + " (0, " + std::to_string(next) + ", " +
                            std::to_string(next) + "): is not 1/sqrt(4 pi), the integral of y_0^0 y_j y_j");
    ++next;
  }
  if (next != count)
    return tripling_error("no entry (0, " + std::to_string(next) + ", " + std::to_string(next) +
                          "): the entries do not cover order " + std::to_string(t.order) + " (" +
                          std::to_string(count) + " coefficients)");
  return t;
}

static_assert(kUnrolledTriplingOrder == detail::kTriplingKernelMaxOrder);

template <class T>
TriplingProduct<T>::TriplingProduct(const TriplingTensor& tensor) : order_(tensor.order) {
  const int count = sh_count(order_);
  struct Pair {
    std::uint32_t k, i, j;
    double w;
  };
  std::vector<Pair> pairs;
  pairs.reserve(3 * tensor.size());
  for (std::size_t e = 0; e < tensor.size(); ++e) {
    const std::uint32_t a = tensor.index[3 * e], b = tensor.index[3 * e + 1],
                        c = tensor.index[3 * e + 2];
    const double v = tensor.value[e];
    // One gather pair per distinct (output, unordered input pair) among the permutations
    // of (a, b, c); the diagonal weight is halved because the loop adds both orders.
    auto add = [&](std::uint32_t k, std::uint32_t i, std::uint32_t j) {
      pairs.push_back({k, i, j, i == j ? 0.5 * v : v});
    };
    add(c, a, b);
    if (b != c) add(b, a, c);
    if (a != b) add(a, b, c);
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
    return std::tie(x.k, x.i, x.j) < std::tie(y.k, y.i, y.j);
  });
  row_.assign(count + 1, 0);
  pair_.reserve(pairs.size());
  weight_.reserve(pairs.size());
  for (const Pair& p : pairs) {
    ++row_[p.k + 1];
    pair_.push_back(p.i | (p.j << 16));
    weight_.push_back(static_cast<T>(p.w));
  }
  for (int k = 0; k < count; ++k) row_[k + 1] += row_[k];

  // Orders 2..6 have a generated straight-line kernel (tripling_kernels.h) with the
  // values of the exact tensor as literals; it runs when this tensor holds the same
  // entries (any construction agrees to ~3e-15; a table edited or truncated by hand does
  // not, and then the gather loop below serves it).
  constexpr double kSameEntry = 1e-14;
  const std::span<const detail::TriplingKernelEntry> baked = detail::tripling_kernel_entries(order_);
  bool same = !baked.empty() && baked.size() == tensor.size();
  for (std::size_t e = 0; same && e < baked.size(); ++e)
    same = baked[e].a == tensor.index[3 * e] && baked[e].b == tensor.index[3 * e + 1] &&
           baked[e].c == tensor.index[3 * e + 2] &&
           std::abs(baked[e].value - tensor.value[e]) <= kSameEntry;
  if (same) kernel_ = detail::tripling_kernel<T>(order_);
}

template <class T>
void TriplingProduct<T>::multiply(std::span<const T> f1, std::span<const T> f2,
                                  std::span<T> g) const {
  const std::size_t n = static_cast<std::size_t>(sh_count(order_));
  detail::check_span_size("TriplingProduct::multiply", "f1", f1.size(), n);
  detail::check_span_size("TriplingProduct::multiply", "f2", f2.size(), n);
  detail::check_span_size("TriplingProduct::multiply", "g", g.size(), n);
  if (kernel_) {
    kernel_(f1.data(), f2.data(), g.data());
    return;
  }
  const int count = sh_count(order_);
  const T* a = f1.data();
  const T* b = f2.data();
  const std::uint32_t* pair = pair_.data();
  const T* w = weight_.data();
  for (int k = 0; k < count; ++k) {
    T acc = 0;
    for (std::uint32_t e = row_[k]; e < row_[k + 1]; ++e) {
      const std::uint32_t i = pair[e] & 0xffffu, j = pair[e] >> 16;
      acc += w[e] * (a[i] * b[j] + a[j] * b[i]);
    }
    g[k] = acc;
  }
}

template <class T>
T TriplingProduct<T>::integral(std::span<const T> f1, std::span<const T> f2,
                               std::span<const T> f3) const {
  const int count = sh_count(order_);
  for (const auto& [f, name] : {std::pair{f1, "f1"}, std::pair{f2, "f2"}, std::pair{f3, "f3"}})
    detail::check_span_size("TriplingProduct::integral", name, f.size(), static_cast<std::size_t>(count));
  const T* a = f1.data();
  const T* b = f2.data();
  T total = 0;
  for (int k = 0; k < count; ++k) {
    T acc = 0;
    for (std::uint32_t e = row_[k]; e < row_[k + 1]; ++e) {
      const std::uint32_t i = pair_[e] & 0xffffu, j = pair_[e] >> 16;
      acc += weight_[e] * (a[i] * b[j] + a[j] * b[i]);
    }
    total += f3[k] * acc;
  }
  return total;
}

template class TriplingProduct<float>;
template class TriplingProduct<double>;

}  // namespace shtool
