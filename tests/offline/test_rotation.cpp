// SH rotations (include/shtool/rotation.h, euler.h, rotation_helpers.h) against references
// that do not share their code:
//  - rotate-then-project: g = project_sh(w -> f(R^-1 w)) by a quadrature exact for the
//    band limit (independent of the Ivanic-Ruedenberg recurrences and of the zyz split);
//  - ZH lobes: a lobe along d must come out as the same lobe along R d (closed form);
//  - group identities: orthogonality, M(R1 R2) = M(R1) M(R2), identity;
//  - the printed values of [2] Fig. 2, the closed form of the y-rotation
//    generator, and finite differences of the reference rotation for the Taylor matrices;
//  - Eigen's JacobiSVD of the exact error matrices for the Taylor error bounds.
// Conventions are those of docs/conventions.md; methods are described in docs/rotation.md.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "allocation_counter.h"
#include "common/generator_record.h"
#include "kernel_copies.h"
#include "shtool/euler.h"
#include "shtool/orthogonal_map.h"
#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/rotation_helpers.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "shtool/zhf_rotation.h"
#include "table_test_util.h"
#include "tensors/rotation_helpers_gen.h"
#include "test_util.h"

namespace shtool {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr float kEpsF = std::numeric_limits<float>::epsilon();

// Every test here works up to order 20 (the required maximum N); the helper table is built once.
constexpr int kHelperOrder = 20;

// Exact methods in double, relative to ||f|| (the accuracy target). Measured:
// <= 6e-15 (reference and zxzxz vs quadrature, N <= 20), so this has margin for other
// compilers while still catching any wrong entry (a sign or a misplaced index is O(1)).
constexpr double kExactTolDouble = 1e-12;
// Exact methods in float, relative to ||f||. Measured <= 8.5e-7 at N = 20 (a float
// recurrence / product chain of ~N steps, each ~0.5 ulp).
constexpr double kExactTolFloat = 1e-5;

std::shared_ptr<const RotationHelpers> helpers() {
  static const std::shared_ptr<const RotationHelpers> h =
      std::make_shared<const RotationHelpers>(compute_rotation_helpers(kHelperOrder));
  return h;
}

// ---------------------------------------------------------------------------
// Small utilities.

Mat3<double> axis_angle(Vec3<double> axis, double angle) {
  axis.normalize();
  const double s = std::sin(angle / 2);
  return matrix_from_quaternion<double>(std::cos(angle / 2), s * axis.x(), s * axis.y(), s * axis.z());
}

Mat3<double> ry(double b) {
  Mat3<double> r;
  r << std::cos(b), 0, std::sin(b), 0, 1, 0, -std::sin(b), 0, std::cos(b);
  return r;
}

// Uniformly distributed rotation (normalised Gaussian quaternion), fixed seed per caller.
Mat3<double> random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return matrix_from_quaternion<double>(q[0], q[1], q[2], q[3]);
}

Vec3<double> random_axis(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Vec3<double> a(n(rng), n(rng), n(rng));
  return a.normalized();
}

using test::norm;
using test::random_coeffs;
using test::reference_matrix;

template <class A, class B>
double distance(const std::vector<A>& a, const std::vector<B>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
    s += d * d;
  }
  return std::sqrt(s);
}

std::string matrix_text(const Mat3<double>& r) {
  std::ostringstream s;
  s.precision(17);
  s << "[" << r.row(0) << "; " << r.row(1) << "; " << r.row(2) << "]";
  return s.str();
}

template <class T>
std::vector<T> rotate(int order, const Mat3<double>& r, RotationMethod method, const std::vector<double>& f,
                      double tol = kDefaultRotationTolerance, RotationMethod* resolved = nullptr) {
  ShRotation<T> rotation(order, helpers());
  const bool ok = rotation.set(r.cast<T>(), method, tol);
  EXPECT_TRUE(ok) << rotation_method_name(method) << " order " << order;
  std::vector<T> in(f.begin(), f.end()), out(f.size());
  rotation.apply(in, out);
  if (resolved) *resolved = rotation.method();
  return out;
}

// The independent check: g(w) = f(R^-1 w) sampled and projected with a rule exact for
// band-limited functions of this order (g stays in the same bands), so g's
// coefficients are exact up to rounding, with no rotation formula involved.
std::vector<double> rotate_by_quadrature(int order, const Mat3<double>& r, const std::vector<double>& f) {
  const Mat3<double> rinv = r.transpose();
  return project_sh(order, [&](const Vec3<double>& w) {
    return reconstruct<double>(std::span<const double>(f), Vec3<double>(rinv * w));
  });
}

// D1 = dM(Ry(b))/db(0) from the stored sub-diagonal (antisymmetric, tridiagonal per band).
Eigen::MatrixXd dense_d1(const RotationHelpers& h, int order) {
  const int n = sh_count(order);
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    if (i == sh_band(i) * sh_band(i)) continue;  // first of its band
    d(i, i - 1) = h.dy_sub[i];
    d(i - 1, i) = -h.dy_sub[i];
  }
  return d;
}

// D2 = d2M(Ry(b))/db2(0) from the stored diagonal and distance-2 entries (symmetric).
Eigen::MatrixXd dense_d2(const RotationHelpers& h, int order) {
  const int n = sh_count(order);
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    d(i, i) = h.ddy_diag[i];
    if (i >= 2 && sh_band(i - 2) == sh_band(i)) {
      d(i, i - 2) = h.ddy_off2[i];
      d(i - 2, i) = h.ddy_off2[i];
    }
  }
  return d;
}

// The Taylor approximations of M(Ry(b)) ([2] Sec. 3), densely.
Eigen::MatrixXd taylor_matrix(RotationMethod method, int order, double b) {
  const RotationHelpers& h = *helpers();
  const int n = sh_count(order);
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(n, n) + b * dense_d1(h, order);
  const Eigen::MatrixXd d2 = dense_d2(h, order);
  if (method == RotationMethod::taylor15) a += 0.5 * b * b * Eigen::MatrixXd(d2.diagonal().asDiagonal());
  if (method == RotationMethod::taylor2) a += 0.5 * b * b * d2;
  return a;
}

const std::vector<int> kOrders = {1, 2, 3, 4, 5, 8, 13, 20};

// ---------------------------------------------------------------------------
// Exact methods against rotate-then-project.

// Both exact methods in precision T against rotate-then-project: `per_order` random
// rotations of random coefficients at every order of kOrders.
template <class T>
void expect_exact_methods_match_quadrature(unsigned seed, int per_order, double tol) {
  std::mt19937_64 rng(seed);
  for (int order : kOrders) {
    for (int k = 0; k < per_order; ++k) {
      const Mat3<double> r = random_rotation(rng);
      const std::vector<double> f = random_coeffs(order, rng);
      const std::vector<double> want = rotate_by_quadrature(order, r, f);
      for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz}) {
        const std::vector<T> got = rotate<T>(order, r, m, f);
        const double err = distance(got, want) / norm(f);
        EXPECT_LE(err, tol) << rotation_method_name(m) << " N " << order << " R " << matrix_text(r);
      }
    }
  }
}

TEST(RotationExact, ReferenceAndZxzxzMatchQuadratureDouble) {
  expect_exact_methods_match_quadrature<double>(101, 3, kExactTolDouble);
}

TEST(RotationExact, ReferenceAndZxzxzMatchQuadratureFloat) {
  expect_exact_methods_match_quadrature<float>(102, 2, kExactTolFloat);
}

TEST(RotationExact, ZxzxzMatchesReferenceEveryOrder) {
  std::mt19937_64 rng(103);
  for (int order = 1; order <= kHelperOrder; ++order) {
    for (int k = 0; k < 4; ++k) {
      const Mat3<double> r = random_rotation(rng);
      const std::vector<double> f = random_coeffs(order, rng);
      const std::vector<double> ref = rotate<double>(order, r, RotationMethod::reference, f);
      const std::vector<double> zx = rotate<double>(order, r, RotationMethod::zxzxz, f);
      EXPECT_LE(distance(zx, ref) / norm(f), kExactTolDouble) << "N " << order << " R " << matrix_text(r);
      const std::vector<float> reff = rotate<float>(order, r, RotationMethod::reference, f);
      const std::vector<float> zxf = rotate<float>(order, r, RotationMethod::zxzxz, f);
      EXPECT_LE(distance(reff, ref) / norm(f), kExactTolFloat) << "float reference N " << order;
      EXPECT_LE(distance(zxf, ref) / norm(f), kExactTolFloat) << "float zxzxz N " << order;
    }
  }
}

TEST(RotationExact, ReferenceBlocksAreOrthogonal) {
  // Each band block must satisfy B B^T = I. Measured 7e-15 (N = 20).
  constexpr double kTol = 1e-13;
  std::mt19937_64 rng(104);
  for (int k = 0; k < 5; ++k) {
    const Mat3<double> r = random_rotation(rng);
    const Eigen::MatrixXd m = reference_matrix(kHelperOrder, r);
    for (int l = 0; l < kHelperOrder; ++l) {
      const Eigen::MatrixXd b = m.block(l * l, l * l, 2 * l + 1, 2 * l + 1);
      const double defect = (b * b.transpose() - Eigen::MatrixXd::Identity(2 * l + 1, 2 * l + 1)).cwiseAbs().maxCoeff();
      EXPECT_LE(defect, kTol) << "band " << l << " R " << matrix_text(r);
    }
    // Nothing outside the band blocks (a rotation never mixes bands).
    Eigen::MatrixXd off = m;
    for (int l = 0; l < kHelperOrder; ++l) off.block(l * l, l * l, 2 * l + 1, 2 * l + 1).setZero();
    EXPECT_EQ(off.cwiseAbs().maxCoeff(), 0.0);
  }
}

