// Glossy LDPRT: the BRDF matrix against closed forms (Phong at normal view, Lambert's
// among them) and against an independent quadrature, the SVD's factors, the transfer matrix
// against the SH rotation (nothing in the way) and against a dense quadrature with
// analytic visibility (a square roof), rows that rotate with a rigidly rotated mesh, and
// the same bytes on 1 and 2 threads.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "fit/deformation.h"
#include "fit/embree_scene.h"
#include "fit/mesh.h"
#include "glossy/brdf.h"
#include "glossy/glossy_transfer.h"
#include "shtool/glossy.h"
#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "test_util.h"

namespace {

using namespace shtool;
using namespace shtool::glossy;
constexpr double kPi = std::numbers::pi;

fit::Mesh from_obj(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "shtool_test_glossy";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / name) << text;
  return fit::load_obj(dir / name, fit::NormalSource::automatic, UpAxis::z);  // written in shtool's frame
}

using test::legendre_p;

TEST(GlossyBrdf, PhongAtNormalViewMatchesItsClosedForm) {
  // Exponent a (m = sqrt(2 / (a + 2))): at v = n the mirror direction is n, so
  // B_{l0} = (a + 2) K_l integral_0^1 mu^(a+1) P_l(mu) d mu, a polynomial integral that a
  // Gauss-Legendre rule of 20 nodes on [0, 1] gets exactly; m != 0 vanish. a = 0 is
  // Lambert's 1/pi: the clamped-cosine coefficients.
  const int g = 3, order = 5;  // odd G: texel (1, 1) is centred on the normal
  const GaussLegendre gl = gauss_legendre(20);
  for (int a : {0, 6, 20}) {
    Brdf brdf{BrdfModel::phong, std::sqrt(2.0 / (a + 2)), 1.0};
    ASSERT_NEAR(phong_exponent(brdf.roughness), a, 1e-12);
    const Eigen::MatrixXd b = brdf_matrix(brdf, order, g, 2);
    const Eigen::RowVectorXd row = b.row(1 * g + 1);
    for (int l = 0; l < order; ++l) {
      double integral = 0;
      for (int i = 0; i < 20; ++i) {
        const double mu = 0.5 * (gl.nodes[i] + 1);
        integral += 0.5 * gl.weights[i] * std::pow(mu, a + 1) * legendre_p(l, mu);
      }
      const double expected = (a + 2) * std::sqrt((2 * l + 1) / (4 * kPi)) * integral;
      for (int m = -l; m <= l; ++m)
        EXPECT_NEAR(row(sh_index(l, m)), m == 0 ? expected : 0.0, 1e-9) << "a " << a << " l " << l << " m " << m;
    }
    // Normalised: the albedo at normal view is 1 (B_00 = albedo / (2 sqrt(pi))).
    EXPECT_NEAR(row(0) * 2 * std::sqrt(kPi), 1.0, 1e-9);
    if (a == 0) EXPECT_NEAR(row(sh_index(2, 0)), 2 * std::sqrt(5 / (4 * kPi)) / 8, 1e-9);  // clamped cosine
  }
}

TEST(GlossyBrdf, CookTorranceMatchesAnIndependentQuadrature) {
  // The same integral by a different rule: 200000 spherical-Fibonacci points, equal weights.
  const Brdf brdf{BrdfModel::cook_torrance, 0.3, 0.04};
  const int g = 4, order = 4;
  const Eigen::MatrixXd b = brdf_matrix(brdf, order, g, 2);
  const int points = 200000;
  std::vector<double> y(16);
  for (int i : {0, 5, 10, 15}) {
    const Vec3<double> v = glossy_view_direction<double>((i % g + 0.5) / g, (i / g + 0.5) / g);
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(16);
    for (int k = 0; k < points; ++k) {
      const double z = 1.0 - (k + 0.5) / points;
      const double phi = 2 * kPi * std::fmod(k * 0.61803398874989484820, 1.0), r = std::sqrt(1 - z * z);
      const Eigen::Vector3d s(r * std::cos(phi), r * std::sin(phi), z);
      const double f = brdf_value(brdf, v, s) * z;
      if (f == 0) continue;
      eval_sh<double>(order, s, y);
      for (int j = 0; j < 16; ++j) sum(j) += f * y[j];
    }
    sum *= 2 * kPi / points;
    for (int j = 0; j < 16; ++j) EXPECT_NEAR(b(i, j), sum(j), 2e-3 * sum.norm()) << "view " << i << " j " << j;
  }
}

