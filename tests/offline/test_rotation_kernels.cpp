// The generated fixed-order rotation kernels (src/runtime/kernels/rotation_kernels.h,
// rotation_kernels_generated.inc) and the three-vector apply:
//  - the committed generated source is byte-identical to what its generator writes
//    now, through the library call and through `shtool gen-tensors`;
//  - apply_rgb gives the bits of three apply() calls, for every method and type;
//  - the Taylor kernels apply Z(a) T(b) Z(g) with T the truncated series, against a dense
//    product of reference z-rotations and D1, D2 (orders across the generated /
//    run-time boundary);
//  - float accuracy near the identity for every kernel order (DirectXMath's weak spot).
// Exactness of zxzxz against quadrature and the reference is in test_rotation.cpp.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "generated_source.h"
#include "kernel_copies.h"
#include "kernels/rotation_kernels.h"
#include "run_command.h"
#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "tensors/rotation_helpers_gen.h"
#include "tensors/rotation_kernels_gen.h"
#include "test_util.h"

namespace shtool {
namespace {

using test::norm;
using test::random_coeffs;
using test::reference_matrix;

constexpr int kHelperOrder = 20;

std::shared_ptr<const RotationHelpers> helpers() {
  static const std::shared_ptr<const RotationHelpers> h =
      std::make_shared<const RotationHelpers>(compute_rotation_helpers(kHelperOrder));
  return h;
}

TEST(RotationKernels, CommittedSourceMatchesGenerator) {
  test::expect_committed_source("rotation-kernels", kRotationKernelsFile, rotation_kernels_source());
}

Mat3<double> random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return matrix_from_quaternion<double>(q[0], q[1], q[2], q[3]);
}

template <class T>
void expect_rgb_equals_three_applies(int order, const Mat3<double>& r, RotationMethod m, std::mt19937_64& rng) {
  ShRotation<T> rot(order, helpers());
  ASSERT_TRUE(rot.set(r.cast<T>(), m, 1e-3));
  const int n = sh_count(order);
  std::vector<std::vector<T>> in(3), one(3, std::vector<T>(n)), rgb(3, std::vector<T>(n, T(-7)));
  for (auto& v : in) {
    const std::vector<double> f = random_coeffs(order, rng);
    v.assign(f.begin(), f.end());
  }
  for (int k = 0; k < 3; ++k) rot.apply(in[k], one[k]);
  rot.apply_rgb({std::span<const T>(in[0]), std::span<const T>(in[1]), std::span<const T>(in[2])},
                {std::span<T>(rgb[0]), std::span<T>(rgb[1]), std::span<T>(rgb[2])});
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < n; ++i)
      ASSERT_EQ(rgb[k][i], one[k][i]) << rotation_method_name(m) << " order " << order << " vector " << k << " i " << i;
}

TEST(RotationKernels, ApplyRgbEqualsThreeApplies) {
  test::for_each_kernel_copy([] {
    std::mt19937_64 rng(11);
    for (int order = 1; order <= 13; ++order) {
      const Mat3<double> big = random_rotation(rng);
      const Mat3<double> small = matrix_from_zyz<double>({0.7, 0.01, -2.1});
      for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz, RotationMethod::taylor1,
                               RotationMethod::taylor15, RotationMethod::taylor2, RotationMethod::automatic}) {
        const Mat3<double>& r = (m == RotationMethod::reference || m == RotationMethod::zxzxz) ? big : small;
        expect_rgb_equals_three_applies<float>(order, r, m, rng);
        expect_rgb_equals_three_applies<double>(order, r, m, rng);
      }
    }
    // A generic rotation with auto takes zxzxz through apply_rgb too.
    expect_rgb_equals_three_applies<double>(20, random_rotation(rng), RotationMethod::automatic, rng);
  });
}

Mat3<double> rz(double a) {
  Mat3<double> r;
  r << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return r;
}

// I + b D1 (+ b^2/2 diag D2 | + b^2/2 D2), dense, from the stored helper entries.
Eigen::MatrixXd taylor_y(RotationMethod m, int order, double b) {
  const RotationHelpers& h = *helpers();
  const int n = sh_count(order);
  Eigen::MatrixXd d1 = Eigen::MatrixXd::Zero(n, n), d2 = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    if (i != sh_band(i) * sh_band(i)) {
      d1(i, i - 1) = h.dy_sub[i];
      d1(i - 1, i) = -h.dy_sub[i];
    }
    d2(i, i) = h.ddy_diag[i];
    if (i >= 2 && sh_band(i - 2) == sh_band(i)) d2(i, i - 2) = d2(i - 2, i) = h.ddy_off2[i];
  }
  Eigen::MatrixXd t = Eigen::MatrixXd::Identity(n, n) + b * d1;
  if (m == RotationMethod::taylor15) t += 0.5 * b * b * Eigen::MatrixXd(d2.diagonal().asDiagonal());
  if (m == RotationMethod::taylor2) t += 0.5 * b * b * d2;
  return t;
}

// ||f rotated by ShRotation<float>(r, m) - want|| / ||f||, with the helpers; `used` gets the
// method the rotation resolved m to.
template <class V>
double float_rotation_error(int order, const Mat3<double>& r, RotationMethod m, const std::vector<double>& f,
                            const V& want, RotationMethod* used = nullptr) {
  ShRotation<float> rot(order, helpers());
  if (!rot.set(r.cast<float>(), m)) {
    ADD_FAILURE() << "set refused " << rotation_method_name(m) << " order " << order;
    return INFINITY;
  }
  if (used) *used = rot.method();
  std::vector<float> ff(f.begin(), f.end()), got(f.size());
  rot.apply(ff, got);
  double err = 0;
  for (std::size_t i = 0; i < f.size(); ++i) err += std::pow(got[i] - want[i], 2);
  return std::sqrt(err) / norm(f);
}