// The reference recurrence builds each band from the one before: at high orders its
// rounding compounds. Carried in long double, R then R^T returns a vector within 7e-15 at
// N = 64 and 1.3e-9 at 128 (in double: 4e-12 and 3e-6), and no band's norm moves by more
// than 2.4e-15 at 64 built by GCC at -O3, 1.4e-14 by clang at -O1 (the apply's sums; 5e-13
// in double).
TEST(RotationExact, ReferenceStaysExactAtHighOrders) {
  std::mt19937_64 rng(106);
  for (const auto& [order, round_trip, band_norm] : {std::tuple{64, 5e-14, 5e-14}, std::tuple{128, 1e-8, 3e-9}}) {
    const Mat3<double> r = random_rotation(rng);
    const std::vector<double> f = random_coeffs(order, rng);
    const std::vector<double> g = rotate<double>(order, r, RotationMethod::reference, f);
    const std::vector<double> back = rotate<double>(order, r.transpose(), RotationMethod::reference, g);
    EXPECT_LE(distance(back, f) / norm(f), round_trip) << "N " << order;
    for (int l = 0; l < order; ++l) {
      double a = 0, b = 0;
      for (int i = l * l; i < (l + 1) * (l + 1); ++i) a += f[i] * f[i], b += g[i] * g[i];
      EXPECT_LE(std::abs(std::sqrt(b / a) - 1), band_norm) << "N " << order << " band " << l;
    }
  }
}

TEST(RotationExact, CompositionApplyTwiceEqualsOnce) {
  std::mt19937_64 rng(105);
  for (int order : {2, 5, 11, 20}) {
    for (int k = 0; k < 3; ++k) {
      const Mat3<double> r1 = random_rotation(rng), r2 = random_rotation(rng);
      const std::vector<double> f = random_coeffs(order, rng);
      for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz}) {
        const std::vector<double> once = rotate<double>(order, r1 * r2, m, f);
        // g = f(R2^-1 .) then h = g(R1^-1 .) = f((R1 R2)^-1 .)
        const std::vector<double> twice = rotate<double>(order, r1, m, rotate<double>(order, r2, m, f));
        EXPECT_LE(distance(once, twice) / norm(f), kExactTolDouble) << rotation_method_name(m) << " N " << order;
      }
    }
  }
}

TEST(RotationExact, IdentityLeavesCoefficientsUnchanged) {
  // Identity: every method, exact up to a few roundings (zxzxz does X90^T X90).
  constexpr double kTol = 1e-14;
  std::mt19937_64 rng(106);
  const int order = kHelperOrder;
  const std::vector<double> f = random_coeffs(order, rng);
  for (RotationMethod m : {RotationMethod::automatic, RotationMethod::reference, RotationMethod::zxzxz,
                           RotationMethod::taylor1, RotationMethod::taylor15, RotationMethod::taylor2}) {
    RotationMethod resolved;
    const std::vector<double> got =
        rotate<double>(order, Mat3<double>::Identity(), m, f, kDefaultRotationTolerance, &resolved);
    EXPECT_LE(distance(got, f) / norm(f), kTol) << rotation_method_name(m);
    if (m == RotationMethod::automatic)
      EXPECT_EQ(resolved, RotationMethod::taylor1) << "no tilt: the cheapest method is exact";
  }
}

// Rotations whose zyz angles sit at or next to the gimbal locks, and half turns.
std::vector<std::pair<std::string, Mat3<double>>> edge_rotations() {
  std::vector<std::pair<std::string, Mat3<double>>> rs;
  const Vec3<double> generic = Vec3<double>(1, 2, 3).normalized();
  rs.push_back({"180 about x", axis_angle({1, 0, 0}, kPi)});
  rs.push_back({"180 about y", axis_angle({0, 1, 0}, kPi)});
  rs.push_back({"180 about z", axis_angle({0, 0, 1}, kPi)});
  rs.push_back({"180 about (1,2,3)", axis_angle(generic, kPi)});
  rs.push_back({"180 about (1,-1,0)", axis_angle({1, -1, 0}, kPi)});
  // Exact half turns as integer matrices (no rounding in the input at all).
  Mat3<double> hx, hy, hz;
  hx << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  hy << -1, 0, 0, 0, 1, 0, 0, 0, -1;
  hz << -1, 0, 0, 0, -1, 0, 0, 0, 1;
  rs.push_back({"exact diag(1,-1,-1)", hx});
  rs.push_back({"exact diag(-1,1,-1)", hy});
  rs.push_back({"exact diag(-1,-1,1)", hz});
  for (double beta : {0.0, kPi, 1e-9, kPi - 1e-9, 1e-300}) {
    std::ostringstream s;
    s << "zyz(0.7, " << beta << ", -2.1)";
    rs.push_back({s.str(), matrix_from_zyz<double>({0.7, beta, -2.1})});
  }
  for (double angle : {1e-3, 1e-5, 1e-8, 1e-12}) {
    std::ostringstream s;
    s << angle << " rad about (1,2,3)";
    rs.push_back({s.str(), axis_angle(generic, angle)});
  }
  return rs;
}

TEST(RotationExact, HalfTurnsAndGimbalLocksMatchQuadrature) {
  std::mt19937_64 rng(107);
  for (int order : {4, 9, 20}) {
    const std::vector<double> f = random_coeffs(order, rng);
    for (const auto& [name, r] : edge_rotations()) {
      const std::vector<double> want = rotate_by_quadrature(order, r, f);
      for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz}) {
        const std::vector<double> got = rotate<double>(order, r, m, f);
        EXPECT_LE(distance(got, want) / norm(f), kExactTolDouble)
            << rotation_method_name(m) << " N " << order << " " << name;
        const std::vector<float> gotf = rotate<float>(order, r, m, f);
        EXPECT_LE(distance(gotf, want) / norm(f), kExactTolFloat)
            << "float " << rotation_method_name(m) << " N " << order << " " << name;
      }
    }
  }
}

