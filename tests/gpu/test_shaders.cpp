// The generated GLSL and HLSL run on a real Vulkan device (lavapipe in CI): each
// operation is wrapped in a compute shader, fed thousands of random inputs from a
// storage buffer, and its outputs are compared with the C++ runtime in double. Both
// languages go through glslang to SPIR-V, spirv-val and the same harness; the GLSL is
// also compiled as OpenGL ES 3.00 (WebGL2's language).
//
// Tolerances are float rounding times the operation's size: sh-eval at 4e-6 of the band's
// scale sqrt((2l+1)/4pi) (the recurrence adds a rounding per band: 1.9e-6 measured at
// N = 10), zh-shade at 2e-6 of the sum of absolute terms,
// rotations at 1e-5 of |f| (the bound docs/shaders.md states for N <= 8; measured errors are printed),
// products and irradiance at 1e-6 of the sum of absolute terms, the probe encodings (l1-,
// zh3-irradiance) at 2e-6 of the sum of their terms' sizes (pow in L1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <initializer_list>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "run_command.h"
#include "scratch_files.h"
#include "shaders/shader_source.h"
#include "shtool/irradiance.h"
#include "shtool/probe_encoding.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/tripling_product.h"
#include "shtool/zh_shading.h"
#include "shtool/zhf_rotation.h"
#include "shader_wrappers.h"
#include "vulkan_compute.h"

namespace {

using shtool::ShaderLanguage;
using shtool::ShaderOperation;
using shtool::ShaderPrecision;
namespace gpu = shtool::gpu;
using gpu::band_textures;
using gpu::load_array;
using gpu::request_for;
using gpu::texture_arguments;
using gpu::vec3_of;
using gpu::wrapper;
using gpu::Wrapper;

constexpr int kInputs = 4096;

Eigen::Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Vector3d v;
  do v = Eigen::Vector3d(g(rng), g(rng), g(rng));
  while (v.norm() < 1e-3);
  return v.normalized();
}

// The larger of two errors, NaN if either is (an output never written is NaN and must
// fail the comparison, which std::max would hide).
double worse(double a, double b) { return std::isnan(a) || std::isnan(b) ? NAN : std::max(a, b); }

double band_scale(int l) { return std::sqrt((2.0 * l + 1.0) / (4.0 * std::numbers::pi)); }

struct Outcome {
  double worst = 0;  // largest error / tolerance unit over every output
};

// Inputs (float, as the shader sees them) and the check of its outputs against the
// runtime in double, for one operation.
struct Problem {
  std::vector<float> in;
  std::function<double(const std::vector<float>& out)> worst_error;  // in units of the tolerance
};

