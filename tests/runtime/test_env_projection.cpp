// The exact texel integrals of the environment projections, against a second
// implementation (Gauss-Legendre per texel in long double, far more nodes than the
// integrands need), closed forms (uniform radiance), and the rates of the discretisation
// error of sampled analytic scenes.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "shtool/env_projection.h"
#include "shtool/legendre.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr double kPi = std::numbers::pi;
using Ld = long double;

// All N^2 SH values at a direction given by (cos t, sin t, p), in long double, from the
// normalised Legendre values (independent of the projector's row and column formulas).
void sh_long(int order, Ld z, Ld s, Ld p, std::vector<Ld>& out) {
  std::vector<Ld> leg(static_cast<std::size_t>(order) * (order + 1) / 2);
  normalized_legendre_all(order, z, s, 1 / std::sqrt(4 * std::numbers::pi_v<Ld>), leg);
  out.assign(sh_count(order), 0);
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) {
      const Ld q = leg[l * (l + 1) / 2 + std::abs(m)];
      out[sh_index(l, m)] = m == 0 ? q : (m > 0 ? std::sqrt(Ld(2)) * q * std::cos(m * p)
                                               : std::sqrt(Ld(2)) * q * std::sin(-m * p));
    }
}

struct Rule {
  std::vector<Ld> x, w;  // on [-1, 1]
};
Rule rule(int n) {
  const GaussLegendre g = gauss_legendre(n);
  return {std::vector<Ld>(g.nodes.begin(), g.nodes.end()), std::vector<Ld>(g.weights.begin(), g.weights.end())};
}

std::vector<float> random_image(int w, int h, int channels, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  std::vector<float> img(static_cast<std::size_t>(w) * h * channels);
  for (float& v : img) v = u(rng);
  return img;
}

// Reference equirect projection: a 2D Gauss rule in (t, p) inside every texel.
std::vector<Ld> reference_equirect(const std::vector<float>& img, int w, int h, int channels, int order) {
  const Rule g = rule(24);
  std::vector<Ld> out(sh_count(order) * channels, 0), y;
  const Ld pi = std::numbers::pi_v<Ld>;
  for (int row = 0; row < h; ++row) {
    const Ld t0 = pi * row / h, t1 = pi * (row + 1) / h;
    for (int x = 0; x < w; ++x) {
      const Ld p0 = pi - 2 * pi * (x + 1) / w, p1 = pi - 2 * pi * x / w;
      std::vector<Ld> texel(sh_count(order), 0);
      for (std::size_t i = 0; i < g.x.size(); ++i) {
        const Ld t = (t0 + t1) / 2 + (t1 - t0) / 2 * g.x[i];
        for (std::size_t j = 0; j < g.x.size(); ++j) {
          const Ld p = (p0 + p1) / 2 + (p1 - p0) / 2 * g.x[j];
          sh_long(order, std::cos(t), std::sin(t), p, y);
          const Ld wgt = g.w[i] * g.w[j] * (t1 - t0) / 2 * (p1 - p0) / 2 * std::sin(t);
          for (int k = 0; k < sh_count(order); ++k) texel[k] += wgt * y[k];
        }
      }
      for (int k = 0; k < sh_count(order); ++k)
        for (int c = 0; c < channels; ++c) out[k * channels + c] += texel[k] * img[(row * w + x) * channels + c];
    }
  }
  return out;
}

Ld max_abs(const std::vector<Ld>& v) {
  Ld m = 0;
  for (Ld x : v) m = std::max(m, std::abs(x));
  return m;
}

// Radiance 1 in all three channels projects to sqrt(4 pi) in band 0 and nothing above it.
void expect_uniform_radiance(const Result<EnvCoefficients>& r, const std::string& what) {
  ASSERT_TRUE(r) << r.error().message;
  const std::vector<double>& c = r.value().coefficients;
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[ch], std::sqrt(4 * kPi), 1e-14) << what;
  for (std::size_t i = 3; i < c.size(); ++i) ASSERT_LT(std::abs(c[i]), 1e-14) << what << " coefficient " << i / 3;
}