TEST(RotationExact, NearIdentityKeepsFullPrecision) {
  // DirectXMath recovers beta from sqrt(1 - cz^2) in float and errs by 1e-4..1e-3 for
  // rotations of 1e-3..1e-4 rad. Here the split is done by atan2 on well-conditioned
  // combinations, so the error stays at rounding level. Measured (N <= 20): double
  // <= 3.6e-15 (1.0e-15 at N = 6, 1.9e-15 at N = 12), float <= 1.4e-6 (8.9e-7 at
  // N = 12) relative to ||f||.
  auto tol_double = [](int n) { return 2e-15 + 2.5e-16 * n; };  // ~1e-15 level
  constexpr double kTolFloat = 2e-6;
  std::mt19937_64 rng(108);
  for (int order : {3, 6, 12, 20}) {
    for (double angle : {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8}) {
      for (int k = 0; k < 4; ++k) {
        const Mat3<double> r = axis_angle(random_axis(rng), angle);
        const std::vector<double> f = random_coeffs(order, rng);
        const std::vector<double> ref = rotate<double>(order, r, RotationMethod::reference, f);
        const std::vector<double> zx = rotate<double>(order, r, RotationMethod::zxzxz, f);
        EXPECT_LE(distance(zx, ref) / norm(f), tol_double(order)) << "N " << order << " angle " << angle;
        // The reference itself against quadrature (no zyz split involved at all).
        if (k == 0)
          EXPECT_LE(distance(ref, rotate_by_quadrature(order, r, f)) / norm(f), 1e-14)
              << "N " << order << " angle " << angle;
        for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz}) {
          const std::vector<float> got = rotate<float>(order, r, m, f);
          EXPECT_LE(distance(got, ref) / norm(f), kTolFloat)
              << "float " << rotation_method_name(m) << " N " << order << " angle " << angle;
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Euler angles.

std::vector<Mat3<double>> euler_test_matrices() {
  std::vector<Mat3<double>> ms;
  for (const auto& [name, r] : edge_rotations()) ms.push_back(r);
  ms.push_back(Mat3<double>::Identity());
  // Quarter turns: permutation matrices with signs.
  for (const Vec3<double>& axis : {Vec3<double>(1, 0, 0), Vec3<double>(0, 1, 0), Vec3<double>(0, 0, 1)})
    for (double angle : {kPi / 2, -kPi / 2, kPi, 3 * kPi / 2}) ms.push_back(axis_angle(axis, angle));
  std::mt19937_64 rng(201);
  std::uniform_real_distribution<double> ua(-kPi, kPi);
  // Gimbal locks reached through matrix_from_zyz with arbitrary alpha, gamma.
  for (double beta : {0.0, kPi, 1e-9, kPi - 1e-9, 1e-16, kPi - 1e-16, 1e-5, kPi - 1e-5})
    for (int k = 0; k < 20; ++k) ms.push_back(matrix_from_zyz<double>({ua(rng), beta, ua(rng)}));
  // Near the identity and near the half turn about z (beta ~ 0, alpha + gamma ~ pi), and
  // near half turns about horizontal axes (beta ~ pi).
  for (double angle = 1e-3; angle >= 1e-13; angle /= 10) {
    for (int k = 0; k < 10; ++k) {
      const Vec3<double> axis = random_axis(rng);
      ms.push_back(axis_angle(axis, angle));
      ms.push_back(axis_angle({angle * axis.x(), angle * axis.y(), 1}, kPi + angle * axis.z()));
      ms.push_back(axis_angle({axis.x(), axis.y(), angle * axis.z()}, kPi - angle));
    }
  }
  for (int k = 0; k < 20000; ++k) ms.push_back(random_rotation(rng));
  return ms;
}

TEST(Euler, ZyzRoundTripDouble) {
  // matrix_from_zyz(zyz_from_matrix(R)) == R to 1e-15 (~4.5 ulp) for every input,
  // including the gimbal locks and rotations of 1e-13 rad. An input that is itself off
  // orthonormal by rounding (a quaternion's matrix: up to ~2e-15) cannot be reproduced
  // closer than that by any rotation, so its defect is added: over 10^6 random
  // quaternion matrices the worst error was 1.33e-15 with a defect of 2.1e-15, and
  // 29 of them exceeded 1e-15, each with a defect above 1.6e-15.
  constexpr double kTol = 1e-15;
  double worst = 0;
  for (const Mat3<double>& r : euler_test_matrices()) {
    const EulerZYZ<double> e = zyz_from_matrix<double>(r);
    const double err = (matrix_from_zyz<double>(e) - r).cwiseAbs().maxCoeff();
    worst = std::max(worst, err);
    EXPECT_LE(err, kTol + orthonormality_defect<double>(r))
        << matrix_text(r) << " -> a " << e.alpha << " b " << e.beta << " g " << e.gamma;
    EXPECT_GE(e.beta, 0.0);
    EXPECT_LE(e.beta, kPi);
    EXPECT_TRUE(std::isfinite(e.alpha) && std::isfinite(e.gamma));
  }
  RecordProperty("worst_roundtrip_error", std::to_string(worst));
}

TEST(Euler, ZyzRoundTripFloat) {
  // Same in float: a few float ulp (the trig calls and products each add ~0.5 ulp;
  // measured 3.3 ulp over 2e5 random matrices), plus the input's own defect.
  constexpr float kTol = 4 * kEpsF;
  for (const Mat3<double>& rd : euler_test_matrices()) {
    const Mat3<float> r = rd.cast<float>();
    const EulerZYZ<float> e = zyz_from_matrix<float>(r);
    const float err = (matrix_from_zyz<float>(e) - r).cwiseAbs().maxCoeff();
    EXPECT_LE(err, kTol + orthonormality_defect<float>(r))
        << matrix_text(rd) << " -> a " << e.alpha << " b " << e.beta << " g " << e.gamma;
    EXPECT_GE(e.beta, 0.0f);
    EXPECT_LE(e.beta, std::numbers::pi_v<float>);
  }
}

TEST(Euler, AnglesAreRecoveredAwayFromLocks) {
  // Away from the locks the angles themselves are unique (alpha, gamma in (-pi, pi]).
  std::mt19937_64 rng(202);
  std::uniform_real_distribution<double> ua(-3.1, 3.1), ub(0.01, kPi - 0.01);
  for (int k = 0; k < 1000; ++k) {
    const EulerZYZ<double> e{ua(rng), ub(rng), ua(rng)};
    const EulerZYZ<double> got = zyz_from_matrix<double>(matrix_from_zyz<double>(e));
    EXPECT_NEAR(got.alpha, e.alpha, 1e-13);
    EXPECT_NEAR(got.beta, e.beta, 1e-13);
    EXPECT_NEAR(got.gamma, e.gamma, 1e-13);
  }
  // The small tilt of a near-identity rotation is recovered with full relative
  // precision (acos(R22) would give 0 below ~1e-8 rad).
  for (double angle : {1e-4, 1e-8, 1e-12}) {
    const EulerZYZ<double> got = zyz_from_matrix<double>(axis_angle({1, 0, 0}, angle));
    EXPECT_NEAR(got.beta, angle, 4 * kEps * angle) << angle;
    const EulerZYZ<float> gotf = zyz_from_matrix<float>(axis_angle({1, 0, 0}, angle).cast<float>());
    EXPECT_NEAR(gotf.beta, angle, 4 * kEpsF * angle) << angle;
  }
}

TEST(Euler, QuaternionAndZyzAgree) {
  // Rz(a) Ry(b) Rz(g) as the quaternion product q_z(a) q_y(b) q_z(g).
  std::mt19937_64 rng(203);
  std::uniform_real_distribution<double> ua(-kPi, kPi), ub(0, kPi);
  for (int k = 0; k < 200; ++k) {
    const double a = ua(rng), b = ub(rng), g = ua(rng);
    const Eigen::Quaterniond q = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(b, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(g, Eigen::Vector3d::UnitZ());
    const Mat3<double> fromq = matrix_from_quaternion<double>(q.w(), q.x(), q.y(), q.z());
    EXPECT_LE((fromq - matrix_from_zyz<double>({a, b, g})).cwiseAbs().maxCoeff(), 4 * kEps);
    EXPECT_LE((fromq - q.toRotationMatrix()).cwiseAbs().maxCoeff(), 4 * kEps);
  }
  // Orthonormality defect of a clean rotation vs a scaled one.
  EXPECT_LE(orthonormality_defect<double>(random_rotation(rng)), 4 * kEps);
  EXPECT_NEAR(orthonormality_defect<double>(1.001 * Mat3<double>::Identity()), 0.002001, 1e-12);
}

// In float on x86-64, matrix_from_quaternion runs in SSE2 lanes; it must give the scalar
// code's bits for every input: random unit quaternions, and every combination of
// components from a set with signed zeros, exact halves, tiny and huge values (the
// entries' zero signs and roundings are where a reordered operation would show; a huge
// component overflows, and then both give NaN, whose sign bit says nothing).
TEST(Euler, FloatQuaternionMatrixIsTheScalarCodeBitForBit) {
  auto same = [](float w, float x, float y, float z) {
    const Mat3<float> fast = matrix_from_quaternion<float>(w, x, y, z);
    const Mat3<float> slow = detail::matrix_from_quaternion_scalar<float>(w, x, y, z);
    for (int i = 0; i < 9; ++i) {
      const float a = fast.data()[i], b = slow.data()[i];
      if (std::isnan(a) != std::isnan(b)) return false;
      if (!std::isnan(a) && std::memcmp(&a, &b, sizeof a) != 0) return false;
    }
    return true;
  };
  std::mt19937_64 rng(205);
  std::normal_distribution<float> n;
  for (int k = 0; k < 100000; ++k) {
    float q[4] = {n(rng), n(rng), n(rng), n(rng)};
    const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (float& c : q) c /= len;
    ASSERT_TRUE(same(q[0], q[1], q[2], q[3])) << "quaternion " << k;
  }
  const float values[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -0.5f, 0.70710677f, -0.3f, 1e-30f, -3e38f};
  for (float w : values)
    for (float x : values)
      for (float y : values)
        for (float z : values) ASSERT_TRUE(same(w, x, y, z)) << w << " " << x << " " << y << " " << z;
}

// zyz_cos_sin_from_quaternion against the matrix route: the same rotation (recomposed
// matrices agree) for random quaternions of both signs, gimbal locks (b = 0, b = pi),
// tiny tilts on both sides of the b = 0 threshold, and near the half turn.
TEST(Euler, QuaternionRouteMatchesMatrixRoute) {
  std::mt19937_64 rng(207);
  std::normal_distribution<double> n;
  std::vector<Eigen::Vector4d> qs;
  for (int k = 0; k < 300; ++k) qs.push_back(Eigen::Vector4d(n(rng), n(rng), n(rng), n(rng)).normalized());
  for (const double t : {0.0, 1e-30, 1e-20, 1e-12, 1e-9, 1e-5}) {  // tilt about (x, y)
    const double p = n(rng);
    qs.push_back(Eigen::Vector4d(std::cos(p), t * 0.6, -t * 0.8, std::sin(p)).normalized());  // b ~ 2t
    qs.push_back(Eigen::Vector4d(t * 0.6, std::cos(p), std::sin(p), -t * 0.8).normalized());  // b ~ pi - 2t
  }
  for (const Eigen::Vector4d& q : qs)
    for (const double sign : {1.0, -1.0}) {
      const double w = sign * q[0], x = sign * q[1], y = sign * q[2], z = sign * q[3];
      const Mat3<double> r = matrix_from_quaternion<double>(w, x, y, z);
      const ZyzCosSin<double> e = zyz_cos_sin_from_quaternion<double>(w, x, y, z);
      // Rz(a) Ry(b) Rz(g) from the cosines and sines
      Mat3<double> za, yb, zg;
      za << e.ca, -e.sa, 0, e.sa, e.ca, 0, 0, 0, 1;
      yb << e.cb, 0, e.sb, 0, 1, 0, -e.sb, 0, e.cb;
      zg << e.cg, -e.sg, 0, e.sg, e.cg, 0, 0, 0, 1;
      EXPECT_LE((za * yb * zg - r).cwiseAbs().maxCoeff(), 8 * kEps)
          << "q = " << w << ", " << x << ", " << y << ", " << z;
      EXPECT_NEAR(e.ca * e.ca + e.sa * e.sa, 1.0, 4 * kEps);
      EXPECT_NEAR(e.cg * e.cg + e.sg * e.sg, 1.0, 4 * kEps);
      EXPECT_GE(e.sb, 0.0);
    }
}

// ShRotation::set_quaternion gives the rotation set(matrix) gives, for every method and
// for orders with and without the generated kernels, in double and float.
template <class T>
void check_set_quaternion(double tol) {
  std::mt19937_64 rng(211);
  std::normal_distribution<double> n;
  for (const int order : {2, 3, 4, 6, 11, 20}) {
    ShRotation<T> by_q(order, helpers()), by_r(order, helpers());
    std::vector<T> in(sh_count(order)), a(sh_count(order)), b(sh_count(order));
    for (auto& v : in) v = static_cast<T>(n(rng));
    for (int k = 0; k < 20; ++k) {
      Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
      if (k == 1) q = Eigen::Vector4d(0.6, 0, 0, 0.8);  // b = 0
      if (k == 2) q = Eigen::Vector4d(0, 0.6, 0.8, 0);  // b = pi
      if (k == 3) q = Eigen::Vector4d(1, 1e-7, 0, 0);   // tilt 2e-7: automatic takes Taylor
      q.normalize();
      const T w = static_cast<T>(q[0]), x = static_cast<T>(q[1]), y = static_cast<T>(q[2]), z = static_cast<T>(q[3]);
      for (const RotationMethod m : {RotationMethod::automatic, RotationMethod::zxzxz, RotationMethod::taylor1,
                                     RotationMethod::taylor2, RotationMethod::reference}) {
        // At b = pi only a - g is defined and the two routes split it differently: exact
        // methods agree, a Taylor expansion in b (meaningless at b = pi) does not.
        const bool taylor = m == RotationMethod::taylor1 || m == RotationMethod::taylor2;
        if (k == 2 && taylor) continue;
        ASSERT_TRUE(by_q.set_quaternion(w, x, y, z, m));
        ASSERT_TRUE(by_r.set(matrix_from_quaternion<T>(w, x, y, z), m));
        EXPECT_EQ(by_q.method(), by_r.method());
        by_q.apply(in, a);
        by_r.apply(in, b);
        // relative to the output too: a Taylor step at a large tilt amplifies (b (N-1))^2
        const double scale =
            norm(std::vector<double>(in.begin(), in.end())) + norm(std::vector<double>(b.begin(), b.end()));
        EXPECT_LE(distance(a, b), tol * scale)
            << "order " << order << " method " << rotation_method_name(m) << " rotation " << k;
      }
    }
  }
}
// Both routes are exact to rounding: double ~1e-15, float ~1e-6 after up to 20 bands of
// multiple-angle recurrences (the Taylor branches' own error is the same on both).
TEST(RotationApi, SetQuaternionEqualsSetMatrixDouble) { check_set_quaternion<double>(1e-13); }
TEST(RotationApi, SetQuaternionEqualsSetMatrixFloat) { check_set_quaternion<float>(2e-5); }

// Order 2 in float runs band 1 in SSE2 lanes (apply, interleaved apply, rotate_batch): the
// scalar band1_closed's bits for random and edge rotations and inputs with zeros of
// both signs (an output that cancels to zero keeps the scalar code's sign).
TEST(RotationApi, Order2FloatIsTheScalarCodeBitForBit) {
  std::mt19937_64 rng(213);
  std::vector<Mat3<float>> rs;
  for (const auto& [name, r] : edge_rotations()) rs.push_back(r.cast<float>());
  for (int k = 0; k < 2000; ++k) rs.push_back(random_rotation(rng).cast<float>());
  // Entries 0, -0 and +-1 (quarter turns about each axis, the cyclic permutation), where
  // outputs cancel to zeros of either sign.
  for (const Vec3<double>& axis : {Vec3<double>(1, 0, 0), Vec3<double>(0, 1, 0), Vec3<double>(0, 0, 1)})
    for (const float sign : {1.0f, -1.0f})
      rs.push_back(matrix_from_quaternion<float>(0.70710677f, sign * 0.70710677f * float(axis.x()),
                                                 sign * 0.70710677f * float(axis.y()),
                                                 sign * 0.70710677f * float(axis.z())));
  Mat3<float> cyclic;
  cyclic << 0, -0.0f, 1, 1, 0, -0.0f, -0.0f, 1, 0;
  rs.push_back(cyclic);
  std::vector<std::array<float, 4>> ins;
  std::uniform_real_distribution<float> u(-1, 1);
  for (int k = 0; k < 8; ++k) ins.push_back({u(rng), u(rng), u(rng), u(rng)});
  ins.push_back({1, 0, 0, 0});
  ins.push_back({-0.0f, -0.0f, 0.0f, -0.0f});
  ins.push_back({2, 1, 1, -1});
  ins.push_back({0, 1, -1, 1});
  ShRotation<float> rotation(2, helpers());
  std::vector<float> flat_in, flat_out;
  for (const Mat3<float>& r : rs)
    for (const auto& in : ins) {
      float want[4], fast[4], applied[4];
      detail::order2_scalar<float>(r.data(), in.data(), want);
      detail::order2_rotate<float>(r.data(), in.data(), fast);
      ASSERT_EQ(std::memcmp(want, fast, sizeof want), 0) << "in " << in[0] << " " << in[1] << " " << in[2];
      ASSERT_TRUE(rotation.set(r));
      rotation.apply(in, applied);
      ASSERT_EQ(std::memcmp(want, applied, sizeof want), 0);
      flat_in.insert(flat_in.end(), in.begin(), in.end());
      flat_out.insert(flat_out.end(), want, want + 4);
    }
  // rotate_batch over the same pairs: each rotation once per input.
  std::vector<Mat3<float>> pairs;
  for (const Mat3<float>& r : rs)
    for (std::size_t k = 0; k < ins.size(); ++k) pairs.push_back(r);
  std::vector<float> out(flat_in.size());
  ASSERT_TRUE(rotate_batch<float>(rotation, pairs, flat_in, out));
  EXPECT_EQ(std::memcmp(out.data(), flat_out.data(), sizeof(float) * out.size()), 0);
}

// ---------------------------------------------------------------------------
// Convention: a lobe along d ends up along R d.

// ZH lobe along s: g*_l y_l^m(s) (docs/conventions.md), with arbitrary g*_l.
std::vector<double> zh_lobe(int order, const Vec3<double>& s) {
  std::vector<double> y(sh_count(order));
  eval_sh<double>(order, s, y);
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) y[sh_index(l, m)] *= 1.0 / (1.0 + l * l);
  return y;
}

TEST(RotationConvention, LobeAlongDEndsUpAlongRD) {
  std::mt19937_64 rng(301);
  for (int order : {2, 3, 8, 20}) {
    for (int k = 0; k < 4; ++k) {
      const Mat3<double> r = random_rotation(rng);
      const Vec3<double> d = random_axis(rng);
      const std::vector<double> f = zh_lobe(order, d);
      const std::vector<double> want = zh_lobe(order, r * d);
      for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz}) {
        EXPECT_LE(distance(rotate<double>(order, r, m, f), want) / norm(f), kExactTolDouble)
            << rotation_method_name(m) << " N " << order;
        EXPECT_LE(distance(rotate<float>(order, r, m, f), want) / norm(f), kExactTolFloat)
            << "float " << rotation_method_name(m) << " N " << order;
      }
    }
  }
}

TEST(RotationConvention, BandOneIsTheRotationInYZXOrderWithSigns) {
  // A linear function a.w has band-1 coefficients k (-a_y, a_z, -a_x) (y_1^-1 = -c y,
  // y_1^0 = c z, y_1^1 = -c x), and rotating it gives (R a).w. So band 1 of M(R) is
  // S P R P^T S with P picking (y, z, x) and S = diag(-1, 1, -1).
  std::mt19937_64 rng(302);
  const int axis[3] = {1, 2, 0};
  const double sign[3] = {-1, 1, -1};
  for (int k = 0; k < 10; ++k) {
    const Mat3<double> r = random_rotation(rng);
    const Eigen::MatrixXd m = reference_matrix(2, r);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        EXPECT_NEAR(m(1 + i, 1 + j), sign[i] * sign[j] * r(axis[i], axis[j]), 2 * kEps)
            << i << "," << j << " R " << matrix_text(r);
  }
  // Worked example: Rx(+90 deg) takes z to -y, so y_1^0 (= c z) becomes c (-y) = y_1^-1.
  Mat3<double> rx90;
  rx90 << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const std::vector<double> e10 = {0, 0, 1, 0};
  for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz}) {
    const std::vector<double> got = rotate<double>(2, rx90, m, e10);
    EXPECT_NEAR(got[0], 0, 1e-15);
    EXPECT_NEAR(got[1], 1, 1e-15) << rotation_method_name(m) << ": y_1^0 must become y_1^-1";
    EXPECT_NEAR(got[2], 0, 1e-15);
    EXPECT_NEAR(got[3], 0, 1e-15);
  }
  // The stored X90 has the same entry: X90[y_1^-1][y_1^0] = +1.
  const RotationHelpers& h = *helpers();
  double x = 0;
  for (int k = h.x90_row[1]; k < h.x90_row[2]; ++k)
    if (h.x90_col[k] == 2) x = h.x90_val[k];
  EXPECT_NEAR(x, 1.0, 1e-15);
}

