#include "tensors/tripling.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "common/input_error.h"
#include "common/table_writer.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

#if defined(__SIZEOF_FLOAT128__)
using Quad = __float128;
#else
using Quad = long double;  // still ~1e-19 per operation; enough for N <= 20
#endif

// Largest factorial argument Racah's formula needs: j1 + j2 + j3 + 1 with j <= 3 (N - 1).
constexpr int kMaxFactorial = 9 * kMaxTriplingOrder + 2;

const std::vector<Quad>& factorials() {
  static const std::vector<Quad> table = [] {
    std::vector<Quad> f(kMaxFactorial + 1);
    f[0] = 1;
    for (int n = 1; n <= kMaxFactorial; ++n) f[n] = f[n - 1] * static_cast<Quad>(n);
    return f;
  }();
  return table;
}

constexpr double kTriplingZero = 1e-12;  // the threshold of TriplingTensor::from_candidates

struct Lm {
  int l, m;
};
Lm band_of(int i) {
  const int l = sh_band(i);
  return {l, i - l * (l + 1)};
}

}  // namespace

long double wigner_3j(int j1, int j2, int j3, int m1, int m2, int m3) {
  if (m1 + m2 + m3 != 0) return 0;
  if (std::abs(m1) > j1 || std::abs(m2) > j2 || std::abs(m3) > j3) return 0;
  if (j3 < std::abs(j1 - j2) || j3 > j1 + j2) return 0;
  if (m1 == 0 && m2 == 0 && m3 == 0 && (j1 + j2 + j3) % 2 != 0) return 0;
  if (j1 + j2 + j3 + 1 > kMaxFactorial) throw InputError("wigner_3j: j too large");
  const std::vector<Quad>& f = factorials();
  // Racah's formula: (-1)^(j1-j2-m3) sqrt(Delta * prod (j+-m)!) sum_k (-1)^k / (...).
  const int kmin = std::max({0, j2 - j3 - m1, j1 - j3 + m2});
  const int kmax = std::min({j1 + j2 - j3, j1 - m1, j2 + m2});
  Quad sum = 0;
  for (int k = kmin; k <= kmax; ++k) {
    const Quad term = 1 / (f[k] * f[j3 - j2 + k + m1] * f[j3 - j1 + k - m2] *
                           f[j1 + j2 - j3 - k] * f[j1 - k - m1] * f[j2 - k + m2]);
    sum += (k % 2 == 0) ? term : -term;
  }
  const Quad pre = f[j1 + j2 - j3] * f[j1 - j2 + j3] * f[-j1 + j2 + j3] / f[j1 + j2 + j3 + 1] *
                   f[j1 + m1] * f[j1 - m1] * f[j2 + m2] * f[j2 - m2] * f[j3 + m3] * f[j3 - m3];
  const long double root = std::sqrt(static_cast<long double>(pre));
  const long double sign = ((j1 - j2 - m3) % 2 == 0) ? 1.0L : -1.0L;
  return sign * static_cast<long double>(sum) * root;
}

long double gaunt_complex(int l1, int m1, int l2, int m2, int l3, int m3) {
  if (m1 + m2 + m3 != 0 || (l1 + l2 + l3) % 2 != 0) return 0;
  const long double pi = std::numbers::pi_v<long double>;
  return std::sqrt((2.0L * l1 + 1) * (2.0L * l2 + 1) * (2.0L * l3 + 1) / (4 * pi)) *
         wigner_3j(l1, l2, l3, 0, 0, 0) * wigner_3j(l1, l2, l3, m1, m2, m3);
}

// Real SH separate as y_l^m = Theta_l^|m|(t) Phi_m(p) with Theta = sqrt(2 pi) K P
// (unit norm on [0, pi] with weight sin t) and Phi the normalised cos/sin of |m| p, so
//   C = [integral Phi_m1 Phi_m2 Phi_m3 dp] * [integral Theta1 Theta2 Theta3 sin t dt].
// The azimuthal factor vanishes unless the largest |m| (say c) is the sum of the other
// two (a + b = c). The complex harmonic is Y_l^m = Theta_l^m e^{imp} / sqrt(2 pi) for
// m >= 0 and Y_l^-m = (-1)^m conj(Y_l^m), so Gaunt's integral with (a, b, -c) is
//   G = (-1)^c / sqrt(2 pi) * integral Theta_l1^a Theta_l2^b Theta_l3^c sin t dt,
// which gives the polar factor without any complex-to-real change of basis (and so
// without its phase bookkeeping).
double tripling_coefficient_exact(int i, int j, int k) {
  const Lm x[3] = {band_of(i), band_of(j), band_of(k)};
  const double az = tripling_azimuthal_factor(x[0].m, x[1].m, x[2].m);
  if (az == 0.0) return 0.0;
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3,
            [&](int p, int q) { return std::abs(x[p].m) < std::abs(x[q].m); });
  const Lm a = x[order[0]], b = x[order[1]], c = x[order[2]];
  const int am = std::abs(a.m), bm = std::abs(b.m), cm = std::abs(c.m);
  if (am + bm != cm) throw std::logic_error("tripling: azimuthal rule without a + b = c");
  const long double pi = std::numbers::pi_v<long double>;
  const long double polar = std::sqrt(2 * pi) * ((cm % 2 == 0) ? 1.0L : -1.0L) *
                            gaunt_complex(a.l, am, b.l, bm, c.l, -cm);
  return static_cast<double>(static_cast<long double>(az) * polar);
}

TriplingTensor compute_tripling_tensor_exact(int order) {
  if (order < 1 || order > kMaxTriplingOrder)
    throw InputError("tripling tensor: order " + std::to_string(order) +
                            " outside 1.." + std::to_string(kMaxTriplingOrder));
  return TriplingTensor::from_candidates(order, tripling_coefficient_exact);
}

Table tripling_tensor_table(int order, const nlohmann::json& generator) {
  const TriplingTensor t = compute_tripling_tensor_exact(order);
  return to_table(t, generator,
                  {{"construction",
                    "Wigner 3j by Racah's formula in quadruple precision, Gaunt's formula, "
                    "real basis by separation into polar and azimuthal integrals"},
                   {"zero_threshold", kTriplingZero}});
}

Table to_table(const TriplingTensor& tensor, const nlohmann::json& generator, const nlohmann::json& extra_meta) {
  const std::int64_t nnz = static_cast<std::int64_t>(tensor.value.size());
  nlohmann::json meta = extra_meta.is_object() ? extra_meta : nlohmann::json::object();
  meta["nonzeros"] = nnz;
  meta["layout"] =
      "canonical non-zeros C_ijk = integral y_i y_j y_k with i <= j <= k < N^2, sorted by "
      "(i, j, k); the other permutations have the same value";
  Table t = new_table(kTriplingTensorKind, tensor.order, generator, meta);
  t.arrays.push_back(TableArray::from<std::uint32_t>("index", {nnz, 3}, tensor.index));
  t.arrays.push_back(TableArray::from<double>("value", {nnz}, tensor.value));
  return t;
}

}  // namespace shtool
