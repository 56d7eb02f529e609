#include "glossy/brdf.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "common/parallel_for.h"
#include "shtool/glossy.h"
#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool::glossy {

const EnumNames<BrdfModel>& brdf_model_names() {
  using enum BrdfModel;
  static const EnumNames<BrdfModel> names = {{"phong", phong}, {"cook-torrance", cook_torrance}};
  return names;
}

double phong_exponent(double roughness) { return 2.0 / (roughness * roughness) - 2.0; }

double brdf_value(const Brdf& brdf, const Eigen::Vector3d& v, const Eigen::Vector3d& s) {
  const double nv = v.z(), ns = s.z();
  if (!(nv > 0) || !(ns > 0)) return 0.0;
  if (brdf.model == BrdfModel::phong) {
    const double a = phong_exponent(brdf.roughness);
    const Eigen::Vector3d mirror(-v.x(), -v.y(), v.z());  // 2 (n.v) n - v with n = z
    const double c = mirror.dot(s);
    return c > 0 ? (a + 2.0) / (2.0 * std::numbers::pi) * std::pow(c, a) : 0.0;
  }
  const Eigen::Vector3d h = (v + s).normalized();
  const double nh = h.z(), vh = v.dot(h);
  if (!(nh > 0) || !(vh > 0)) return 0.0;
  const double m2 = brdf.roughness * brdf.roughness;
  const double cos2 = nh * nh;
  const double tan2 = (1.0 - cos2) / cos2;
  const double d = std::exp(-tan2 / m2) / (std::numbers::pi * m2 * cos2 * cos2);
  const double g = std::min({1.0, 2.0 * nh * nv / vh, 2.0 * nh * ns / vh});
  const double f = brdf.f0 + (1.0 - brdf.f0) * std::pow(1.0 - vh, 5);
  return d * g * f / (4.0 * ns * nv);
}

namespace {

// The quadrature's light directions with their SH values times s_z and the weight.
struct HemispherePoints {
  std::vector<Eigen::Vector3d> dirs;
  Eigen::MatrixXd weighted;  // points x order^2
};

HemispherePoints hemisphere_points(int order, const HemisphereRule& rule) {
  const int n2 = sh_count(order);
  const GaussLegendre gl = gauss_legendre(rule.cos_nodes);
  const std::size_t points = std::size_t(rule.cos_nodes) * rule.azimuths;
  HemispherePoints h{std::vector<Eigen::Vector3d>(points), Eigen::MatrixXd(points, n2)};
  std::vector<double> y(n2);
  for (int i = 0; i < rule.cos_nodes; ++i) {
    const double z = 0.5 * (gl.nodes[i] + 1.0), w = 0.5 * gl.weights[i] * 2.0 * std::numbers::pi / rule.azimuths;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    for (int k = 0; k < rule.azimuths; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + 0.5) / rule.azimuths;
      const std::size_t p = std::size_t(i) * rule.azimuths + k;
      h.dirs[p] = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
      eval_sh<double>(order, h.dirs[p], y);
      for (int j = 0; j < n2; ++j) h.weighted(p, j) = w * z * y[j];
    }
  }
  return h;
}

Eigen::RowVectorXd brdf_row(const Brdf& brdf, const Eigen::Vector3d& v, const HemispherePoints& h) {
  Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(h.weighted.cols());
  for (std::size_t p = 0; p < h.dirs.size(); ++p) {
    const double f = brdf_value(brdf, v, h.dirs[p]);
    if (f != 0.0) sum += f * h.weighted.row(p);
  }
  return sum;
}

Eigen::Vector3d texel_view(int a, int b, int g) {
  return glossy_view_direction<double>((a + 0.5) / g, (b + 0.5) / g);
}

}  // namespace

