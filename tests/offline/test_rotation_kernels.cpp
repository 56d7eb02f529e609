// The generated fixed-order rotation kernels (src/runtime/kernels/rotation_kernels.h,
// rotation_kernels_generated.inc) and the interleaved colour apply:
//  - the committed generated source is byte-identical to what its generator writes
//    now, through the library call and through `shtool gen-tensors`;
//  - apply() of interleaved channels gives the bits of apply() of each channel, for every
//    method and type and 1..6 channels, writes nothing outside its spans, and refuses
//    wrong sizes;
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

constexpr int kHelperOrder = 24;

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

// apply(in, out, channels) on interleaved channels against apply() of each channel alone:
// the same bits (the lanes of the three-lane kernels are independent, and a group of two
// lanes or one must not disturb them).
template <class T>
void expect_interleaved_equals_per_channel(int order, const Mat3<double>& r, RotationMethod m, int channels,
                                           std::mt19937_64& rng) {
  ShRotation<T> rot(order, helpers());
  ASSERT_TRUE(rot.set(r.cast<T>(), m, 1e-3));
  const int n = sh_count(order);
  std::vector<T> in(static_cast<std::size_t>(n) * channels), out(in.size(), T(-7)), one(n), rotated(n);
  for (T& v : in) v = static_cast<T>(std::uniform_real_distribution<double>(-1, 1)(rng));
  ASSERT_TRUE(rot.apply(in, out, channels));
  for (int c = 0; c < channels; ++c) {
    for (int i = 0; i < n; ++i) one[i] = in[i * channels + c];
    rot.apply(one, rotated);
    for (int i = 0; i < n; ++i)
      ASSERT_EQ(out[i * channels + c], rotated[i])
          << rotation_method_name(m) << " order " << order << " channels " << channels << " channel " << c << " i "
          << i;
  }
}

TEST(RotationKernels, InterleavedChannelsEqualPerChannelApplies) {
  test::for_each_kernel_copy([] {
    std::mt19937_64 rng(11);
    for (int order = 1; order <= 13; ++order) {
      const Mat3<double> big = random_rotation(rng);
      const Mat3<double> small = matrix_from_zyz<double>({0.7, 0.01, -2.1});
      for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz, RotationMethod::taylor1,
                               RotationMethod::taylor15, RotationMethod::taylor2, RotationMethod::automatic}) {
        const Mat3<double>& r = (m == RotationMethod::reference || m == RotationMethod::zxzxz) ? big : small;
        for (int channels = 1; channels <= 6; ++channels) {
          expect_interleaved_equals_per_channel<float>(order, r, m, channels, rng);
          expect_interleaved_equals_per_channel<double>(order, r, m, channels, rng);
        }
      }
    }
    // Above the whole-order kernels: the kernels of single bands (up to band 19), the
    // table-driven bands (20 on; in double zxzxz the paired rows from band 10), and the
    // reference method (no helpers needed) at 24 and at the largest order.
    for (int channels : {2, 3, 4, 5}) {
      for (int order : {16, 22}) {
        expect_interleaved_equals_per_channel<float>(order, random_rotation(rng), RotationMethod::zxzxz, channels, rng);
        expect_interleaved_equals_per_channel<double>(order, random_rotation(rng), RotationMethod::zxzxz, channels, rng);
        const Mat3<double> small = matrix_from_zyz<double>({0.7, 0.01, -2.1});
        expect_interleaved_equals_per_channel<float>(order, small, RotationMethod::taylor2, channels, rng);
        expect_interleaved_equals_per_channel<double>(order, small, RotationMethod::taylor15, channels, rng);
      }
      expect_interleaved_equals_per_channel<double>(20, random_rotation(rng), RotationMethod::automatic, channels, rng);
      expect_interleaved_equals_per_channel<double>(24, random_rotation(rng), RotationMethod::reference, channels, rng);
      expect_interleaved_equals_per_channel<float>(24, random_rotation(rng), RotationMethod::reference, channels, rng);
    }
    expect_interleaved_equals_per_channel<float>(kMaxOrder, random_rotation(rng), RotationMethod::reference, 3, rng);
    expect_interleaved_equals_per_channel<double>(kMaxOrder, random_rotation(rng), RotationMethod::reference, 4, rng);
  });
}