TEST(RotationKernels, TaylorAppliesZTZ) {
  // Rotation Rz(a) Ry(b) Rz(g): the Taylor methods must give M(Rz(a)) T(b) M(Rz(g)) f,
  // with the z-rotations from the reference method. Tolerances: double 1e-13 (entries of
  // D2 reach ~l^2 = 400 times b^2 / 2, products of ~20 terms); float 2e-6 relative.
  std::mt19937_64 rng(12);
  const double a = 0.9, b = 0.03, g = -2.4;
  const Mat3<double> r = matrix_from_zyz<double>({a, b, g});
  for (int order : {1, 2, 3, 4, 6, 9, 10, 11, 12, 14}) {
    const std::vector<double> f = random_coeffs(order, rng);
    const Eigen::Map<const Eigen::VectorXd> fv(f.data(), f.size());
    for (RotationMethod m : {RotationMethod::taylor1, RotationMethod::taylor15, RotationMethod::taylor2}) {
      const Eigen::VectorXd want =
          reference_matrix(order, rz(a)) * taylor_y(m, order, b) * reference_matrix(order, rz(g)) * fv;
      ShRotation<double> rot(order, helpers());
      ASSERT_TRUE(rot.set(r, m));
      std::vector<double> got(f.size());
      rot.apply(f, got);
      double err = 0;
      for (std::size_t i = 0; i < f.size(); ++i) err = std::max(err, std::abs(got[i] - want[i]));
      EXPECT_LE(err, 1e-13) << rotation_method_name(m) << " order " << order;
      EXPECT_LE(float_rotation_error(order, r, m, f, want), 2e-6)
          << "float " << rotation_method_name(m) << " order " << order;
    }
  }
}

TEST(RotationKernels, FloatNearIdentityEveryKernelOrder) {
  // DirectXMath's float XMSHRotate errs by 1e-4..1e-3 for rotations of 1e-3..1e-4 rad;
  // the float kernels stay at rounding level (measured <= 1.1e-6 relative to ||f||).
  test::for_each_kernel_copy([] {
    constexpr double kTolFloat = 2e-6;
    std::mt19937_64 rng(13);
    std::normal_distribution<double> nd;
    for (int order = 2; order <= detail::kKernelMaxOrder + 1; ++order) {
      for (double angle : {1e-2, 1e-3, 1e-4, 1e-5, 1e-7}) {
        Eigen::Vector3d axis(nd(rng), nd(rng), nd(rng));
        axis.normalize();
        const double s = std::sin(angle / 2);
        const Mat3<double> r =
            matrix_from_quaternion<double>(std::cos(angle / 2), s * axis.x(), s * axis.y(), s * axis.z());
        const std::vector<double> f = random_coeffs(order, rng);
        ShRotation<double> ref(order, nullptr);
        ASSERT_TRUE(ref.set(r, RotationMethod::reference));
        std::vector<double> want(f.size());
        ref.apply(f, want);
        for (RotationMethod m : {RotationMethod::zxzxz, RotationMethod::automatic}) {
          RotationMethod used = m;
          EXPECT_LE(float_rotation_error(order, r, m, f, want, &used), kTolFloat)
              << rotation_method_name(m) << " (" << rotation_method_name(used) << ") order " << order << " angle "
              << angle;
        }
      }
    }
  });
}

// The FMA copy is what ShRotation takes on a CPU with AVX2 and FMA; it differs from the
// baseline copy by rounding only (one rounding fewer per fused a * b + c).
template <class T>
void check_fma_copy_agrees_with_baseline(double tol) {
  std::mt19937_64 rng(14);
  bool some_bits_differ = false;
  for (int order = 2; order <= detail::kBandKernelMaxBand + 1; ++order) {
    const Mat3<double> big = random_rotation(rng);
    const Mat3<double> small = matrix_from_zyz<double>({0.7, 0.01, -2.1});
    for (RotationMethod m : {RotationMethod::zxzxz, RotationMethod::taylor1, RotationMethod::taylor2}) {
      const Mat3<T> r = (m == RotationMethod::zxzxz ? big : small).template cast<T>();
      const std::vector<double> f = random_coeffs(order, rng);
      const std::vector<T> ft(f.begin(), f.end());
      std::vector<T> got[2];
      for (bool fused : {false, true}) {
        detail::use_fma_kernels(fused);
        ShRotation<T> rot(order, helpers());
        ASSERT_TRUE(rot.set(r, m));
        got[fused].resize(f.size());
        rot.apply(ft, got[fused]);
      }
      detail::use_fma_kernels(true);
      double diff = 0;
      for (std::size_t i = 0; i < f.size(); ++i) {
        diff = std::max(diff, std::abs(double(got[0][i]) - double(got[1][i])));
        some_bits_differ |= got[0][i] != got[1][i];
      }
      EXPECT_LE(diff, tol * norm(f)) << rotation_method_name(m) << " order " << order;
    }
  }
  // Proof that the FMA copy ran: fused and unfused results cannot agree in every bit.
  EXPECT_EQ(some_bits_differ, detail::fma_kernels_supported());
}

TEST(RotationKernels, FmaCopyAgreesWithBaselineToRounding) {
  check_fma_copy_agrees_with_baseline<float>(2e-6);
  check_fma_copy_agrees_with_baseline<double>(1e-14);
}

}  // namespace
}  // namespace shtool