TEST(GlossyBrdf, RingsTurnedEqualTheDirectIntegrals) {
  // The fast B (one integral per ring of the view map, turned by SH rotations about z)
  // against every row integrated at its own view, odd and even G, both BRDFs: they differ
  // by the quadrature's error on the turned integrand only.
  for (const Brdf brdf : {Brdf{BrdfModel::cook_torrance, 0.3, 0.04}, Brdf{BrdfModel::phong, 0.5, 1.0}})
    for (int g : {5, 8}) {
      const Eigen::MatrixXd fast = brdf_matrix(brdf, 4, g, 2, {64, 128});
      const Eigen::MatrixXd direct = brdf_matrix_direct(brdf, 4, g, 2, {64, 128});
      ASSERT_EQ(fast.rows(), g * g);
      EXPECT_LT((fast - direct).cwiseAbs().maxCoeff(), 2e-4 * direct.cwiseAbs().maxCoeff())
          << int(brdf.model) << " G " << g;
      EXPECT_GT(direct.cwiseAbs().maxCoeff(), 0.01);
    }
}

TEST(GlossyBrdf, BrdfValuesFollowTheirDefinitions) {
  const Eigen::Vector3d v = Eigen::Vector3d(0.3, -0.2, 0.9).normalized(), s = Eigen::Vector3d(-0.4, 0.1, 0.8).normalized();
  // Reciprocity holds for both models.
  for (BrdfModel model : {BrdfModel::phong, BrdfModel::cook_torrance}) {
    const Brdf brdf{model, 0.4, 0.5};
    EXPECT_NEAR(brdf_value(brdf, v, s), brdf_value(brdf, s, v), 1e-12 * brdf_value(brdf, v, s));
    EXPECT_EQ(brdf_value(brdf, v, Eigen::Vector3d(0.1, 0.2, -0.97).normalized()), 0.0);  // light below
    EXPECT_EQ(brdf_value(brdf, Eigen::Vector3d(0.1, 0.2, -0.97).normalized(), s), 0.0);  // view below
  }
  // Cook-Torrance at the mirror configuration: h = n, D = 1 / (pi m^2), G = 1, and Schlick's
  // F = f0 + (1 - f0)(1 - v.h)^5 with v.h = v_z.
  const Eigen::Vector3d mirror(-v.x(), -v.y(), v.z());
  const double m = 0.4, f = 0.5 + 0.5 * std::pow(1 - v.z(), 5);
  EXPECT_NEAR(brdf_value({BrdfModel::cook_torrance, m, 0.5}, v, mirror), f / (kPi * m * m) / (4 * v.z() * v.z()),
              1e-14);
}

TEST(GlossyBrdf, FactorsReconstructWithTheDroppedSingularValues) {
  const Eigen::MatrixXd b = brdf_matrix({BrdfModel::cook_torrance, 0.3, 1.0}, 4, 8, 2, {64, 128});
  const BrdfFactors f = factor_brdf(b, 3);
  EXPECT_LT((f.view_factors.transpose() * f.view_factors - Eigen::MatrixXd::Identity(3, 3)).norm(), 1e-12);
  const double dropped = std::sqrt(f.singular_values.tail(f.singular_values.size() - 3).squaredNorm());
  EXPECT_NEAR((b - f.view_factors * f.rows).norm(), dropped, 1e-9 * b.norm());
  for (int j = 0; j < 3; ++j) {
    Eigen::Index largest;
    f.view_factors.col(j).cwiseAbs().maxCoeff(&largest);
    EXPECT_GT(f.view_factors(largest, j), 0.0);
  }
}