// The three-lane kernels load and store a coefficient's three values with 4-wide vector
// moves: nothing before or after the spans may be written, at every order with a
// generated kernel (whole-order or one band) and beyond, for every method. The spans
// sit inside larger arrays, between guard values.
template <class T>
void check_interleaved_stays_in_bounds() {
  std::mt19937_64 rng(23);
  constexpr std::size_t kGuard = 8;
  const T guard = T(-12345);
  for (int order : {1, 2, 3, 4, 5, 9, 10, 11, 12, 19, 20, 21, 22}) {
    for (RotationMethod m : {RotationMethod::reference, RotationMethod::zxzxz, RotationMethod::taylor1,
                             RotationMethod::taylor2}) {
      const bool exact = m == RotationMethod::reference || m == RotationMethod::zxzxz;
      ShRotation<T> rot(order, helpers());
      ASSERT_TRUE(rot.set((exact ? random_rotation(rng) : matrix_from_zyz<double>({0.7, 0.01, -2.1})).cast<T>(), m));
      const std::size_t n = 3 * static_cast<std::size_t>(sh_count(order));
      std::vector<T> in(n + 2 * kGuard, guard), out(n + 2 * kGuard, guard);
      for (std::size_t i = kGuard; i < kGuard + n; ++i)
        in[i] = static_cast<T>(std::uniform_real_distribution<double>(-1, 1)(rng));
      ASSERT_TRUE(rot.apply(std::span<const T>(in).subspan(kGuard, n), std::span<T>(out).subspan(kGuard, n), 3));
      for (std::size_t i = 0; i < kGuard; ++i) {
        ASSERT_EQ(out[i], guard) << "order " << order << " " << rotation_method_name(m) << " before";
        ASSERT_EQ(out[kGuard + n + i], guard) << "order " << order << " " << rotation_method_name(m) << " after";
      }
      for (std::size_t i = kGuard; i < kGuard + n; ++i)
        ASSERT_NE(out[i], guard) << "order " << order << " " << rotation_method_name(m) << " i " << i - kGuard;
    }
  }
}

TEST(RotationKernels, InterleavedApplyWritesNothingOutsideTheSpans) {
  test::for_each_kernel_copy([] {
    check_interleaved_stays_in_bounds<float>();
    check_interleaved_stays_in_bounds<double>();
  });
}

// Wrong sizes and channel counts are refused and nothing is written, at an order with the
// inline kernels (3), at order 2 (inline band 1) and above them (12).
TEST(RotationKernels, InterleavedApplyRefusesWrongSizes) {
  std::mt19937_64 rng(5);
  for (int order : {1, 2, 3, 12}) {
    ShRotation<float> rot(order, helpers());
    ASSERT_TRUE(rot.set(random_rotation(rng).cast<float>(), RotationMethod::zxzxz));
    const std::size_t n = static_cast<std::size_t>(sh_count(order));
    const std::vector<float> in(4 * n + 1, 0.5f);
    std::vector<float> out(4 * n + 1, -7.0f);
    auto untouched = [&out] {
      for (float v : out)
        if (v != -7.0f) return false;
      return true;
    };
    const std::span<const float> i3(in.data(), 3 * n);
    const std::span<float> o3(out.data(), 3 * n);
    EXPECT_FALSE(rot.apply(i3, o3, 0)) << "order " << order;
    EXPECT_FALSE(rot.apply(i3, o3, -3)) << "order " << order;
    EXPECT_FALSE(rot.apply(i3, o3, 4)) << "order " << order;  // 3 N^2 values for 4 channels
    EXPECT_FALSE(rot.apply(i3, std::span<float>(out.data(), 3 * n + 1), 3)) << "order " << order;
    EXPECT_FALSE(rot.apply(std::span<const float>(in.data(), 3 * n - 1), o3, 3)) << "order " << order;
    EXPECT_FALSE(rot.apply(std::span<const float>(in.data(), 3 * n + 1), o3, 3)) << "order " << order;
    EXPECT_FALSE(rot.apply(std::span<const float>(in.data(), 2 * n), std::span<float>(out.data(), 2 * n), 1))
        << "order " << order;
    EXPECT_TRUE(untouched()) << "order " << order;
    EXPECT_TRUE(rot.apply(i3, o3, 3)) << "order " << order;
    EXPECT_FALSE(untouched()) << "order " << order;
  }
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