// ---------------------------------------------------------------------------
// Taylor derivative matrices.

// D1 of [2] Fig. 2 in the paper's basis (real SH without the Condon-Shortley
// phase): the printed sub-diagonal D1[m][m-1] of bands 1-3, m = -l+1..l.
// Our basis differs from the paper's by (-1)^m on every function, so our
// D1[m][m'] = (-1)^(m+m') paper[m][m']: every sub-diagonal entry flips sign (m' = m-1),
// which for an antisymmetric tridiagonal matrix is the same as our D1 = paper's D1^T.
// D2 has entries only at even distance, so it matches the paper without any sign.
// Checked below: with the sign flip every printed digit agrees; without it none of the
// non-zero entries would.
struct PrintedSub {
  int l, m;
  double value;
};
const PrintedSub kPaperD1Sub[] = {{1, 0, 0.0},    {1, 1, 1.0},                                // band 1
                                  {2, -1, -1.0},  {2, 0, 0.0},    {2, 1, 1.73}, {2, 2, 1.0},  // band 2
                                  {3, -2, -1.22}, {3, -1, -1.58}, {3, 0, 0.0},  {3, 1, 2.45},
                                  {3, 2, 1.58},   {3, 3, 1.22}};

struct PrintedD2 {
  int l, m, mp;
  double value;
};
const PrintedD2 kPaperD2[] = {{1, -1, -1, 0.0},  {1, 0, 0, -1.0},   {1, 1, 1, -1.0},  // band 1
                              {2, -2, -2, -1.0}, {2, -1, -1, -1.0}, {2, 0, 0, -3.0},   {2, 1, 1, -4.0},
                              {2, 2, 2, -1.0},   {2, 0, 2, 1.73},   {2, -2, 0, 0.0},   {2, -1, 1, 0.0},  // band 2
                              {3, -3, -3, -1.5}, {3, -2, -2, -4.0}, {3, -1, -1, -2.5}, {3, 0, 0, -6.0},
                              {3, 1, 1, -8.5},   {3, 2, 2, -4.0},   {3, 3, 3, -1.5},   {3, -3, -1, 1.94},
                              {3, 0, 2, 3.87},   {3, 1, 3, 1.94},   {3, -2, 0, 0.0},   {3, -1, 1, 0.0}};

// Half a unit in the last of the 3 printed significant digits (values 1..10).
constexpr double kPrintedHalfUnit = 0.005;

TEST(TaylorMatrices, BandsOneToThreeMatchPaperFigure2) {
  const RotationHelpers& h = *helpers();
  for (const PrintedSub& p : kPaperD1Sub) {
    const double ours = h.dy_sub[sh_index(p.l, p.m)];
    EXPECT_NEAR(ours, -p.value, kPrintedHalfUnit) << "D1[" << p.m << "][" << p.m - 1 << "] band " << p.l << ": ours "
                                                  << ours << ", paper (no Condon-Shortley phase) " << p.value;
    if (p.value == 0.0) EXPECT_EQ(ours, 0.0) << "structural zero, band " << p.l << " m " << p.m;
  }
  const Eigen::MatrixXd d2 = dense_d2(h, 4);
  for (const PrintedD2& p : kPaperD2) {
    const double ours = d2(sh_index(p.l, p.m), sh_index(p.l, p.mp));
    EXPECT_NEAR(ours, p.value, kPrintedHalfUnit)
        << "D2[" << p.m << "][" << p.mp << "] band " << p.l << ": ours " << ours << ", paper " << p.value;
    EXPECT_EQ(ours, d2(sh_index(p.l, p.mp), sh_index(p.l, p.m)));
  }
}