Eigen::MatrixXd brdf_matrix_direct(const Brdf& brdf, int order, int view_resolution, int threads,
                                   const HemisphereRule& rule) {
  const HemispherePoints h = hemisphere_points(order, rule);
  const int g = view_resolution;
  Eigen::MatrixXd b(std::size_t(g) * g, sh_count(order));
  parallel_for(std::size_t(g) * g, threads, [&](std::size_t row) {
    b.row(row) = brdf_row(brdf, texel_view(static_cast<int>(row % g), static_cast<int>(row / g), g), h);
  });
  return b;
}

Eigen::MatrixXd brdf_matrix(const Brdf& brdf, int order, int view_resolution, int threads,
                            const HemisphereRule& rule) {
  const HemispherePoints h = hemisphere_points(order, rule);
  const int g = view_resolution, n2 = sh_count(order);
  // Ring k holds the texels with max(|a - c|, |b - c|) = k + 1/2 around the centre
  // c = (G - 1) / 2 (or k for odd G, ring 0 the centre texel): concentric radius
  // rho = (2k + 1) / G (2k / G for odd G), polar z = 1 - rho^2.
  const int rings = (g + 1) / 2;
  auto ring_of = [g](int a, int b) {
    const int da = std::abs(2 * a + 1 - g), db = std::abs(2 * b + 1 - g);  // 2 |a + 1/2 - G/2|
    return std::max(da, db);  // odd G: 0, 2, 4...; even G: 1, 3, 5...
  };
  Eigen::MatrixXd base(rings, n2);
  parallel_for(static_cast<std::size_t>(rings), threads, [&](std::size_t k) {
    const int twice = static_cast<int>(2 * k) + (g % 2 == 0 ? 1 : 0);
    const double rho = static_cast<double>(twice) / g, z = 1.0 - rho * rho;
    base.row(k) = brdf_row(brdf, Eigen::Vector3d(std::sqrt(std::max(0.0, 1.0 - z * z)), 0.0, z), h);
  });
  Eigen::MatrixXd b(std::size_t(g) * g, n2);
  parallel_for(std::size_t(g) * g, threads, [&](std::size_t row) {
    const int a = static_cast<int>(row % g), bb = static_cast<int>(row / g);
    const Eigen::Vector3d v = texel_view(a, bb, g);
    const int k = ring_of(a, bb) / 2;
    // g_i(s) = b(v_i, s) s_z is g_0 turned by R_z(phi_i): its row is the ring's, rotated.
    const double phi = std::atan2(v.y(), v.x());
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    ShRotation<double> rotation(order, nullptr);
    if (!rotation.set(turn, RotationMethod::reference)) throw std::logic_error("the reference rotation needs no table");
    std::vector<double> in(n2), out(n2);
    for (int j = 0; j < n2; ++j) in[j] = base(k, j);
    rotation.apply(in, out);
    for (int j = 0; j < n2; ++j) b(row, j) = out[j];
  });
  return b;
}

BrdfFactors factor_brdf(const Eigen::MatrixXd& b, int terms) {
  if (terms < 1 || terms > std::min(b.rows(), b.cols()))
    throw std::invalid_argument("factor_brdf: " + std::to_string(terms) + " terms of a " + std::to_string(b.rows()) +
                                " x " + std::to_string(b.cols()) + " matrix");
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(b, Eigen::ComputeThinU | Eigen::ComputeThinV);
  BrdfFactors f;
  f.singular_values = svd.singularValues();
  f.view_factors = svd.matrixU().leftCols(terms);
  f.rows = f.singular_values.head(terms).asDiagonal() * svd.matrixV().leftCols(terms).transpose();
  for (int j = 0; j < terms; ++j) {
    Eigen::Index largest;
    f.view_factors.col(j).cwiseAbs().maxCoeff(&largest);
    if (f.view_factors(largest, j) < 0) {
      f.view_factors.col(j) *= -1.0;
      f.rows.row(j) *= -1.0;
    }
  }
  return f;
}

}  // namespace shtool::glossy