// amplification[l]: how much more error band l may have than a float rotation (ZHF:
// rounding amplified by cond(Y_l)); empty: none.
Problem make_problem(ShaderOperation op, int n, int lobes, const Wrapper& w, std::mt19937_64& rng,
                     std::vector<double> amplification = {}) {
  if (amplification.empty()) amplification.assign(n, 1.0);
  const int nn = n * n;
  std::uniform_real_distribution<double> u(-1, 1);
  Problem p;
  p.in.resize(static_cast<std::size_t>(kInputs) * w.in_stride);
  auto at = [&](int inv, int k) -> float& { return p.in[static_cast<std::size_t>(inv) * w.in_stride + k]; };
  auto dvec = [&](int inv, int k) { return Eigen::Vector3d(at(inv, k), at(inv, k + 1), at(inv, k + 2)); };
  auto put_dir = [&](int inv, int k, int case_index) {
    // The poles and the axes first, then random directions.
    static const double special[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    Eigen::Vector3d d = case_index < 6 ? Eigen::Vector3d(special[case_index][0], special[case_index][1],
                                                         special[case_index][2])
                                       : random_unit(rng);
    for (int c = 0; c < 3; ++c) at(inv, k + c) = static_cast<float>(d[c]);
  };
  for (int inv = 0; inv < kInputs; ++inv)
    for (int k = 0; k < w.in_stride; ++k) at(inv, k) = static_cast<float>(u(rng));
  switch (op) {
    case ShaderOperation::sh_eval:
    case ShaderOperation::sh_irradiance:
      for (int inv = 0; inv < kInputs; ++inv) put_dir(inv, 0, inv);
      break;
    case ShaderOperation::zxzxz_rotate:
    case ShaderOperation::zhf_rotate:
    case ShaderOperation::zhf_tailored_rotate:
      for (int inv = 0; inv < kInputs; ++inv) {
        Eigen::Matrix3d r;
        if (inv == 0) r.setIdentity();
        else if (inv == 1) r = Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).toRotationMatrix();
        else if (inv == 2) r = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        else if (inv == 3) r = Eigen::AngleAxisd(1e-4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
        else if (inv == 4) r = Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
        else {
          std::normal_distribution<double> g;
          r = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
        }
        for (int k = 0; k < 9; ++k) at(inv, k) = static_cast<float>(r(k / 3, k % 3));
      }
      break;
    case ShaderOperation::zh_shade:
      for (int inv = 0; inv < kInputs; ++inv)
        for (int i = 0; i < lobes; ++i) put_dir(inv, 3 * i, inv < 6 ? inv : 6 + i);
      break;
    case ShaderOperation::triple_product: break;
    case ShaderOperation::l1_irradiance:
    case ShaderOperation::zh3_irradiance:
      // A light with positive band 0 (c00 in [0.5, 1.5]); |d| up to sqrt3 covers r beyond 1.
      for (int inv = 0; inv < kInputs; ++inv) {
        put_dir(inv, 0, inv);
        for (int c = 0; c < 3; ++c) at(inv, 3 + c) = static_cast<float>(1.0 + 0.5 * u(rng));
      }
      break;
  }
  const std::vector<float> in = p.in;  // the float values are the problem
  const int in_stride = w.in_stride, out_stride = w.out_stride;
  auto in_at = [in, in_stride](int inv, int k) { return static_cast<double>(in[std::size_t(inv) * in_stride + k]); };
  // The float direction at k..k+2 of input inv, made unit: the shader takes it as unit, and
  // so does the reference.
  auto unit_at = [in_at](int inv, int k) {
    const Eigen::Vector3d d(in_at(inv, k), in_at(inv, k + 1), in_at(inv, k + 2));
    return Eigen::Vector3d(d / d.norm());
  };
  // The worst of check(inv, y, out) over the inputs, y the SH values at input inv's
  // direction (its first three values).
  auto worst_at_directions = [=](auto check) {
    return [=](const std::vector<float>& out) {
      double worst = 0;
      std::vector<double> y(nn);
      for (int inv = 0; inv < kInputs; ++inv) {
        shtool::eval_sh<double>(n, unit_at(inv, 0), y);
        worst = worse(worst, check(inv, y, out));
      }
      return worst;
    };
  };
  switch (op) {
    case ShaderOperation::sh_eval:
      p.worst_error = worst_at_directions([=](int inv, const std::vector<double>& y, const std::vector<float>& out) {
        double worst = 0;
        for (int i = 0; i < nn; ++i) {
          const int l = shtool::sh_band(i);
          worst = worse(worst, std::abs(out[std::size_t(inv) * out_stride + i] - y[i]) / (4e-6 * band_scale(l)));
        }
        return worst;
      });
      break;
    case ShaderOperation::sh_irradiance:
      p.worst_error = worst_at_directions([=](int inv, const std::vector<double>& y, const std::vector<float>& out) {
        double worst = 0;
        for (int c = 0; c < 4; ++c) {
          double e = 0, scale = 0;
          for (int i = 0; i < nn; ++i) {
            const double a = shtool::clamped_cosine_band(shtool::sh_band(i));
            const double li = c == 0 ? in_at(inv, 3 + i) : in_at(inv, 3 + nn + 3 * i + (c - 1));
            e += a * li * y[i];
            scale += std::abs(a * li * y[i]);
          }
          worst = worse(worst, std::abs(out[std::size_t(inv) * out_stride + c] - e) / (1e-6 * scale + 1e-30));
        }
        return worst;
      });
      break;
    case ShaderOperation::zxzxz_rotate:
    case ShaderOperation::zhf_rotate:
    case ShaderOperation::zhf_tailored_rotate:
      p.worst_error = [=](const std::vector<float>& out) {
        double worst = 0;
        shtool::ShRotation<double> rot(n, nullptr);  // the reference method: no tables
        std::vector<double> f(nn), g(nn);
        for (int inv = 0; inv < kInputs; ++inv) {
          Eigen::Matrix3d r;
          for (int k = 0; k < 9; ++k) r(k / 3, k % 3) = in_at(inv, k);
          // The float matrix, made orthonormal again in double: what it stands for.
          const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
          rot.set(svd.matrixU() * svd.matrixV().transpose(), shtool::RotationMethod::reference);
          for (int i = 0; i < nn; ++i) f[i] = in_at(inv, 9 + i);
          rot.apply(f, g);
          double fn = 0;
          for (int i = 0; i < nn; ++i) fn += f[i] * f[i];
          for (int i = 0; i < nn; ++i)
            worst = worse(worst, std::abs(out[std::size_t(inv) * out_stride + i] - g[i]) /
                                     (1e-5 * std::sqrt(fn) * amplification[shtool::sh_band(i)]));
        }
        return worst;
      };
      break;
    case ShaderOperation::triple_product:
      p.worst_error = [=](const std::vector<float>& out) {
        const shtool::TriplingTensor t = shtool::TriplingTensor::compute(n);
        double worst = 0;
        std::vector<double> c(nn), scale(nn);
        for (int inv = 0; inv < kInputs; ++inv) {
          std::fill(c.begin(), c.end(), 0.0);
          std::fill(scale.begin(), scale.end(), 0.0);
          auto add = [&](int i, int j, int k, double v) {
            c[k] += v * in_at(inv, i) * in_at(inv, nn + j);
            scale[k] += std::abs(v * in_at(inv, i) * in_at(inv, nn + j));
          };
          for (std::size_t e = 0; e < t.size(); ++e) {
            const int i = t.index[3 * e], j = t.index[3 * e + 1], k = t.index[3 * e + 2];
            // every distinct permutation (i', j', k') contributes a_i' b_j' to c_k'
            const int perm[6][3] = {{i, j, k}, {i, k, j}, {j, i, k}, {j, k, i}, {k, i, j}, {k, j, i}};
            for (int q = 0; q < 6; ++q) {
              bool repeat = false;
              for (int r = 0; r < q; ++r)
                repeat |= perm[r][0] == perm[q][0] && perm[r][1] == perm[q][1] && perm[r][2] == perm[q][2];
              if (!repeat) add(perm[q][0], perm[q][1], perm[q][2], t.value[e]);
            }
          }
          for (int k = 0; k < nn; ++k)
            worst = worse(worst, std::abs(out[std::size_t(inv) * out_stride + k] - c[k]) /
                                        (1e-6 * scale[k] + 1e-30));
        }
        return worst;
      };
      break;
    case ShaderOperation::zh_shade:
      p.worst_error = [=](const std::vector<float>& out) {
        double worst = 0;
        std::vector<Eigen::Vector3d> axes(lobes);
        std::vector<double> g(lobes * n), e(nn), y(nn);
        for (int inv = 0; inv < kInputs; ++inv) {
          double scale = 0;
          for (int i = 0; i < lobes; ++i) axes[i] = unit_at(inv, 3 * i);
          for (int k = 0; k < lobes * n; ++k) g[k] = in_at(inv, 3 * lobes + k);
          for (int k = 0; k < nn; ++k) e[k] = in_at(inv, 3 * lobes + lobes * n + k);
          const double r = shtool::zh_shade_exact<double>(e, std::span<const Eigen::Vector3d>(axes), g);
          for (int i = 0; i < lobes; ++i) {
            shtool::eval_sh<double>(n, axes[i], y);
            for (int k = 0; k < nn; ++k) scale += std::abs(g[i * n + shtool::sh_band(k)] * y[k] * e[k]);
          }
          worst = worse(worst, std::abs(out[inv] - r) / (2e-6 * scale + 1e-30));
        }
        return worst;
      };
      break;
    case ShaderOperation::l1_irradiance:
    case ShaderOperation::zh3_irradiance:
      p.worst_error = [=](const std::vector<float>& out) {
        const bool zh3 = op == ShaderOperation::zh3_irradiance;
        const double pi = std::numbers::pi;
        double worst = 0;
        for (int inv = 0; inv < kInputs; ++inv) {
          const Eigen::Vector3d d(in_at(inv, 0), in_at(inv, 1), in_at(inv, 2));
          const Eigen::Vector3d nrm = d / d.norm();
          shtool::Zh3Probe<double> probe;
          for (int k = 0; k < 12; ++k) probe.l1.coefficients[k] = in_at(inv, 3 + k);
          const auto tol = [&](int c, double f) {
            // float rounding of every term: 2e-6 of the sum of their sizes (pow's argument
            // and exponent reach 3: a few ulps each; measured 0.15 of it on lavapipe)
            const double c00 = probe.l1.coefficients[c], dn = shtool::l1_vector(probe.l1, c).norm();
            return 2e-6 * (pi * 0.2820948 * std::abs(c00) * 5 + 2.1 * 0.4886 * dn + 0.25 * 3 * std::abs(f) + 1e-6);
          };
          if (!zh3) {
            const Eigen::Vector3d e = shtool::l1_nonlinear_irradiance(probe.l1, nrm);
            for (int c = 0; c < 3; ++c)
              worst = worse(worst, std::abs(out[std::size_t(inv) * out_stride + c] - e[c]) / tol(c, 0));
            continue;
          }
          for (int c = 0; c < 3; ++c) probe.zonal[c] = in_at(inv, 15 + c);
          int slot = 0;
          for (bool hallucinated : {false, true})
            for (shtool::Zh3Axis axis : {shtool::Zh3Axis::luminance, shtool::Zh3Axis::per_channel}) {
              shtool::Zh3Probe<double> q = probe;
              if (hallucinated)
                for (int c = 0; c < 3; ++c) q.zonal[c] = shtool::zh3_hallucinated_zonal(q.l1, axis, c);
              const Eigen::Vector3d e = shtool::zh3_irradiance(q, axis, nrm);
              for (int c = 0; c < 3; ++c)
                worst = worse(worst, std::abs(out[std::size_t(inv) * out_stride + 3 * slot + c] - e[c]) / tol(c, q.zonal[c]));
              ++slot;
            }
        }
        return worst;
      };
      break;
  }
  return p;
}

struct Case {
  ShaderLanguage language;
  ShaderOperation operation;
  int order;
  int lobes = 4;
};

std::string case_name(const testing::TestParamInfo<Case>& info) {
  std::string name = std::string(info.param.language == ShaderLanguage::glsl ? "glsl_" : "hlsl_") +
                     std::string(shtool::shader_operation_name(info.param.operation)) + "_N" +
                     std::to_string(info.param.order);
  if (info.param.operation == ShaderOperation::zh_shade) name += "_lobes" + std::to_string(info.param.lobes);
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (ShaderLanguage lang : {ShaderLanguage::glsl, ShaderLanguage::hlsl}) {
    // Every order shipped (a device can fail at one size and not another).
    for (int n = 1; n <= 10; ++n) cases.push_back({lang, ShaderOperation::sh_eval, n});
    for (int n = 1; n <= 10; ++n) cases.push_back({lang, ShaderOperation::sh_irradiance, n});
    for (int n = 2; n <= 8; ++n) cases.push_back({lang, ShaderOperation::zxzxz_rotate, n});
    for (int n = 2; n <= 10; ++n) cases.push_back({lang, ShaderOperation::zhf_rotate, n});
    for (int n = 2; n <= 10; ++n) cases.push_back({lang, ShaderOperation::zhf_tailored_rotate, n});
    for (int n = 2; n <= 6; ++n) cases.push_back({lang, ShaderOperation::triple_product, n});
    for (int n = 1; n <= 10; ++n) cases.push_back({lang, ShaderOperation::zh_shade, n, n == 1 ? 1 : (n % 3) + 2});
    // The probe encodings read the same numbers at every order.
    cases.push_back({lang, ShaderOperation::l1_irradiance, 2});
    cases.push_back({lang, ShaderOperation::zh3_irradiance, 3});
  }
  return cases;
}

class GeneratedShader : public testing::TestWithParam<Case> {};

TEST_P(GeneratedShader, MatchesTheRuntimeOnVulkan) {
  SHTOOL_REQUIRE_VULKAN();
  const Case c = GetParam();
  const shtool::ShaderRequest request = request_for(c.language, c.operation, c.order, c.lobes);
  const shtool::ShaderSource source = shtool::shader_source(request);
  const Wrapper w = wrapper(c.language, c.operation, c.order, c.lobes);
  const std::vector<uint32_t> spirv = gpu::compiled_wrapper(c.language, source.text, w);
  // ZHF is exact up to rounding amplified by cond(Y_l) of band l's lobe set (recorded in
  // the table): band l's tolerance is 1e-5 |f| max(1, cond(Y_l) / 10), i.e. beyond cond 10
  // about 16 float epsilons times cond(Y_l) |f|.
  std::vector<double> amplification(c.order, 1.0);
  if (request.lobes)
    for (int l = 0; l < c.order; ++l) amplification[l] = std::max(1.0, request.lobes->cond[l] / 10);
  std::mt19937_64 rng(1234 + c.order);
  const Problem p = make_problem(c.operation, c.order, c.lobes, w, rng, amplification);
  std::vector<std::vector<float>> buffers = {p.in, std::vector<float>(std::size_t(kInputs) * w.out_stride, NAN)};
  const uint32_t count = kInputs;
  const gpu::WrapperPush push{count, count};
  gpu::shared_device()->run(spirv, buffers, count, &push, sizeof push);
  const double worst = p.worst_error(buffers[1]);
  std::printf("%s: worst error %.3g of the tolerance (largest band factor %.3g); %ld multiplications, %ld additions\n",
              case_name({c, 0}).c_str(), worst, *std::max_element(amplification.begin(), amplification.end()),
              source.multiplications, source.additions);
  EXPECT_LE(worst, 1.0);  // NaN (an output never written) fails too
}

INSTANTIATE_TEST_SUITE_P(AllOperations, GeneratedShader, testing::ValuesIn(all_cases()), case_name);

// Relaxed precision compiles, validates and stays within half precision of the result
// (lavapipe evaluates it in float, so this checks the code, not 16-bit arithmetic).
TEST(GeneratedShaderHalf, CompilesAndRunsEveryOperation) {
  SHTOOL_REQUIRE_VULKAN();
  for (ShaderLanguage language : {ShaderLanguage::glsl, ShaderLanguage::hlsl})
    for (ShaderOperation op : shtool::shader_operations()) {
      const shtool::ShaderRequest request = request_for(language, op, 3, 4, ShaderPrecision::half);
      const shtool::ShaderSource source = shtool::shader_source(request);
      const Wrapper w = wrapper(language, op, 3, request.zh_lobes);
      const std::vector<uint32_t> spirv = gpu::compiled_wrapper(language, source.text, w);
      std::mt19937_64 rng(99);
      const Problem p = make_problem(op, 3, request.zh_lobes, w, rng);
      std::vector<std::vector<float>> buffers = {p.in, std::vector<float>(std::size_t(kInputs) * w.out_stride, NAN)};
      const uint32_t count = kInputs;
      const gpu::WrapperPush push{count, count};
      gpu::shared_device()->run(spirv, buffers, count, &push, sizeof push);
      // 1e3 of the float tolerance units: 4e-3 of a band's scale for sh-eval, 1e-2 |f| for
      // rotations, 1e-3 of the sum of absolute terms for products and irradiance, about
      // what 11-bit half arithmetic allows at order 3 (lavapipe itself computes in float).
      EXPECT_LE(p.worst_error(buffers[1]), 1e3) << shtool::shader_operation_name(op);
    }
}

// Files of one order can be included together (shtool_sh_band_sums and SHTOOL_BAND_TEXTURES
// are defined by two of them, SHTOOL_ORDER by all), in both languages: every operation of
// order 3 in one compute shader.
TEST(GeneratedShaderIncludes, EveryOperationOfOneOrderTogether) {
  for (ShaderLanguage lang : {ShaderLanguage::glsl, ShaderLanguage::hlsl}) {
    std::string all;
    for (ShaderOperation op : shtool::shader_operations()) all += shtool::shader_source(request_for(lang, op, 3, 4)).text;
    const Wrapper w = gpu::wrapper(lang, ShaderOperation::zxzxz_rotate, 3, 4);
    EXPECT_NO_THROW(gpu::compiled_wrapper(lang, all, w)) << (lang == ShaderLanguage::glsl ? "glsl" : "hlsl");
  }
}

// The GLSL is also valid OpenGL ES 3.00 (WebGL2): each file inside an ES fragment shader.
TEST(GeneratedShaderGlslEs, EveryOperationCompilesAsEs300) {
  for (ShaderOperation op : shtool::shader_operations())
    for (ShaderPrecision precision : {ShaderPrecision::float32, ShaderPrecision::half}) {
      const shtool::ShaderRequest request =
          request_for(ShaderLanguage::glsl, op, shtool::shader_max_order(op), 4, precision);
      const Wrapper w = wrapper(ShaderLanguage::glsl, op, request.order, request.zh_lobes);
      std::string body = w.body;
      // ES fragment shader: the inputs come from a uniform array instead of a buffer.
      const std::string source = "#version 300 es\nprecision highp float;\nprecision highp int;\n"
                                 "uniform float inp[" + std::to_string(w.in_stride) + "];\nout vec4 color;\n" +
                                 shtool::shader_source(request).text +
                                 "void main() {\n  int ib = 0;\n  float outp[" + std::to_string(w.out_stride) +
                                 "];\n  int ob = 0;\n" + body + "  color = vec4(outp[0]);\n}\n";
      const auto path = shtool::test::scratch_path("shaders", "es300.frag");
      {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fwrite(source.data(), 1, source.size(), f);
        std::fclose(f);
      }
      const auto r = shtool::test::run_command({SHTOOL_GLSLANG_VALIDATOR, path.string()});
      EXPECT_EQ(r.exit_code, 0) << shtool::shader_operation_name(op) << ":\n" << r.out << r.err;
    }
}

// ---- Band textures (zh-shade's table form, the tailored ZHF rotation's texture form) ----

// Band l's size: sqrt((2l+1)/4pi) |c_l| bounds its band sum everywhere.
std::vector<double> band_bounds(int n, const std::vector<double>& c) {
  std::vector<double> b(n);
  for (int l = 0; l < n; ++l) {
    double norm = 0;
    for (int m = -l; m <= l; ++m) norm += c[l * (l + 1) + m] * c[l * (l + 1) + m];
    b[l] = band_scale(l) * std::sqrt(norm);
  }
  return b;
}

// Node tables read with linear filtering err by about l(l+1) / (2 R^2) of the band's size,
// R = size - 1 (bilinear interpolation over cells 2/R wide in face coordinates); the tests
// allow 2 l(l+1) / R^2 and check that the error falls at least 12x from R = 32 to 128 (16x
// for second-order interpolation; a first-order error, as across a cube's folds, gives 4x).
double interpolation_allowance(int l, int size) {
  const double r = size - 1;
  return 2.0 * l * (l + 1) / (r * r) + 2e-6;
}

struct TextureRun {
  double worst = 0;  // largest error / allowance
  double max_error = 0;  // largest absolute error, for the convergence check

  void add(double err, double allowance) {
    worst = worse(worst, err / allowance);
    max_error = std::max(max_error, std::isnan(err) ? INFINITY : err);
  }
};

// The generated source of `request` (order n, `lobes` lobes) in its textured wrapper,
// compiled; it reads one band texture per four bands.
std::vector<uint32_t> textured_spirv(ShaderLanguage lang, const shtool::ShaderRequest& request, int n, int lobes) {
  const std::string generated = shtool::shader_source(request).text;
  const Wrapper w = gpu::textured_wrapper(lang, request.operation, n, lobes);
  return gpu::compiled_wrapper(lang, generated, w, (n + 3) / 4);
}

// One dispatch over kInputs inputs with the band textures of the SH function `f`, R = size.
void run_with_band_textures(const std::vector<uint32_t>& spirv, std::vector<std::vector<float>>& buffers, int n,
                            const std::vector<double>& f, int size) {
  const uint32_t count = kInputs;
  const gpu::WrapperPush push{count, count};
  gpu::shared_device()->run(spirv, buffers, count, &push, sizeof push, band_textures(n, f, size));
}

// Both languages at each order: within the interpolation allowance at 33 and 129 nodes per
// face side, and the error falling as R^-2 between them ((129 / 33)^2 = 15.3; 12 required).
template <class Run>
void expect_texture_convergence(const char* name, std::initializer_list<int> orders, Run run) {
  for (ShaderLanguage lang : {ShaderLanguage::glsl, ShaderLanguage::hlsl})
    for (int n : orders) {
      const TextureRun coarse = run(lang, n, 33), fine = run(lang, n, 129);
      std::printf("%s %s N=%d: worst %.3g / %.3g of the allowance at 33 / 129 nodes per face side, error ratio %.3g\n",
                  name, lang == ShaderLanguage::glsl ? "glsl" : "hlsl", n, coarse.worst, fine.worst,
                  coarse.max_error / fine.max_error);
      EXPECT_LE(coarse.worst, 1.0) << n;
      EXPECT_LE(fine.worst, 1.0) << n;
      EXPECT_GT(coarse.max_error / fine.max_error, 12.0) << n;
    }
}

TextureRun run_zh_shade_table(ShaderLanguage lang, int n, int lobes, int size) {
  const shtool::ShaderRequest request = request_for(lang, ShaderOperation::zh_shade, n, lobes);
  const int in_stride = 3 * lobes + lobes * n;
  const std::vector<uint32_t> spirv = textured_spirv(lang, request, n, lobes);
  std::mt19937_64 rng(77 + n);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> e(n * n);
  for (double& v : e) v = u(rng);
  std::vector<float> in(std::size_t(kInputs) * in_stride);
  for (int inv = 0; inv < kInputs; ++inv) {
    for (int i = 0; i < lobes; ++i) {
      const Eigen::Vector3d a = random_unit(rng);
      for (int c = 0; c < 3; ++c) in[std::size_t(inv) * in_stride + 3 * i + c] = static_cast<float>(a[c]);
    }
    for (int k = 0; k < lobes * n; ++k) in[std::size_t(inv) * in_stride + 3 * lobes + k] = static_cast<float>(u(rng));
  }
  std::vector<std::vector<float>> buffers = {in, std::vector<float>(kInputs, NAN)};
  run_with_band_textures(spirv, buffers, n, e, size);
  const std::vector<double> bound = band_bounds(n, e);
  TextureRun result;
  std::vector<Eigen::Vector3d> axes(lobes);
  std::vector<double> g(lobes * n);
  for (int inv = 0; inv < kInputs; ++inv) {
    double allowance = 0;
    for (int i = 0; i < lobes; ++i) {
      for (int c = 0; c < 3; ++c) axes[i][c] = in[std::size_t(inv) * in_stride + 3 * i + c];
      axes[i] /= axes[i].norm();
      for (int l = 0; l < n; ++l) {
        g[i * n + l] = in[std::size_t(inv) * in_stride + 3 * lobes + i * n + l];
        allowance += std::abs(g[i * n + l]) * bound[l] * interpolation_allowance(l, size);
      }
    }
    const double r = shtool::zh_shade_exact<double>(e, std::span<const Eigen::Vector3d>(axes), g);
    result.add(std::abs(buffers[1][inv] - r), allowance);
  }
  return result;
}

// Eq. 24-25 on the GPU: the lighting's band textures filled as documented, shaded per lobe
// with one fetch per four bands; converges to Eq. 13 as R grows.
TEST(GeneratedShaderTextures, ZhShadeTableConvergesToEq13) {
  SHTOOL_REQUIRE_VULKAN();
  expect_texture_convergence("zh_shade_table", {3, 6, 10},
                             [](ShaderLanguage lang, int n, int size) { return run_zh_shade_table(lang, n, 4, size); });
}

TextureRun run_tailored(ShaderLanguage lang, int n, int size) {
  const shtool::ShaderRequest request = request_for(lang, ShaderOperation::zhf_tailored_rotate, n, 4);
  const int nn = n * n;
  const std::vector<uint32_t> spirv = textured_spirv(lang, request, n, 4);
  std::mt19937_64 rng(5 + n);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> f(nn);
  for (double& v : f) v = u(rng);
  std::vector<float> in(std::size_t(kInputs) * 9);
  std::vector<Eigen::Matrix3d> rotations(kInputs);
  std::normal_distribution<double> gauss;
  for (int inv = 0; inv < kInputs; ++inv) {
    rotations[inv] = inv == 0 ? Eigen::Matrix3d::Identity()
                              : Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng))
                                    .normalized()
                                    .toRotationMatrix();
    for (int k = 0; k < 9; ++k) in[std::size_t(inv) * 9 + k] = static_cast<float>(rotations[inv](k / 3, k % 3));
  }
  std::vector<std::vector<float>> buffers = {in, std::vector<float>(std::size_t(kInputs) * nn, NAN)};
  run_with_band_textures(spirv, buffers, n, f, size);
  // Each g_lm sums A^_l[m][d] times samples that err by the band's allowance.
  const shtool::ZhfLobes& lobes = *request.lobes;
  const std::vector<double> bound = band_bounds(n, f);
  std::vector<double> row_allowance(nn);
  for (int i = 0; i < nn; ++i) {
    const int l = shtool::sh_band(i);
    for (int k = lobes.row_start[i]; k < lobes.row_start[i + 1]; ++k)
      row_allowance[i] += std::abs(lobes.val[k]) * bound[l] * interpolation_allowance(l, size);
  }
  shtool::ShRotation<double> rot(n, nullptr);
  std::vector<double> g(nn);
  TextureRun result;
  for (int inv = 0; inv < kInputs; ++inv) {
    Eigen::Matrix3d r;
    for (int k = 0; k < 9; ++k) r(k / 3, k % 3) = in[std::size_t(inv) * 9 + k];
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    rot.set(svd.matrixU() * svd.matrixV().transpose(), shtool::RotationMethod::reference);
    rot.apply(f, g);
    for (int i = 0; i < nn; ++i) result.add(std::abs(buffers[1][std::size_t(inv) * nn + i] - g[i]), row_allowance[i]);
  }
  return result;
}

// The signal-tailored rotation from band textures ([1] Eq. 11 as the paper runs it on the
// GPU): equal to the exact rotation up to the texture's interpolation error, which falls
// as R^-2.
TEST(GeneratedShaderTextures, TailoredZhfRotationFromBandTextures) {
  SHTOOL_REQUIRE_VULKAN();
  expect_texture_convergence("zhf_tailored", {3, 5, 8}, run_tailored);
}

}  // namespace