TEST(TaylorMatrices, D1MatchesAngularMomentumClosedForm) {
  // The y-rotation generator in complex SH has the ladder entries
  // (1/2) sqrt((l+m)(l-m+1)); in the real basis with the Condon-Shortley phase the
  // (m, m-1) entry is -(1/2) sqrt((l+m)(l-m+1)) for m >= 2, -sqrt(l(l+1)/2) for m = 1
  // (the m = 0 function pairs with both cos terms, hence sqrt2), 0 for m = 0 (the
  // sin and cos families do not mix under a y-rotation) and +(1/2) sqrt((l+m)(l-m+1))
  // for m <= -1. Bands 1-3 of this formula are the paper's printed values above.
  // Tolerance: X90 comes from a quadrature (~1e-15) and D1 = X90^T Gz X90 multiplies
  // by |m| <= l, so ~l * 1e-15.
  const RotationHelpers& h = *helpers();
  for (int l = 0; l < kHelperOrder; ++l) {
    EXPECT_EQ(h.dy_sub[sh_index(l, -l)], 0.0) << "first of band " << l;
    for (int m = -l + 1; m <= l; ++m) {
      double want;
      if (m >= 2)
        want = -0.5 * std::sqrt(double((l + m) * (l - m + 1)));
      else if (m == 1)
        want = -std::sqrt(l * (l + 1) / 2.0);
      else if (m == 0)
        want = 0.0;
      else
        want = 0.5 * std::sqrt(double((l + m) * (l - m + 1)));
      EXPECT_NEAR(h.dy_sub[sh_index(l, m)], want, 1e-14 * (l + 1)) << "band " << l << " m " << m;
    }
  }
}

TEST(TaylorMatrices, D1IsTheDerivativeOfTheReferenceYRotation) {
  // 4-point central difference of M(Ry(b)) at b = 0 from the reference (IR) rotation:
  // truncation h^4 m^5 / 30 for the e^{i m b} eigen-components, rounding ~1.5 eps_M / h
  // with eps_M ~ 1e-15 the error of the reference entries. Measured at h = 1e-4:
  // 2.7e-15 (band 3), 2e-13 (band 10), 4.4e-12 (band 19).
  constexpr double kH = 1e-4;
  const int order = kHelperOrder;
  const Eigen::MatrixXd fd = (8.0 * (reference_matrix(order, ry(kH)) - reference_matrix(order, ry(-kH))) -
                              (reference_matrix(order, ry(2 * kH)) - reference_matrix(order, ry(-2 * kH)))) /
                             (12.0 * kH);
  const Eigen::MatrixXd d1 = dense_d1(*helpers(), order);
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1;
    const double tol = 2 * std::pow(kH, 4) * std::pow(l, 5) / 30 + 20 * kEps / kH;
    const Eigen::MatrixXd fb = fd.block(l * l, l * l, size, size);
    const double err = (fb - d1.block(l * l, l * l, size, size)).cwiseAbs().maxCoeff();
    EXPECT_LE(err, tol) << "band " << l;
    // Antisymmetric (an infinitesimal rotation) and tridiagonal (what the storage assumes).
    EXPECT_LE((fb + fb.transpose()).cwiseAbs().maxCoeff(), tol) << "band " << l;
    for (int a = 0; a < size; ++a)
      for (int b = 0; b < size; ++b)
        if (std::abs(a - b) > 1) EXPECT_LE(std::abs(fb(a, b)), tol) << "band " << l << " " << a << "," << b;
  }
}

TEST(TaylorMatrices, D2IsD1Squared) {
  // Tolerance: products of two entries of size ~l, each exact to ~l * 1e-15.
  const int order = kHelperOrder;
  const RotationHelpers& h = *helpers();
  const Eigen::MatrixXd d1 = dense_d1(h, order), d2 = dense_d2(h, order);
  const Eigen::MatrixXd sq = d1 * d1;
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1;
    const double err = (sq.block(l * l, l * l, size, size) - d2.block(l * l, l * l, size, size)).cwiseAbs().maxCoeff();
    EXPECT_LE(err, 1e-13 * (l + 1) * (l + 1)) << "band " << l;
  }
  // D1^2 has nothing beyond the stored diagonals (else D2 storage would lose entries).
  Eigen::MatrixXd rest = sq - d2;
  EXPECT_LE(rest.cwiseAbs().maxCoeff(), 1e-13 * order * order);
  for (int l = 0; l < order; ++l) {
    EXPECT_EQ(h.ddy_off2[sh_index(l, -l)], 0.0);
    if (l >= 1) EXPECT_EQ(h.ddy_off2[sh_index(l, -l + 1)], 0.0);
  }
}

TEST(TaylorMatrices, TaylorMethodsApplyTheTruncatedSeries) {
  // ShRotation's sparse Taylor y-rotation equals the dense polynomial in D1, D2 (with
  // the superdiagonal taken as minus the stored subdiagonal). Pure y-rotations have
  // zyz angles (0, b, 0) exactly, so no z-rotation is involved.
  std::mt19937_64 rng(401);
  const int order = 9;
  const std::vector<double> f = random_coeffs(order, rng);
  const Eigen::Map<const Eigen::VectorXd> fv(f.data(), f.size());
  for (double b : {0.01, 0.2}) {
    for (RotationMethod m : {RotationMethod::taylor1, RotationMethod::taylor15, RotationMethod::taylor2}) {
      const Eigen::VectorXd want = taylor_matrix(m, order, b) * fv;
      const std::vector<double> got = rotate<double>(order, ry(b), m, f);
      double err = 0;
      for (int i = 0; i < sh_count(order); ++i) err = std::max(err, std::abs(got[i] - want[i]));
      EXPECT_LE(err, 1e-14) << rotation_method_name(m) << " b " << b;
    }
  }
}

// ---------------------------------------------------------------------------
// Taylor error bounds and the automatic choice.

Eigen::VectorXd error_singular_values(RotationMethod m, int order, double b) {
  const Eigen::MatrixXd e = reference_matrix(order, ry(b)) - taylor_matrix(m, order, b);
  return Eigen::JacobiSVD<Eigen::MatrixXd>(e).singularValues();
}

TEST(TaylorBounds, FirstAndSecondOrderBoundsAreExactNorms) {
  // The error matrix is a polynomial in the normal matrix D1, so its norm is the
  // largest scalar error |e^{i t} - poly(i t)| at t = b (N-1). Compared with the SVD of
  // (reference - approximation): the entries of that difference carry ~1e-14 absolute
  // rounding, so the relative tolerance is 1e-12 plus an absolute floor. Measured:
  // relative differences <= 1e-13 where the norm exceeds 1e-2; absolute <= 1e-15.
  constexpr double kRel = 1e-12, kAbs = 5e-15;
  for (int order : {2, 3, 5, 8, 12, 20}) {
    for (double b : {0.02, 0.1, 0.3, 0.7, 1.2}) {
      for (RotationMethod m : {RotationMethod::taylor1, RotationMethod::taylor2}) {
        const double svd = error_singular_values(m, order, b)(0);
        const double bound = taylor_error_bound(m, order, b);
        EXPECT_NEAR(bound, svd, kRel * svd + kAbs) << rotation_method_name(m) << " N " << order << " b " << b;
      }
    }
  }
  EXPECT_EQ(taylor_error_bound(RotationMethod::taylor1, 1, 0.5), 0.0) << "band 0 does not rotate";
  EXPECT_EQ(taylor_error_bound(RotationMethod::zxzxz, 8, 0.5), 0.0);
  EXPECT_EQ(taylor_error_bound(RotationMethod::reference, 8, 0.5), 0.0);
}

TEST(TaylorBounds, OneAndAHalfOrderBoundIsAnUpperBound) {
  const RotationHelpers& h = *helpers();
  for (int order : {2, 3, 5, 8, 12, 20}) {
    // Spectral norm of D2's off-diagonal part, and the cheaper infinity norm.
    const Eigen::MatrixXd d2 = dense_d2(h, order);
    const Eigen::MatrixXd off = d2 - Eigen::MatrixXd(d2.diagonal().asDiagonal());
    const double two_norm = Eigen::JacobiSVD<Eigen::MatrixXd>(off).singularValues()(0);
    const double inf_norm = off.cwiseAbs().rowwise().sum().maxCoeff();
    for (double b : {0.001, 0.02, 0.1, 0.3, 0.7}) {
      const double svd = error_singular_values(RotationMethod::taylor15, order, b)(0);
      for (double n2 : {two_norm, inf_norm}) {
        const double bound = taylor_error_bound(RotationMethod::taylor15, order, b, n2);
        EXPECT_GE(bound * (1 + 1e-12) + 5e-15, svd) << "N " << order << " b " << b << " |off| " << n2;
      }
      // Without the norm, the closed form (N - 1)^2, which bounds it.
      EXPECT_LE(two_norm, (order - 1) * (order - 1) * (1 + 1e-12)) << "N " << order;
      EXPECT_GE(taylor_error_bound(RotationMethod::taylor15, order, b) * (1 + 1e-12) + 5e-15, svd)
          << "N " << order << " b " << b;
    }
  }
}