// Every coefficient within 1e-12 of the largest reference coefficient of the per-texel
// quadrature `ref`.
void expect_matches_reference(const Result<EnvCoefficients>& r, const std::vector<Ld>& ref, int channels,
                              const std::string& what) {
  ASSERT_TRUE(r) << r.error().message;
  const Ld scale = max_abs(ref);
  for (std::size_t i = 0; i < ref.size(); ++i)
    ASSERT_NEAR(r.value().coefficients[i], static_cast<double>(ref[i]), 1e-12 * static_cast<double>(scale))
        << what << " coefficient " << i / channels;
}

TEST(EquirectProjection, UniformRadianceIsExact) {
  for (int h : {1, 2, 3, 8, 64, 301}) {
    for (int order : {1, 2, 5, 9, 16}) {
      const int w = 2 * h;
      const std::vector<float> img(static_cast<std::size_t>(w) * h * 3, 1.0f);
      const Result<EnvCoefficients> r = project_equirect({img.data(), w, h, 3}, order);
      expect_uniform_radiance(r, "h " + std::to_string(h) + " order " + std::to_string(order));
    }
  }
}

TEST(EquirectProjection, MatchesPerTexelQuadratureOnRandomImages) {
  struct Case {
    int h, channels, order;
  };
  for (const Case& k : {Case{1, 1, 4}, Case{2, 3, 6}, Case{4, 3, 8}, Case{5, 2, 5}, Case{8, 3, 10}}) {
    const int w = 2 * k.h;
    const std::vector<float> img = random_image(w, k.h, k.channels, 17 + k.h);
    const Result<EnvCoefficients> r = project_equirect({img.data(), w, k.h, k.channels}, k.order);
    expect_matches_reference(r, reference_equirect(img, w, k.h, k.channels, k.order), k.channels,
                             "h " + std::to_string(k.h) + " order " + std::to_string(k.order));
  }
}

TEST(EquirectProjection, RowIntegralsSumToTheWholeSphere) {
  // The rows of any height tile [0, pi]: sum_y T_l^0(y) = integral K_l P_l(z) dz = 0 for
  // l > 0 (sqrt(4 pi) / (2 pi) = 1 / sqrt(pi) for l = 0); odd m integrate to pi-multiples
  // that the closed form fixes too, so check the zonal ones.
  for (int h : {1, 7, 100}) {
    const Result<EquirectProjector> p = EquirectProjector::create(2 * h, h, 12);
    ASSERT_TRUE(p);
    for (int l = 0; l < 12; ++l) {
      double sum = 0;
      for (int y = 0; y < h; ++y) sum += p.value().row_integrals(y)[l * (l + 1) / 2];
      EXPECT_NEAR(sum, l == 0 ? 1 / std::sqrt(kPi) : 0.0, 1e-15) << "h " << h << " l " << l;
    }
  }
}

TEST(EquirectProjection, BadInputIsReported) {
  std::vector<float> img(8 * 4 * 3, 1.0f);
  EXPECT_FALSE(project_equirect({img.data(), 8, 3, 3}, 3));  // not 2:1
  EXPECT_FALSE(project_equirect({img.data(), 8, 4, 3}, 0));
  EXPECT_FALSE(project_equirect({img.data(), 8, 4, 3}, kMaxEnvOrder + 1));
  img[(2 * 8 + 5) * 3 + 1] = std::numeric_limits<float>::quiet_NaN();
  const Result<EnvCoefficients> r = project_equirect({img.data(), 8, 4, 3}, 3);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("texel (5, 2) channel 1 is NaN"), std::string::npos) << r.error().message;
  img[(2 * 8 + 5) * 3 + 1] = std::numeric_limits<float>::infinity();
  EXPECT_NE(project_equirect({img.data(), 8, 4, 3}, 3).error().message.find("infinite"), std::string::npos);
}

TEST(EquirectProjection, RowStrideIsHonoured) {
  const int w = 16, h = 8;
  const std::vector<float> img = random_image(w, h, 3, 5);
  std::vector<float> padded(static_cast<std::size_t>(h) * (w * 3 + 7), -1.0f);
  for (int y = 0; y < h; ++y)
    std::copy(img.begin() + y * w * 3, img.begin() + (y + 1) * w * 3, padded.begin() + y * (w * 3 + 7));
  const auto a = project_equirect({img.data(), w, h, 3}, 5);
  const auto b = project_equirect({padded.data(), w, h, 3, w * 3 + 7}, 5);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a.value().coefficients, b.value().coefficients);
}

