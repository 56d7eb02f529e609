// Zeros of the associated Legendre functions (src/offline/lobes/legendre_zeros.h),
// checked against a long double evaluation by the textbook unnormalised recurrence, its
// derivative by the next order (src/runtime/basis/legendre.cpp uses Golub-Welsch plus the
// normalised recurrence and its derivative), sign counts on fine grids, closed-form zeros
// and std::sph_legendre.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "lobes/legendre_zeros.h"
#include "shtool/legendre.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

using LD = long double;
constexpr double kPi = std::numbers::pi;
constexpr LD kPiL = 3.141592653589793238462643383279502884L;

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// R_l^m(z) = P_l^m(z) / ((2m-1)!! sin^m t) = (d/dz)^m P_l(z) / (2m-1)!!, in long double, by
// (l-m) R_l = (2l-1) z R_{l-1} - (l+m-1) R_{l-2} from R_m = 1. R is a polynomial of degree
// l - m with R(+-1) != 0, so its sign is well defined at and next to the poles, where
// P_l^m itself vanishes for m > 0. (The explicit finite sums of P_l lose more digits to
// cancellation than long double holds beyond l ~ 20, so they cannot check 1e-15 zeros.)
LD reference_r(int l, int m, LD z) {
  LD before = 0, r = 1;
  for (int k = m + 1; k <= l; ++k) {
    const LD next = ((2 * k - 1) * z * r - (k + m - 1) * before) / (k - m);
    before = r;
    r = next;
  }
  return r;
}

// dR_l^m/dz = (2m+1) R_l^{m+1}, from (d/dz)^{m+1} P_l: the derivative is a second
// evaluation, not the differentiated recurrence the runtime's Newton uses.
LD reference_dr(int l, int m, LD z) { return l > m ? (2 * m + 1) * reference_r(l, m + 1, z) : 0; }

LD reference_r_at(int l, int m, LD t) { return reference_r(l, m, std::cos(t)); }

// Long double Newton in t on R(cos t), from the implementation's zero.
LD refine_zero(int l, int m, double t0) {
  LD t = t0;
  for (int it = 0; it < 6; ++it) {
    const LD z = std::cos(t);
    t -= reference_r(l, m, z) / (-std::sin(t) * reference_dr(l, m, z));
  }
  return t;
}

// Zeros are O(1) angles; the header promises ~1e-15 rad, i.e. a few ulp of pi/2..pi,
// which is asserted up to l = 30 (measured 1.0e-15). Beyond, the double recurrence that
// Newton evaluates carries ~l^2/6 ulp near the poles (see test_sh.cpp), which moves the
// zeros closest to the poles: measured 2.8e-15 at l = 127; the required 1e-14 applies.
double zero_tol(int l) { return l <= 30 ? 2e-15 : 1e-14; }

struct ZeroStats {
  double worst_err = 0, worst_sym = 0, worst_resid = 0;
};

void check_zeros(int l, int m, ZeroStats& st) {
  SCOPED_TRACE("l " + std::to_string(l) + " m " + std::to_string(m));
  const std::vector<double> z = legendre_zeros(l, m);
  const int n = l - m;
  ASSERT_EQ(int(z.size()), n);
  for (int k = 0; k < n; ++k) {
    EXPECT_GT(z[k], 0.0) << "k " << k;
    EXPECT_LT(z[k], kPi) << "k " << k;
    if (k > 0) {
      EXPECT_LT(z[k - 1], z[k]) << "k " << k;
    }

    // Accuracy against the long double zero.
    const double err = double(std::abs(refine_zero(l, m, z[k]) - LD(z[k])));
    st.worst_err = std::max(st.worst_err, err);
    EXPECT_LE(err, zero_tol(l)) << "k " << k << " t " << z[k];

    // Symmetry t <-> pi - t (P_l^m(-z) = (-1)^(l+m) P_l^m(z)).
    const double sym = std::abs(z[k] + z[n - 1 - k] - kPi);
    st.worst_sym = std::max(st.worst_sym, sym);
    EXPECT_LE(sym, 2 * zero_tol(l)) << "k " << k << " t " << z[k] << " mirror " << z[n - 1 - k];

    // A zero of the shipped normalized_legendre too: small against its size nearby
    // (max over the neighbouring gaps), and a sign change across +-1e-9.
    const double lo = k > 0 ? z[k - 1] : 0.0, hi = k + 1 < n ? z[k + 1] : kPi;
    double scale = 0;
    for (int j = 1; j < 32; ++j)
      scale = std::max(scale, std::abs(normalized_legendre(l, m, lo + (hi - lo) * j / 32.0)));
    const double resid = std::abs(normalized_legendre(l, m, z[k])) / scale;
    st.worst_resid = std::max(st.worst_resid, resid);
    // |f(t_k)| <= |f'| zero_tol + evaluation error, with |f'| <= l max|f| (Bernstein's
    // inequality for a trigonometric polynomial of degree l) and the recurrence budget
    // (4 + l^2/3) ulp of test_sh.cpp for the evaluation.
    const double resid_tol = l * zero_tol(l) + (4.0 + l * l / 3.0) * 2.220446049250313e-16;
    EXPECT_LE(resid, resid_tol) << "k " << k << " t " << z[k];
    const double fm = normalized_legendre(l, m, z[k] - 1e-9);
    const double fp = normalized_legendre(l, m, z[k] + 1e-9);
    EXPECT_TRUE((fm < 0 && fp > 0) || (fm > 0 && fp < 0))
        << "k " << k << " t " << z[k] << " f(t-1e-9) " << fm << " f(t+1e-9) " << fp;
  }

  // None missed: R keeps one sign strictly inside each gap (0, t_0), (t_0, t_1), ...,
  // (t_{n-1}, pi), sampled on a grid much finer than any gap, and flips across each
  // zero. With the count above that is exactly l - m simple zeros.
  std::vector<double> edges = {0.0};
  edges.insert(edges.end(), z.begin(), z.end());
  edges.push_back(kPi);
  int prev_sign = 0;
  for (std::size_t g = 0; g + 1 < edges.size(); ++g) {
    const int samples = 48;
    int sign = 0;
    for (int j = 0; j <= samples; ++j) {
      // j = 0 and j = samples sit 1e-7 of the gap inside its ends.
      const LD a = edges[g], b = edges[g + 1];
      const LD t = a + (b - a) * (1e-7L + (1 - 2e-7L) * j / samples);
      const LD r = reference_r_at(l, m, t);
      const int s = r > 0 ? 1 : (r < 0 ? -1 : 0);
      ASSERT_NE(s, 0) << "gap " << g << " t " << double(t);
      if (sign == 0) sign = s;
      EXPECT_EQ(s, sign) << "sign change inside gap " << g << " (" << edges[g] << ", "
                         << edges[g + 1] << ") at t " << double(t) << ": a zero was missed";
    }
    if (g > 0) {
      EXPECT_EQ(sign, -prev_sign) << "no sign flip across zero " << g - 1;
    }
    prev_sign = sign;
  }

  // And an independent count: sign changes of R on a uniform grid of 40 l points.
  const int grid = 40 * l + 40;
  int changes = 0;
  LD prev = reference_r_at(l, m, LD(0));
  for (int j = 1; j <= grid; ++j) {
    const LD r = reference_r_at(l, m, kPiL * j / grid);
    if ((r > 0) != (prev > 0)) ++changes;
    prev = r;
  }
  EXPECT_EQ(changes, n) << "sign changes on a uniform grid";
}