// 3x3 grid in z = 0, normal +z; vertex 4 (0-based) is at the centre.
const std::string kPlane =
    "v -1 -1 0\nv 0 -1 0\nv 1 -1 0\nv -1 0 0\nv 0 0 0\nv 1 0 0\nv -1 1 0\nv 0 1 0\nv 1 1 0\n"
    "f 1 2 5\nf 1 5 4\nf 2 3 6\nf 2 6 5\nf 4 5 8\nf 4 8 7\nf 5 6 9\nf 5 9 8\n";

TEST(GlossyTransfer, OpenPlaneIsTheRotationIntoTheLocalFrame) {
  const fit::Mesh plane = from_obj("plane.obj", kPlane);
  const std::vector<Eigen::Matrix3d> frames = fit::vertex_frames(plane, plane);
  const auto scene = fit::build_scene(plane);
  GlossyTransferOptions o;
  o.order = 4;
  o.rays = 256;
  const Eigen::MatrixXd t = transfer_matrix(plane, 4, frames[4], o, 1e-4, scene.get());
  // T_jk = integral y_j(F^T s) y_k(s) ds by an exact quadrature.
  const SphereQuadrature q = sphere_quadrature(8);
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(16, 16);
  std::vector<double> yl(16), ys(16);
  for (std::size_t p = 0; p < q.directions.size(); ++p) {
    eval_sh<double>(4, (frames[4].transpose() * q.directions[p]).eval(), yl);
    eval_sh<double>(4, q.directions[p], ys);
    for (int j = 0; j < 16; ++j)
      for (int k = 0; k < 16; ++k) expected(j, k) += q.weights[p] * yl[j] * ys[k];
  }
  EXPECT_LT((t - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((t - Eigen::MatrixXd::Identity(16, 16)).norm(), 0.1);  // the frame's tangent is not +x
}

TEST(GlossyTransfer, SquareRoofMatchesAnalyticVisibility) {
  // A vertex at the origin of a 2 x 2 floor (normal +z) under a 2 x 2 roof at height 1
  // facing down: a direction s is blocked when it meets |x|, |y| <= 1 at z = 1. Reference:
  // a 400 x 800 product rule on the upper hemisphere with that visibility.
  const std::string mesh =
      "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 0 0\n"
      "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
      "f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 6 8 7\nf 6 9 8\n";
  const fit::Mesh m = from_obj("roof.obj", mesh);
  const std::size_t centre = 4;
  ASSERT_NEAR(m.positions[centre].norm(), 0.0, 0.0);
  const std::vector<Eigen::Matrix3d> frames = fit::vertex_frames(m, m);
  const Eigen::Matrix3d f = frames[centre];
  const auto scene = fit::build_scene(m);
  GlossyTransferOptions o;
  o.order = 3;
  o.rays = 65536;
  const Eigen::MatrixXd t = transfer_matrix(m, centre, f, o, 1e-6, scene.get());
  const Eigen::MatrixXd d = transfer_matrix(m, centre, f, o, 1e-6, nullptr);
  const GaussLegendre gl = gauss_legendre(400);
  Eigen::MatrixXd blocked = Eigen::MatrixXd::Zero(9, 9);
  std::vector<double> yl(9), ys(9);
  for (int i = 0; i < 400; ++i) {
    const double z = 0.5 * (gl.nodes[i] + 1), r = std::sqrt(1 - z * z);
    for (int k = 0; k < 800; ++k) {
      const double phi = 2 * kPi * (k + 0.5) / 800;
      const Eigen::Vector3d s(r * std::cos(phi), r * std::sin(phi), z);
      if (std::abs(s.x() / z) > 1 || std::abs(s.y() / z) > 1) continue;
      const double w = 0.5 * gl.weights[i] * 2 * kPi / 800;
      eval_sh<double>(3, (f.transpose() * s).eval(), yl);
      eval_sh<double>(3, s, ys);
      for (int a = 0; a < 9; ++a)
        for (int c = 0; c < 9; ++c) blocked(a, c) += w * yl[a] * ys[c];
    }
  }
  // The roof covers a solid angle of 2 pi / 3; 65536 stratified rays err well below 1e-2.
  EXPECT_LT(((d - t) - blocked).cwiseAbs().maxCoeff(), 1e-2);
  EXPECT_GT(blocked.cwiseAbs().maxCoeff(), 0.3);
}

TEST(GlossyTransfer, RowsRotateWithARigidlyRotatedMesh) {
  // Unshadowed, M' of a rotated mesh is M' of the rest mesh with each row rotated as an
  // SH vector in the scene frame (the frames turn with the mesh).
  const fit::Mesh rest = fit::load_obj(std::string(SHTOOL_SOURCE_DIR) + "/data/spot.obj");
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  fit::Mesh turned = rest;
  for (auto& p : turned.positions) p = r * p;
  for (auto& n : turned.normals) n = r * n;
  const Eigen::MatrixXd b = brdf_matrix({BrdfModel::cook_torrance, 0.3, 1.0}, 4, 8, 2, {64, 128});
  const BrdfFactors factors = factor_brdf(b, 3);
  GlossyTransferOptions o;
  o.order = 4;
  o.shadowed = false;
  const GlossyTransfer a = glossy_transfer(rest, fit::vertex_frames(rest, rest), factors.rows,
                                           b.transpose() * b, o);
  const GlossyTransfer c = glossy_transfer(turned, fit::vertex_frames(turned, turned), factors.rows,
                                           b.transpose() * b, o);
  ShRotation<double> rotation(4, nullptr);
  ASSERT_TRUE(rotation.set(r, RotationMethod::reference));
  std::vector<double> expected(16);
  double worst = 0;
  for (std::size_t row = 0; row < a.rows.size() / 16; row += 37) {
    rotation.apply(std::span<const double>(a.rows.data() + row * 16, 16), expected);
    for (int k = 0; k < 16; ++k) worst = std::max(worst, std::abs(c.rows[row * 16 + k] - expected[k]));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(a.exit_norm2, c.exit_norm2, 1e-9 * a.exit_norm2);
}

TEST(GlossyTransfer, BytesDoNotDependOnTheThreadCount) {
  const fit::Mesh spot = fit::load_obj(std::string(SHTOOL_SOURCE_DIR) + "/data/spot.obj");
  const Eigen::MatrixXd b = brdf_matrix({BrdfModel::phong, 0.3, 1.0}, 3, 8, 1, {32, 64});
  const BrdfFactors factors = factor_brdf(b, 3);
  GlossyTransferOptions o;
  o.order = 3;
  o.rays = 64;
  o.threads = 1;
  const auto frames = fit::vertex_frames(spot, spot);
  const GlossyTransfer one = glossy_transfer(spot, frames, factors.rows, b.transpose() * b, o);
  o.threads = 2;
  const GlossyTransfer two = glossy_transfer(spot, frames, factors.rows, b.transpose() * b, o);
  EXPECT_EQ(one.rows, two.rows);
  EXPECT_EQ(one.exit_norm2, two.exit_norm2);
  // Shadowing removes energy: some rows differ from the unshadowed ones.
  o.shadowed = false;
  const GlossyTransfer open = glossy_transfer(spot, frames, factors.rows, b.transpose() * b, o);
  EXPECT_LT(one.exit_norm2, open.exit_norm2);
}

}  // namespace