// ---------------------------------------------------------------------------
// Cubemaps

// Reference: a 48 x 48 Gauss rule per texel in long double, directions from the face
// table written out here again.
std::vector<Ld> reference_cubemap(const std::array<std::vector<float>, 6>& faces, int size, int channels,
                                  int order, bool mirror_x) {
  const Rule g = rule(48);
  std::vector<Ld> out(sh_count(order) * channels, 0), y;
  for (int f = 0; f < 6; ++f) {
    for (int ty = 0; ty < size; ++ty)
      for (int tx = 0; tx < size; ++tx) {
        std::vector<Ld> texel(sh_count(order), 0);
        for (std::size_t i = 0; i < g.x.size(); ++i)
          for (std::size_t j = 0; j < g.x.size(); ++j) {
            const Ld s = -1 + (2 * tx + 1 + g.x[j]) / Ld(size), t = -1 + (2 * ty + 1 + g.x[i]) / Ld(size);
            const std::array<std::array<Ld, 3>, 6> table = {{{1, -t, -s}, {-1, -t, s}, {s, 1, t},
                                                             {s, -1, -t}, {s, -t, 1}, {-s, -t, -1}}};
            std::array<Ld, 3> d = table[f];
            if (mirror_x) d[0] = -d[0];
            const Ld r = std::sqrt(1 + s * s + t * t);
            const Ld wx = d[0] / r, wy = -d[2] / r, wz = d[1] / r;  // y-up cube frame -> shtool
            const Ld st = std::sqrt(wx * wx + wy * wy);
            sh_long(order, wz, st, std::atan2(wy, wx), y);
            const Ld wgt = g.w[i] * g.w[j] / (Ld(size) * size) / (r * r * r);
            for (int k = 0; k < sh_count(order); ++k) texel[k] += wgt * y[k];
          }
        for (int k = 0; k < sh_count(order); ++k)
          for (int c = 0; c < channels; ++c)
            out[k * channels + c] += texel[k] * faces[f][(ty * size + tx) * channels + c];
      }
  }
  return out;
}

std::array<FloatImageView, 6> views(const std::array<std::vector<float>, 6>& faces, int size, int channels) {
  std::array<FloatImageView, 6> v;
  for (int f = 0; f < 6; ++f) v[f] = {faces[f].data(), size, size, channels};
  return v;
}

TEST(CubemapProjection, UniformRadianceIsExact) {
  for (int size : {1, 2, 5, 32}) {
    for (int order : {1, 3, 6, 10}) {
      std::array<std::vector<float>, 6> faces;
      for (auto& f : faces) f.assign(static_cast<std::size_t>(size) * size * 3, 1.0f);
      const auto v = views(faces, size, 3);
      const Result<EnvCoefficients> r = project_cubemap(v, order);
      expect_uniform_radiance(r, "size " + std::to_string(size) + " order " + std::to_string(order));
    }
  }
}

TEST(CubemapProjection, MatchesPerTexelQuadratureOnRandomImages) {
  struct Case {
    int size, channels, order;
    bool mirror;
  };
  for (const Case& k : {Case{1, 3, 6, false}, Case{2, 1, 8, true}, Case{3, 3, 5, false}, Case{4, 2, 7, false}}) {
    std::array<std::vector<float>, 6> faces;
    for (int f = 0; f < 6; ++f) faces[f] = random_image(k.size, k.size, k.channels, 100 + 7 * f + k.size);
    const Result<EnvCoefficients> r = project_cubemap(views(faces, k.size, k.channels), k.order, k.mirror);
    expect_matches_reference(r, reference_cubemap(faces, k.size, k.channels, k.order, k.mirror), k.channels,
                             "size " + std::to_string(k.size) + " order " + std::to_string(k.order));
  }
}