TEST(LegendreZeros, AllUpTo30) {
  ZeroStats st;
  for (int l = 0; l <= 30; ++l)
    for (int m = 0; m <= l; ++m) check_zeros(l, m, st);
  RecordProperty("max_zero_err", sci(st.worst_err));
  RecordProperty("max_symmetry_err", sci(st.worst_sym));
  RecordProperty("max_rel_residual", sci(st.worst_resid));
}

TEST(LegendreZeros, SpotChecksAt60And127) {
  ZeroStats st;
  for (int m : {0, 1, 2, 7, 30, 58, 59, 60}) check_zeros(60, m, st);
  for (int m : {0, 64, 126}) check_zeros(kMaxOrder - 1, m, st);
  RecordProperty("max_zero_err", sci(st.worst_err));
  RecordProperty("max_symmetry_err", sci(st.worst_sym));
  RecordProperty("max_rel_residual", sci(st.worst_resid));
}

TEST(LegendreZeros, ClosedForms) {
  // Each case: P_l^m = sin^m t * (polynomial in z = cos t) whose roots are written out.
  const auto ac = [](double z) { return std::acos(z); };
  const double z4a = std::sqrt((3 - 2 * std::sqrt(6.0 / 5)) / 7);
  const double z4b = std::sqrt((3 + 2 * std::sqrt(6.0 / 5)) / 7);
  const std::vector<std::pair<std::pair<int, int>, std::vector<double>>> cases = {
      {{1, 0}, {kPi / 2}},                                                    // z
      {{2, 0}, {ac(1 / std::sqrt(3.0)), ac(-1 / std::sqrt(3.0))}},            // 3z^2 - 1
      {{2, 1}, {kPi / 2}},                                                    // z sin t
      {{3, 0}, {ac(std::sqrt(0.6)), kPi / 2, ac(-std::sqrt(0.6))}},           // 5z^3 - 3z
      {{3, 1}, {ac(1 / std::sqrt(5.0)), ac(-1 / std::sqrt(5.0))}},            // 5z^2 - 1
      {{4, 2}, {ac(1 / std::sqrt(7.0)), ac(-1 / std::sqrt(7.0))}},            // 7z^2 - 1
      {{4, 0}, {ac(z4b), ac(z4a), ac(-z4a), ac(-z4b)}},                       // 35z^4 - 30z^2 + 3
      {{5, 1}, {ac(std::sqrt((7 + 2 * std::sqrt(7.0)) / 21)), ac(std::sqrt((7 - 2 * std::sqrt(7.0)) / 21)),
                ac(-std::sqrt((7 - 2 * std::sqrt(7.0)) / 21)), ac(-std::sqrt((7 + 2 * std::sqrt(7.0)) / 21))}},
      // 21z^4 - 14z^2 + 1
  };
  for (const auto& [lm, ref] : cases) {
    const auto z = legendre_zeros(lm.first, lm.second);
    ASSERT_EQ(z.size(), ref.size()) << "l " << lm.first << " m " << lm.second;
    for (std::size_t k = 0; k < z.size(); ++k)
      // acos of a rounded argument: a few ulp, and 1/sqrt(1-z^2) <= 1.6 amplification.
      EXPECT_NEAR(z[k], ref[k], 2e-15) << "l " << lm.first << " m " << lm.second << " k " << k;
  }
  for (int l = 1; l <= 30; ++l) {
    // P_l^{l-1} = sin^{l-1} t * z * const: the only zero is the equator.
    const auto z = legendre_zeros(l, l - 1);
    ASSERT_EQ(z.size(), 1u) << "l " << l;
    EXPECT_NEAR(z[0], kPi / 2, 2e-16) << "l " << l;
    EXPECT_TRUE(legendre_zeros(l, l).empty()) << "l " << l;
  }
  EXPECT_TRUE(legendre_zeros(0, 0).empty());
}

// ---------------------------------------------------------------------------
// normalized_legendre values.

}  // namespace
}  // namespace shtool