TEST(TaylorBounds, AutomaticMethodMeetsToleranceAndPrefersTaylor) {
  std::mt19937_64 rng(501);
  std::uniform_real_distribution<double> ua(-kPi, kPi);
  // Extra allowance for the rounding of the exact methods (~1e-15 relative at N = 20).
  constexpr double kRoundingFloor = 1e-13;
  int taylor_picks = 0;
  for (int order : {3, 4, 6, 12, 20}) {
    for (double tol : {1e-3, 1e-5, 1e-8, 1e-10}) {
      for (double tilt : {0.0, 1e-7, 1e-5, 1e-4, 1e-3, 1e-2, 0.1, 0.5, 2.0}) {
        const Mat3<double> r = matrix_from_zyz<double>({ua(rng), tilt, ua(rng)});
        const std::vector<double> f = random_coeffs(order, rng);
        RotationMethod chosen;
        const std::vector<double> got = rotate<double>(order, r, RotationMethod::automatic, f, tol, &chosen);
        const std::vector<double> ref = rotate<double>(order, r, RotationMethod::reference, f);
        const std::string what = "N " + std::to_string(order) + " tol " + std::to_string(tol) + " tilt " +
                                 std::to_string(tilt) + " chose " + std::string(rotation_method_name(chosen));
        EXPECT_LE(distance(got, ref), (tol + kRoundingFloor) * norm(f)) << what;
        EXPECT_NE(chosen, RotationMethod::automatic) << what;
        // Cheapest first: 1st order whenever its (exact) bound passes; at orders up to 4
        // zxzxz is closed forms in R, cheaper than any Taylor step (rotation.h).
        if (order <= detail::kClosedMaxOrder)
          EXPECT_EQ(chosen, RotationMethod::zxzxz) << what;
        else if (taylor_error_bound(RotationMethod::taylor1, order, tilt) <= tol * (1 - 1e-9))
          EXPECT_EQ(chosen, RotationMethod::taylor1) << what;
        // A Taylor method is only chosen when its bound passes; 2nd order never beats
        // the tolerance when its exact error norm exceeds it.
        if (taylor_error_bound(RotationMethod::taylor2, order, tilt) > tol * (1 + 1e-9))
          EXPECT_EQ(chosen, RotationMethod::zxzxz) << what;
        if (chosen != RotationMethod::zxzxz) ++taylor_picks;
      }
    }
  }
  EXPECT_GT(taylor_picks, 20);
  // A typical case from the paper's use (normal-map perturbations): N = 5, 1 mrad tilt.
  RotationMethod chosen;
  rotate<double>(5, matrix_from_zyz<double>({0.3, 1e-3, -0.2}), RotationMethod::automatic, std::vector<double>(25, 0.1),
                 1e-5, &chosen);
  EXPECT_EQ(chosen, RotationMethod::taylor1);
}

TEST(TaylorBounds, AutomaticFloatMeetsTolerance) {
  std::mt19937_64 rng(502);
  std::uniform_real_distribution<double> ua(-kPi, kPi);
  for (double tilt : {0.0, 1e-4, 1e-2, 0.3, 1.5}) {
    const Mat3<double> r = matrix_from_zyz<double>({ua(rng), tilt, ua(rng)});
    const std::vector<double> f = random_coeffs(6, rng);
    const std::vector<float> got = rotate<float>(6, r, RotationMethod::automatic, f, 1e-3);
    const std::vector<double> ref = rotate<double>(6, r, RotationMethod::reference, f);
    EXPECT_LE(distance(got, ref), (1e-3 + kExactTolFloat) * norm(f)) << "tilt " << tilt;
  }
}

// ---------------------------------------------------------------------------
// Batch and API edge cases.

TEST(RotationApi, BatchEqualsIndividualRotations) {
  test::for_each_kernel_copy([] {
    std::mt19937_64 rng(601);
    const int order = 7, n = sh_count(order), count = 6;
    std::vector<Mat3<double>> rs;
    std::vector<double> in;
    for (int k = 0; k < count; ++k) {
      rs.push_back(k == 0 ? Mat3<double>::Identity() : random_rotation(rng));
      const std::vector<double> f = random_coeffs(order, rng);
      in.insert(in.end(), f.begin(), f.end());
    }
    for (RotationMethod m :
         {RotationMethod::automatic, RotationMethod::reference, RotationMethod::zxzxz, RotationMethod::taylor2}) {
      ShRotation<double> rotation(order, helpers());
      std::vector<double> out(in.size());
      ASSERT_TRUE(rotate_batch<double>(rotation, rs, in, out, m, 1e-6));
      for (int k = 0; k < count; ++k) {
        const std::vector<double> f(in.begin() + k * n, in.begin() + (k + 1) * n);
        const std::vector<double> one = rotate<double>(order, rs[k], m, f, 1e-6);
        for (int i = 0; i < n; ++i)
          EXPECT_EQ(out[k * n + i], one[i]) << rotation_method_name(m) << " pair " << k << " i " << i;
      }
      // Float batch against float single rotations.
      std::vector<Mat3<float>> rsf;
      for (const auto& r : rs) rsf.push_back(r.cast<float>());
      std::vector<float> inf(in.begin(), in.end()), outf(in.size());
      ShRotation<float> rotf(order, helpers());
      ASSERT_TRUE(rotate_batch<float>(rotf, rsf, inf, outf, m, 1e-6));
      for (int k = 0; k < count; ++k) {
        const std::vector<double> f(in.begin() + k * n, in.begin() + (k + 1) * n);
        const std::vector<float> one = rotate<float>(order, rs[k], m, f, 1e-6);
        for (int i = 0; i < n; ++i) EXPECT_EQ(outf[k * n + i], one[i]) << "float pair " << k;
      }
    }
  });
}

// The lane path of rotate_batch (groups of 4 float / 2 double rotations of one method;
// orders <= 20, double zxzxz <= 10) against set() + apply() of each pair, bit for bit:
// counts that leave a tail, every order with a whole-order kernel, band kernels, and
// order 21 (no lane path); every method but the reference; the edge rotations (half
// turns, gimbal locks, tiny tilts) mixed with generic ones (under `automatic`, groups
// mixing Taylor and zxzxz run one at a time), and small tilts only (Taylor lanes).
// The lanes run the scalar form of the kernels and tables, so this also holds apply()'s
// float paths to them: its z-rotations with four pairs in lanes (from order 5) and the
// cos / sin tables that set() computes for the three angles in SSE2 lanes.
template <class T>
void check_batch_lanes_bitwise() {
  std::mt19937_64 rng(617);
  std::vector<Mat3<T>> mixed, small;
  for (const auto& [name, r] : edge_rotations()) mixed.push_back(r.template cast<T>());
  for (int k = 0; k < 13; ++k) mixed.push_back(random_rotation(rng).template cast<T>());
  std::shuffle(mixed.begin(), mixed.end(), rng);
  // Small tilts only: under `automatic` every group is one Taylor method.
  for (int k = 0; k < 11; ++k) {
    const double a = std::uniform_real_distribution<double>(-kPi, kPi)(rng);
    const double g = std::uniform_real_distribution<double>(-kPi, kPi)(rng);
    small.push_back(matrix_from_zyz<double>({a, 1e-4 * (1 + k % 3), g}).template cast<T>());
  }
  ASSERT_NE(mixed.size() % 4, 0u);  // a tail in float
  // Helpers beyond the other tests' order, for an order without a lane path.
  static const auto h22 = std::make_shared<const RotationHelpers>(compute_rotation_helpers(22));
  // vectors: 1, or 3 per rotation (a splat's colour channels, the lanes' setup shared).
  for (const int vectors : {1, 3})
    for (const std::vector<Mat3<T>>* rs : {&mixed, &small})
      for (int order : {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 15, 20, 21}) {
        const int n = sh_count(order), count = static_cast<int>(rs->size());
        std::vector<T> in(count * vectors * n);
        for (T& v : in) v = static_cast<T>(std::uniform_real_distribution<double>(-1, 1)(rng));
        for (RotationMethod m : {RotationMethod::zxzxz, RotationMethod::automatic, RotationMethod::taylor1,
                                 RotationMethod::taylor15, RotationMethod::taylor2}) {
          const double tol = rs == &small ? 0.1 : 1e-5;  // small: `automatic` takes Taylor
          ShRotation<T> batch(order, h22), single(order, h22);
          std::vector<T> out(in.size(), T(7)), one(n);
          ASSERT_TRUE(rotate_batch<T>(batch, *rs, in, out, m, tol, vectors));
          for (int k = 0; k < count; ++k) {
            ASSERT_TRUE(single.set((*rs)[k], m, tol));
            if (rs == &small && m == RotationMethod::automatic && order > detail::kClosedMaxOrder)  // else zxzxz
              ASSERT_NE(single.method(), RotationMethod::zxzxz) << "order " << order;
            for (int c = k * vectors; c < (k + 1) * vectors; ++c) {
              single.apply(std::span<const T>(in.data() + c * n, n), one);
              for (int i = 0; i < n; ++i)
                ASSERT_EQ(out[c * n + i], one[i]) << "order " << order << " " << rotation_method_name(m) << " pair "
                                                  << k << " vector " << c << " ("
                                                  << rotation_method_name(single.method()) << ") i " << i;
            }
          }
          // The rotation object holds the last rotation afterwards.
          EXPECT_EQ(batch.method(), single.method());
          std::vector<T> again(n);
          batch.apply(std::span<const T>(in.data() + (count * vectors - 1) * n, n), again);
          for (int i = 0; i < n; ++i) EXPECT_EQ(again[i], one[i]);
        }
      }
}

TEST(RotationApi, BatchLanesAreBitIdenticalToSingleRotationsFloat) {
  test::for_each_kernel_copy([] { check_batch_lanes_bitwise<float>(); });
}
TEST(RotationApi, BatchLanesAreBitIdenticalToSingleRotationsDouble) {
  test::for_each_kernel_copy([] { check_batch_lanes_bitwise<double>(); });
}

// apply() of one channel and of three interleaved call the generated kernel of the current rotation directly
// when it covers every band: one object switched between methods, tilts and orders of
// rotation must give what a fresh object gives for each, bit for bit.
template <class T>
void check_reused_rotation() {
  std::mt19937_64 rng(631);
  const RotationMethod methods[] = {RotationMethod::zxzxz,   RotationMethod::reference, RotationMethod::taylor1,
                                    RotationMethod::taylor2, RotationMethod::automatic, RotationMethod::taylor15,
                                    RotationMethod::zxzxz};
  for (int order : {2, 3, 4, 5, 7, 10, 11, 14}) {
    const int n = sh_count(order);
    ShRotation<T> reused(order, helpers());
    std::vector<T> in(3 * n);
    for (T& v : in) v = static_cast<T>(std::uniform_real_distribution<double>(-1, 1)(rng));
    for (int round = 0; round < 2; ++round)
      for (RotationMethod m : methods) {
        const Mat3<T> r = (round ? axis_angle({1, 2, 3}, 1e-4) : random_rotation(rng)).template cast<T>();
        ShRotation<T> fresh(order, helpers());
        ASSERT_TRUE(reused.set(r, m));
        ASSERT_TRUE(fresh.set(r, m));
        ASSERT_EQ(reused.method(), fresh.method());
        std::vector<T> a(3 * n), b(3 * n);
        reused.apply(std::span<const T>(in).first(n), std::span<T>(a).first(n));
        fresh.apply(std::span<const T>(in).first(n), std::span<T>(b).first(n));
        for (int i = 0; i < n; ++i) ASSERT_EQ(a[i], b[i]) << "order " << order << " " << rotation_method_name(m);
        ASSERT_TRUE(reused.apply(in, a, 3));
        ASSERT_TRUE(fresh.apply(in, b, 3));
        for (int i = 0; i < 3 * n; ++i)
          ASSERT_EQ(a[i], b[i]) << "rgb order " << order << " " << rotation_method_name(m);
      }
  }
}