TEST(CubemapProjection, SingleTexelsOfLargeFacesAtHighOrders) {
  // The node count shrinks with the texel; check one texel's integrals against a
  // long-double rule of twice as many nodes and 8 more at face sizes up to 2048 and
  // orders up to 32, at the face centre, an edge and a corner (where the texels are
  // smallest and most skewed).
  std::vector<Ld> y;
  for (int size : {1, 7, 64, 512, 2048}) {
    for (int order : {3, 10, 20, 32}) {
      if (size < 64 && order > 20) continue;  // the reference alone would take seconds
      const CubemapProjector p = CubemapProjector::create(size, order).value();
      const Rule g = rule(std::min(64, 2 * p.nodes_per_side() + 8));
      const int n = sh_count(order);
      std::vector<double> got(n);
      for (const auto& [face, x, ty] : {std::tuple{CubeFace::pz, size / 2, size / 2}, std::tuple{CubeFace::nx, 0, size / 3},
                                        std::tuple{CubeFace::py, size - 1, size - 1}}) {
        p.texel_integrals(face, x, ty, got);
        std::vector<Ld> ref(n, 0);
        Ld solid = 0;
        for (std::size_t i = 0; i < g.x.size(); ++i)
          for (std::size_t j = 0; j < g.x.size(); ++j) {
            const Ld s = -1 + (2 * x + 1 + g.x[j]) / Ld(size), t = -1 + (2 * ty + 1 + g.x[i]) / Ld(size);
            const Eigen::Vector3d d = p.direction(face, static_cast<double>(s), static_cast<double>(t));
            const Ld r = std::sqrt(1 + s * s + t * t);
            const Ld wgt = g.w[i] * g.w[j] / (Ld(size) * size) / (r * r * r);
            sh_long(order, d.z(), std::sqrt(Ld(d.x()) * d.x() + Ld(d.y()) * d.y()), std::atan2(Ld(d.y()), Ld(d.x())), y);
            for (int k = 0; k < n; ++k) ref[k] += wgt * y[k];
            solid += wgt;
          }
        for (int k = 0; k < n; ++k)
          ASSERT_NEAR(got[k], static_cast<double>(ref[k]), 1e-12 * static_cast<double>(solid))
              << "size " << size << " order " << order << " nodes " << p.nodes_per_side() << " i " << k;
      }
    }
  }
}

TEST(CubemapProjection, FaceTableAndFrame) {
  const Result<CubemapProjector> p = CubemapProjector::create(4, 2);
  ASSERT_TRUE(p);
  // Face centres: the y-up cube axes, in shtool's z-up frame (X, -Z, Y).
  const CubemapProjector& q = p.value();
  EXPECT_TRUE(q.direction(CubeFace::px, 0, 0).isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_TRUE(q.direction(CubeFace::py, 0, 0).isApprox(Eigen::Vector3d(0, 0, 1)));
  EXPECT_TRUE(q.direction(CubeFace::pz, 0, 0).isApprox(Eigen::Vector3d(0, -1, 0)));
  EXPECT_TRUE(q.direction(CubeFace::nz, 0, 0).isApprox(Eigen::Vector3d(0, 1, 0)));
  // +Z face, right edge (s = 1) leans to +X; its top (t = -1) leans up (+Y cube = +z).
  EXPECT_GT(q.direction(CubeFace::pz, 1, 0).x(), 0.5);
  EXPECT_GT(q.direction(CubeFace::pz, 0, -1).z(), 0.5);
  const Result<CubemapProjector> m = CubemapProjector::create(4, 2, true);
  EXPECT_TRUE(m.value().direction(CubeFace::px, 0, 0).isApprox(Eigen::Vector3d(-1, 0, 0)));
}


// The coefficients against the reference's per-texel integrals (texel_integrals) summed
// in long double: with 6 R^2 = 14k..38k texels, project_cubemap_reference's own double
// sums drift by about sqrt(6 R^2) ulps, as much as the tolerance (4e-15 of the largest).
void expect_near_texel_integral_sums(const std::array<FloatImageView, 6>& v, int size, int channels, int order,
                                     bool mirror, const EnvCoefficients& fast) {
  const CubemapProjector p = CubemapProjector::create(size, order, mirror).value();
  const int n = sh_count(order);
  std::vector<Ld> slow(static_cast<std::size_t>(n) * channels, 0);
  std::vector<double> integral(n);
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        p.texel_integrals(static_cast<CubeFace>(f), x, y, integral);
        const float* texel = v[f].row(y) + static_cast<std::size_t>(x) * channels;
        for (int i = 0; i < n; ++i)
          for (int c = 0; c < channels; ++c) slow[i * channels + c] += Ld(integral[i]) * texel[c];
      }
  double scale = 0;
  for (Ld c : slow) scale = std::max(scale, static_cast<double>(std::abs(c)));
  for (std::size_t i = 0; i < slow.size(); ++i)
    ASSERT_NEAR(fast.coefficients[i], static_cast<double>(slow[i]), 4e-15 * scale)
        << "size " << size << " order " << order << " coefficient " << i / channels;
}

