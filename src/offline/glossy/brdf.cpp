#include "glossy/brdf.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/SVD>

#include "common/parallel_for.h"
#include "shtool/glossy.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool::glossy {

const std::vector<std::pair<std::string, BrdfModel>>& brdf_model_names() {
  static const std::vector<std::pair<std::string, BrdfModel>> names = {{"phong", BrdfModel::phong},
                                                                       {"cook-torrance", BrdfModel::cook_torrance}};
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

Eigen::MatrixXd brdf_matrix(const Brdf& brdf, int order, int view_resolution, int threads,
                            const HemisphereRule& rule) {
  const int n2 = sh_count(order);
  // Light directions and weights (sum 2 pi) with each one's SH values times s_z.
  const GaussLegendre gl = gauss_legendre(rule.cos_nodes);
  const std::size_t points = std::size_t(rule.cos_nodes) * rule.azimuths;
  std::vector<Eigen::Vector3d> dirs(points);
  Eigen::MatrixXd weighted(points, n2);
  std::vector<double> y(n2);
  for (int i = 0; i < rule.cos_nodes; ++i) {
    const double z = 0.5 * (gl.nodes[i] + 1.0), w = 0.5 * gl.weights[i] * 2.0 * std::numbers::pi / rule.azimuths;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    for (int k = 0; k < rule.azimuths; ++k) {
      const double phi = 2.0 * std::numbers::pi * (k + 0.5) / rule.azimuths;
      const std::size_t p = std::size_t(i) * rule.azimuths + k;
      dirs[p] = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
      eval_sh<double>(order, dirs[p], y);
      for (int j = 0; j < n2; ++j) weighted(p, j) = w * z * y[j];
    }
  }
  const int g = view_resolution;
  Eigen::MatrixXd b(std::size_t(g) * g, n2);
  parallel_for(std::size_t(g) * g, threads, [&](std::size_t row) {
    const int a = static_cast<int>(row % g), bb = static_cast<int>(row / g);
    const Eigen::Vector3d v = glossy_view_direction<double>((a + 0.5) / g, (bb + 0.5) / g);
    Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(n2);
    for (std::size_t p = 0; p < points; ++p) {
      const double f = brdf_value(brdf, v, dirs[p]);
      if (f != 0.0) sum += f * weighted.row(p);
    }
    b.row(row) = sum;
  });
  return b;
}

BrdfFactors factor_brdf(const Eigen::MatrixXd& b, int terms) {
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