// From order 5 to 10, set() and set_quaternion() under zxzxz take a short path of their
// own once the automatic choice's limits are cached for the tolerance (or zxzxz is asked
// for); a tolerance not seen before goes through the general path. Both must pick the
// same method and give the same rotation bit for bit, generic and near-identity (Taylor)
// tilts alike.
template <class T>
void check_short_set_path() {
  std::mt19937_64 rng(977);
  const double tolerance = default_rotation_tolerance<T>();
  for (int order = 5; order <= 11; ++order) {
    const int n = sh_count(order);
    std::vector<T> in(n);
    for (T& v : in) v = static_cast<T>(std::uniform_real_distribution<double>(-1, 1)(rng));
    ShRotation<T> cached(order, helpers()), general(order, helpers());
    for (int k = 0; k < 24; ++k) {
      // Half of the rotations by quaternion (set_quaternion), half by matrix.
      const bool by_quaternion = k % 8 >= 4;
      std::normal_distribution<double> normal;
      Eigen::Vector4d q(normal(rng), normal(rng), normal(rng), normal(rng));
      if (k % 4 == 3) q = Eigen::Vector4d(1, 5e-5 * q[1], 5e-5 * q[2], 5e-5 * q[3]);  // tilt ~1e-4
      q.normalize();
      const Eigen::Vector4<T> qt = q.cast<T>();
      const Mat3<T> r = matrix_from_quaternion<T>(qt[0], qt[1], qt[2], qt[3]);
      const RotationMethod method = k % 6 == 5 ? RotationMethod::zxzxz : RotationMethod::automatic;
      // Two tolerances in turn for `general`, each new to the object: every call derives
      // the limits again. The second changes the limits by a relative 1e-12: no tilt here is
      // that close to one.
      const double new_tolerance = k % 2 ? tolerance : tolerance * (1 + 1e-12);
      if (by_quaternion) {
        ASSERT_TRUE(cached.set_quaternion(qt[0], qt[1], qt[2], qt[3], method, tolerance));
        ASSERT_TRUE(general.set_quaternion(qt[0], qt[1], qt[2], qt[3], method, new_tolerance));
      } else {
        ASSERT_TRUE(cached.set(r, method, tolerance));
        ASSERT_TRUE(general.set(r, method, new_tolerance));
      }
      ASSERT_EQ(cached.method(), general.method()) << "order " << order << " rotation " << k;
      if (method == RotationMethod::automatic && k % 4 != 3)
        ASSERT_EQ(cached.method(), RotationMethod::zxzxz);  // a generic tilt: the short path's case
      std::vector<T> a(n), b(n);
      cached.apply(in, a);
      general.apply(in, b);
      for (int i = 0; i < n; ++i) ASSERT_EQ(a[i], b[i]) << "order " << order << " rotation " << k << " i " << i;
    }
  }
}

TEST(RotationApi, ShortSetPathMatchesGeneralPathFloat) { check_short_set_path<float>(); }
TEST(RotationApi, ShortSetPathMatchesGeneralPathDouble) { check_short_set_path<double>(); }

TEST(RotationApi, ReusedRotationMatchesFreshOneFloat) { check_reused_rotation<float>(); }
TEST(RotationApi, ReusedRotationMatchesFreshOneDouble) { check_reused_rotation<double>(); }

// apply() of one vector checks its spans as apply() of several channels does: a short
// one is std::invalid_argument, on every path (order 2 inline, a generated kernel, the
// general code).
TEST(RotationApi, ShortSpansAreRefused) {
  for (const int order : {2, 4, 12}) {
    const int n = sh_count(order);
    ShRotation<double> rotation(order, helpers());
    ASSERT_TRUE(rotation.set(matrix_from_zyz<double>({0.3, 0.7, -0.2}), RotationMethod::zxzxz));
    const std::vector<double> in(n, 1.0), short_in(n - 1, 1.0);
    std::vector<double> out(n), short_out(n - 1);
    EXPECT_THROW(rotation.apply(short_in, out), std::invalid_argument) << order;
    try {
      rotation.apply(in, short_out);
      FAIL() << "no exception for a short output at order " << order;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("ShRotation::apply: out holds " + std::to_string(n - 1) + " values, " +
                                           std::to_string(n) + " needed"),
                std::string::npos)
          << e.what();
    }
    rotation.apply(in, out);  // the right sizes still work
  }
  auto lobes = ZhfLobes::load(default_zhf_lobes_path(4));
  ASSERT_TRUE(lobes.ok()) << lobes.error().message;
  ZhfRotation<double> zhf(4, std::make_shared<const ZhfLobes>(std::move(lobes.value())));
  ASSERT_TRUE(zhf.set(matrix_from_zyz<double>({0.3, 0.7, -0.2})));
  const std::vector<double> in(16, 1.0);
  std::vector<double> short_out(15);
  EXPECT_THROW(zhf.apply(in, short_out), std::invalid_argument);
  EXPECT_THROW(zhf.apply(std::span<const double>(in).first(15), std::span<double>(short_out.data(), 15)),
               std::invalid_argument);
}