TEST(CubemapProjection, FastPathMatchesTheReferenceToRoundOff) {
  // The class-folded path against every texel's own rule in shtool's frame: the same
  // integrals, summed in another order, over odd and even faces (classes of 1, 4 and 8
  // texels), every channel count and both mirrors.
  struct Case {
    int size, channels, order;
    bool mirror;
  };
  for (const Case& k : {Case{1, 3, 6, false}, Case{2, 1, 8, true}, Case{3, 3, 5, false}, Case{4, 2, 7, false},
                        Case{5, 4, 10, true}, Case{8, 3, 1, false}, Case{9, 3, 2, true}, Case{16, 3, 4, false},
                        Case{33, 1, 9, false}, Case{12, 3, 13, true}}) {
    std::array<std::vector<float>, 6> faces;
    for (int f = 0; f < 6; ++f) faces[f] = random_image(k.size, k.size, k.channels, 300 + 11 * f + k.size);
    const auto v = views(faces, k.size, k.channels);
    const Result<EnvCoefficients> fast = project_cubemap(v, k.order, k.mirror);
    ASSERT_TRUE(fast);
    expect_near_texel_integral_sums(v, k.size, k.channels, k.order, k.mirror, fast.value());
  }
}

TEST(CubemapProjection, FastPathMatchesTheReferenceOnFacesOfManyTiles) {
  // Faces of several bands and tiles of 16 x 16 classes, whole tiles (read as runs of
  // texels) and tiles cut by the face's edge (read texel by texel), in batches of rows
  // that end inside a tile; a row stride wider than the row. Tolerance as above, against
  // the same per-texel integrals.
  struct Case {
    int size, channels, order;
    bool mirror;
  };
  for (const Case& k : {Case{48, 3, 6, false}, Case{67, 2, 4, true}, Case{80, 4, 3, false}, Case{20, 1, 32, true}}) {
    const std::size_t stride = static_cast<std::size_t>(k.size + 5) * k.channels;
    std::array<std::vector<float>, 6> faces;
    std::array<FloatImageView, 6> v;
    for (int f = 0; f < 6; ++f) {
      faces[f] = random_image(k.size + 5, k.size, k.channels, 700 + 13 * f + k.size);
      v[f] = {faces[f].data(), k.size, k.size, k.channels, stride};
    }
    const Result<EnvCoefficients> fast = project_cubemap(v, k.order, k.mirror);
    ASSERT_TRUE(fast);
    expect_near_texel_integral_sums(v, k.size, k.channels, k.order, k.mirror, fast.value());
  }
}

// What a parallel caller does, with the blocks run last first: each block into its own
// partial sums of a 3-channel image, then the partials summed in block order.
template <class Projector, class Image>
std::vector<double> blocks_in_reverse(const Projector& p, const Image& image) {
  std::vector<std::vector<double>> partials(p.block_count(), std::vector<double>(p.partial_size(3), 0.0));
  for (int b = p.block_count() - 1; b >= 0; --b) EXPECT_TRUE(p.accumulate_block(image, b, partials[b])) << b;
  std::vector<double> sum(p.partial_size(3), 0.0);
  for (const auto& part : partials)
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += part[i];
  return sum;
}

TEST(CubemapProjection, BlocksCanRunInAnyOrderAndNonFiniteTexelsAreNamed) {
  const int size = 37, order = 5;
  std::array<std::vector<float>, 6> faces;
  for (int f = 0; f < 6; ++f) faces[f] = random_image(size, size, 3, 40 + f);
  const auto v = views(faces, size, 3);
  const CubemapProjector p = CubemapProjector::create(size, order).value();
  ASSERT_GT(p.block_count(), 1);
  EXPECT_EQ(blocks_in_reverse(p, v), project_cubemap(v, order).value().coefficients);
  // Two bad texels: every path names the first (face, row, column), whichever block meets it.
  faces[3][(20 * size + 2) * 3 + 1] = std::numeric_limits<float>::infinity();
  faces[4][(1 * size + 30) * 3 + 0] = std::numeric_limits<float>::quiet_NaN();
  const std::string expected = "-Y face texel (2, 20) channel 1 is infinite";
  EXPECT_EQ(project_cubemap(v, order).error().message, expected);
  EXPECT_EQ(project_cubemap_reference(v, order).error().message, expected);
  for (int b = 0; b < p.block_count(); ++b) {
    std::vector<double> part(p.partial_size(3), 0.0);
    const Result<Ok> r = p.accumulate_block(v, b, part);
    if (!r) EXPECT_EQ(r.error().message, expected);
  }
}

// ---------------------------------------------------------------------------
// One analytic scene in both layouts: texel values sampled at texel centres, so the
// projections err by O(h^2) against the scene's own coefficients and agree with each
// other to that error.

double scene(const Eigen::Vector3d& w) {
  return 1.0 + 0.8 * std::exp(4 * (w.dot(Eigen::Vector3d(0.48, -0.6, 0.64)) - 1)) + 0.3 * w.x() * w.z();
}

std::vector<double> equirect_of_scene(int h, int order) {
  const int w = 2 * h;
  std::vector<float> img(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img[y * w + x] = static_cast<float>(
          scene(direction_from_angles<double>(kPi * (y + 0.5) / h, kPi - 2 * kPi * (x + 0.5) / w)));
  return project_equirect({img.data(), w, h, 1}, order).value().coefficients;
}

std::vector<double> cubemap_of_scene(int size, int order) {
  const CubemapProjector p = CubemapProjector::create(size, order).value();
  std::array<std::vector<float>, 6> faces;
  for (int f = 0; f < 6; ++f) {
    faces[f].resize(static_cast<std::size_t>(size) * size);
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x)
        faces[f][y * size + x] = static_cast<float>(
            scene(p.direction(static_cast<CubeFace>(f), -1 + (2 * x + 1.0) / size, -1 + (2 * y + 1.0) / size)));
  }
  return project_cubemap(views(faces, size, 1), order).value().coefficients;
}

double distance(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}

TEST(EnvProjection, LayoutsAgreeAndConvergeQuadratically) {
  const int order = 6;
  const std::vector<double> exact = project_sh(order, scene, 40);
  const double e_eq1 = distance(equirect_of_scene(32, order), exact);
  const double e_eq2 = distance(equirect_of_scene(64, order), exact);
  const double e_cu1 = distance(cubemap_of_scene(16, order), exact);
  const double e_cu2 = distance(cubemap_of_scene(32, order), exact);
  // Midpoint sampling: the error falls by 4 per halving of the texel size.
  EXPECT_GT(e_eq1 / e_eq2, 3.5) << e_eq1 << " " << e_eq2;
  EXPECT_LT(e_eq1 / e_eq2, 4.5) << e_eq1 << " " << e_eq2;
  EXPECT_GT(e_cu1 / e_cu2, 3.5) << e_cu1 << " " << e_cu2;
  EXPECT_LT(e_cu1 / e_cu2, 4.5) << e_cu1 << " " << e_cu2;
  EXPECT_LT(distance(equirect_of_scene(64, order), cubemap_of_scene(32, order)), 2 * (e_eq2 + e_cu2));
  EXPECT_LT(e_eq2, 1e-3);
}

TEST(EnvProjection, BlocksCanRunInAnyOrder) {
  const int w = 64, h = 32, order = 7;
  const std::vector<float> img = random_image(w, h, 3, 9);
  const FloatImageView view{img.data(), w, h, 3};
  const EquirectProjector p = EquirectProjector::create(w, h, order).value();
  EXPECT_EQ(blocks_in_reverse(p, view), project_equirect(view, order).value().coefficients);
}

}  // namespace
}  // namespace shtool