TEST(RotationApi, BatchOfNothingAndWrongSizes) {
  ShRotation<float> rotation(4, helpers());
  std::vector<Mat3<float>> rs(5, Mat3<float>::Identity());
  std::vector<float> in(5 * 16, 1.0f), out(5 * 16), short_out(4 * 16);
  EXPECT_TRUE(rotate_batch<float>(rotation, std::span<const Mat3<float>>(), {}, {}));
  try {
    rotate_batch<float>(rotation, rs, in, short_out);
    FAIL() << "no exception for a short output";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("need 80 coefficients"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rotate_batch<float>(rotation, rs, std::span<const float>(in).first(79), out), std::invalid_argument);
  // Three vectors per rotation need three times the coefficients; none per rotation is refused.
  try {
    rotate_batch<float>(rotation, rs, in, out, RotationMethod::automatic, 1e-6, 3);
    FAIL() << "no exception for three vectors per rotation in room for one";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("and 3 vectors each need 240 coefficients"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rotate_batch<float>(rotation, rs, in, out, RotationMethod::automatic, 1e-6, 0), std::invalid_argument);
  // Without helpers only the reference method works, in batches as in set().
  ShRotation<float> none(4, nullptr);
  EXPECT_FALSE(rotate_batch<float>(none, rs, in, out, RotationMethod::zxzxz));
  EXPECT_TRUE(rotate_batch<float>(none, rs, in, out, RotationMethod::reference));
  EXPECT_EQ(out, in);  // identity rotations
}

TEST(RotationApi, BatchAllocatesNothing) {
  std::mt19937_64 rng(619);
  for (int order : {3, 6, 10, 14}) {
    const int n = sh_count(order), count = 9;
    std::vector<Mat3<float>> rs;
    for (int k = 0; k < count; ++k) rs.push_back(random_rotation(rng).cast<float>());
    std::vector<float> in(count * n, 0.5f), out(count * n);
    ShRotation<float> rotation(order, helpers());
    ASSERT_TRUE(rotate_batch<float>(rotation, rs, in, out, RotationMethod::zxzxz));  // warm-up
    const long before = test::allocation_count();
    ASSERT_TRUE(rotate_batch<float>(rotation, rs, in, out, RotationMethod::zxzxz));
    ASSERT_TRUE(rotate_batch<float>(rotation, rs, in, out, RotationMethod::automatic));
    EXPECT_EQ(test::allocation_count(), before) << "order " << order;
  }
}

// apply(in, out, channels) allocates nothing, for any channel count, at orders within the
// whole-order kernels, with band kernels, with table-driven bands and at the largest
// order (reference), and not on the first call either (no per-thread buffer).
template <class T>
void check_interleaved_allocates_nothing() {
  std::mt19937_64 rng(641);
  for (int order : {2, 3, 6, 10, 14, 20, kMaxOrder}) {
    const RotationMethod m = order <= 20 ? RotationMethod::zxzxz : RotationMethod::reference;
    for (int channels : {3, 4, 5}) {
      ShRotation<T> rotation(order, helpers());
      ASSERT_TRUE(rotation.set(random_rotation(rng).cast<T>(), m));
      const std::vector<T> in(static_cast<std::size_t>(channels) * sh_count(order), T(0.5));
      std::vector<T> out(in.size());
      const long before = test::allocation_count();
      ASSERT_TRUE(rotation.apply(in, out, channels));
      ASSERT_TRUE(rotation.apply(in, out, channels));
      EXPECT_EQ(test::allocation_count(), before) << "order " << order << " channels " << channels;
    }
  }
}
TEST(RotationApi, InterleavedApplyAllocatesNothing) {
  check_interleaved_allocates_nothing<float>();
  check_interleaved_allocates_nothing<double>();
}

// OrthogonalMap::apply(in, out, channels): a reflection (the inversion's signs after the
// rotation, on every channel) and a rotation, against apply() of each channel, bit for
// bit; wrong sizes refused with nothing written.
TEST(RotationApi, OrthogonalMapInterleavedEqualsPerChannel) {
  std::mt19937_64 rng(643);
  for (int order : {1, 3, 4, 7}) {
    for (bool reflect : {false, true}) {
      const Eigen::Matrix3d q = reflect ? Eigen::Matrix3d(-random_rotation(rng)) : random_rotation(rng);
      Result<OrthogonalMap> map = OrthogonalMap::make(q, order);
      ASSERT_TRUE(map.ok());
      ASSERT_EQ(map.value().reflects(), reflect);
      for (int channels : {1, 3, 4}) {
        const int n = sh_count(order);
        std::vector<double> in(static_cast<std::size_t>(channels) * n), out(in.size(), -7.0), one(n), mapped(n);
        for (double& v : in) v = std::uniform_real_distribution<double>(-1, 1)(rng);
        ASSERT_TRUE(map.value().apply(in, out, channels));
        for (int c = 0; c < channels; ++c) {
          for (int i = 0; i < n; ++i) one[i] = in[i * channels + c];
          map.value().apply(one, mapped);
          for (int i = 0; i < n; ++i)
            ASSERT_EQ(out[i * channels + c], mapped[i]) << "order " << order << " reflect " << reflect << " c " << c;
        }
        std::vector<double> untouched(in.size() + 1, -7.0), wrong(in.size() + 1, 0.5);
        EXPECT_FALSE(map.value().apply(wrong, untouched, channels));
        EXPECT_FALSE(map.value().apply(std::span<const double>(in), std::span<double>(untouched).first(in.size()), 0));
        for (double v : untouched) ASSERT_EQ(v, -7.0);
      }
    }
  }
}

TEST(RotationApi, MissingOrTooSmallHelpersOnlyAllowReference) {
  const Mat3<double> r = axis_angle({1, 1, 0}, 0.4);
  ShRotation<double> none(5, nullptr);
  EXPECT_TRUE(none.set(r, RotationMethod::reference));
  for (RotationMethod m : {RotationMethod::automatic, RotationMethod::zxzxz, RotationMethod::taylor1})
    EXPECT_FALSE(none.set(r, m)) << rotation_method_name(m);
  auto small = std::make_shared<const RotationHelpers>(compute_rotation_helpers(4));
  ShRotation<double> too_big(5, small);
  EXPECT_FALSE(too_big.set(r, RotationMethod::zxzxz));
  EXPECT_TRUE(too_big.set(r, RotationMethod::reference));
  // A table for more bands than needed is fine: its first N^2 rows are used.
  ShRotation<double> smaller(3, small);
  EXPECT_TRUE(smaller.set(r, RotationMethod::zxzxz));
  // Orders up to 4 take the inline set() / apply() path: a refused set() must still keep
  // the previous rotation.
  std::mt19937_64 rng(603);
  for (int order : {2, 3, 4}) {
    ShRotation<double> bare(order, nullptr);
    const std::vector<double> f = random_coeffs(order, rng);
    ASSERT_TRUE(bare.set(r, RotationMethod::reference));
    std::vector<double> before(f.size()), after(f.size());
    bare.apply(f, before);
    for (RotationMethod m : {RotationMethod::automatic, RotationMethod::zxzxz}) {
      EXPECT_FALSE(bare.set(axis_angle({0, 0, 1}, 1.0), m)) << "N " << order << " " << rotation_method_name(m);
      EXPECT_EQ(bare.method(), RotationMethod::reference) << "N " << order;
      bare.apply(f, after);
      for (std::size_t i = 0; i < f.size(); ++i)
        EXPECT_EQ(after[i], before[i]) << "N " << order << " " << rotation_method_name(m) << " i " << i;
    }
  }
}

TEST(RotationApi, MethodNamesRoundTrip) {
  for (RotationMethod m : {RotationMethod::automatic, RotationMethod::reference, RotationMethod::zxzxz,
                           RotationMethod::taylor1, RotationMethod::taylor15, RotationMethod::taylor2})
    EXPECT_EQ(rotation_method_from_name(rotation_method_name(m)), m);
  EXPECT_EQ(rotation_method_name(RotationMethod::taylor15), "taylor1.5");
  EXPECT_FALSE(rotation_method_from_name("taylor3").has_value());
  EXPECT_FALSE(rotation_method_from_name("").has_value());
}

// ---------------------------------------------------------------------------
// Helper table round trip and validation.

// A fresh scratch folder, removed again when the object goes out of scope.
struct ScratchDir {
  std::filesystem::path path;
  ScratchDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "shtool-test-rotation-XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

TEST(RotationHelpersTable, WriteReadRoundTripIsExact) {
  const RotationHelpers h = compute_rotation_helpers(9);
  const nlohmann::json generator = generator_record("test_rotation", {{"order", 9}});
  const Table t = to_table(h, generator);
  // Helpers are the same when their tables are: every array's bytes.
  const auto expect_same_helpers = [&](const RotationHelpers& other) {
    test::expect_same_table(t, to_table(other, generator));
  };
  const ScratchDir scratch;
  for (TableEncoding enc : {TableEncoding::binary, TableEncoding::json}) {
    const std::filesystem::path path = scratch.path / (enc == TableEncoding::binary ? "helpers.shtb" : "helpers.json");
    const Result<Ok> written = shtool::test::try_write(t, path, enc);
    ASSERT_TRUE(written) << written.error().message;
    const Result<Table> read = read_table(path);
    ASSERT_TRUE(read) << read.error().message;
    const Result<RotationHelpers> back = RotationHelpers::from_table(read.value());
    ASSERT_TRUE(back) << back.error().message;
    expect_same_helpers(back.value());
    const Result<RotationHelpers> loaded = RotationHelpers::load(path);
    ASSERT_TRUE(loaded) << loaded.error().message;
    expect_same_helpers(loaded.value());
  }
  // The table is a pure function of the order (byte-identical output).
  expect_same_helpers(compute_rotation_helpers(9));
}

// The quadrature sums run on several threads, a group of bands each: every band's sum
// keeps its node order, so the values are the same bytes whatever the thread count
// (and so are the shipped table's: gen-tensors runs on every core).
TEST(RotationHelpersTable, SameBytesWhateverTheThreadCount) {
  const nlohmann::json generator = generator_record("test_rotation", {{"order", 13}});
  const Table one = to_table(compute_rotation_helpers(13, 1), generator);
  for (int threads : {2, 3, 5, 0}) {
    SCOPED_TRACE(threads);
    test::expect_same_table(one, to_table(compute_rotation_helpers(13, threads), generator));
  }
}

// Replaces array `name` of a table.
template <class T>
void replace_array(Table& t, const std::string& name, const std::vector<T>& values) {
  for (TableArray& a : t.arrays)
    if (a.name == name) a = TableArray::from<T>(name, {static_cast<std::int64_t>(values.size())}, values);
}

// A corruption: a copy of one of the helpers' arrays, changed by `edit`, stored as array
// `name`.
template <class T, class Edit>
std::function<void(Table&)> edited(const std::string& name, const std::vector<T>& values, Edit edit) {
  return [name, values, edit](Table& t) {
    std::vector<T> v = values;
    edit(v);
    replace_array(t, name, v);
  };
}

TEST(RotationHelpersTable, FromTableRejectsCorruption) {
  const RotationHelpers h = compute_rotation_helpers(5);
  const Table good = to_table(h, generator_record("test_rotation", {{"order", 5}}));
  ASSERT_TRUE(RotationHelpers::from_table(good));
  const int nnz = static_cast<int>(h.x90_col.size());
  struct Case {
    std::string name;
    std::function<void(Table&)> corrupt;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"column in another band", edited("x90_col", h.x90_col, [&](auto& c) { c[h.x90_row[5]] = 0; }),
       "outside its band"},
      {"column beyond the matrix", edited("x90_col", h.x90_col, [&](auto& c) { c.back() = 1 << 30; }),
       "outside its band"},
      {"negative column", edited("x90_col", h.x90_col, [&](auto& c) { c[3] = -1; }), "outside its band"},
      {"row starts one short", edited("x90_row", h.x90_row, [&](auto& r) { r.pop_back(); }), "sizes"},
      {"dy_sub too long", edited("dy_sub", h.dy_sub, [&](auto& d) { d.push_back(0); }), "sizes"},
      {"ddy_off2 too short", edited("ddy_off2", h.ddy_off2, [&](auto& d) { d.pop_back(); }), "sizes"},
      {"last row start is not nnz", edited("x90_row", h.x90_row, [&](auto& r) { r.back() = nnz - 1; }), "inconsistent"},
      {"values shorter than columns", edited("x90_val", h.x90_val, [&](auto& v) { v.pop_back(); }), "inconsistent"},
      {"row starts decrease", edited("x90_row", h.x90_row, [&](auto& r) { std::swap(r[3], r[4]); }), "decrease"},
      // A row start far beyond the data, with the last start still correct: must be
      // caught before any column of that row is read. (With the check done row by row
      // inside the column loop, the row before it reads past the end of x90_col: this
      // case then passes or fails by chance and valgrind reports the invalid read.)
      {"row start beyond the data", edited("x90_row", h.x90_row, [&](auto& r) { r[r.size() - 2] = 1 << 28; }), "X90"},
      {"wrong dtype",
       [&](Table& t) {
         std::vector<float> v(h.x90_val.begin(), h.x90_val.end());
         replace_array(t, "x90_val", v);
       },
       "dtype"},
      {"missing array",
       [&](Table& t) { std::erase_if(t.arrays, [](const TableArray& a) { return a.name == "ddy_diag"; }); }, "missing"},
      {"wrong kind", [&](Table& t) { t.kind = "tripling"; }, "wrong kind"},
      // Values that pass every index check but break the class structure the packed
      // rotation loops rely on: ShRotation's constructor used to throw a logic_error on
      // them (found by the fuzz target fuzz_table_kinds).
      {"a row of zeros",
       edited("x90_val", h.x90_val,
              [&](auto& v) {
                for (int k = h.x90_row[1]; k < h.x90_row[2]; ++k) v[k] = 0;
              }),
       "sparsity structure"},
      {"a non-zero outside its class",
       edited("x90_col", h.x90_col,
              [&](auto& c) {
                // Row 6 (band 2, m = 0) has two non-zeros of one parity: one moves by a column.
                ASSERT_EQ(h.x90_row[7] - h.x90_row[6], 2);
                int& first = c[h.x90_row[6]];
                first = first < 8 ? first + 1 : first - 1;
              }),
       "sparsity structure"},
  };
  for (const Case& c : cases) {
    Table t = good;
    c.corrupt(t);
    const Result<RotationHelpers> got = RotationHelpers::from_table(t);
    ASSERT_FALSE(got) << c.name << " was accepted";
    EXPECT_NE(got.error().message.find(c.message), std::string::npos)
        << c.name << ": message should mention '" << c.message << "': " << got.error().message;
    EXPECT_NE(got.error().message.find("rotation-helpers"), std::string::npos) << got.error().message;
  }
}

}  // namespace
}  // namespace shtool
