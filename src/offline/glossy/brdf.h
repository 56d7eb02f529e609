// The BRDF side of glossy LDPRT ([4] Sec. 3.2, Eq. 14-15): a BRDF b(v, s), its matrix B
// over the view samples of the u(v) map against the SH lighting basis, and B's truncated
// SVD. Everything is in the local frame of a surface point: z the normal, v and s unit
// vectors with z >= 0 (view and light directions, both pointing away from the surface).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/enum_names.h"

namespace shtool::glossy {

enum class BrdfModel { phong, cook_torrance };
const EnumNames<BrdfModel>& brdf_model_names();

struct Brdf {
  BrdfModel model = BrdfModel::cook_torrance;
  // Beckmann roughness m (the RMS microfacet slope): Cook-Torrance's D is Beckmann's with
  // this m; Phong's exponent is 2 / m^2 - 2, the exponent whose lobe matches Beckmann's
  // near its peak (Walter et al. 2007, Sec. 5.2). [4] Fig. 4 uses Cook-Torrance at 0.3.
  double roughness = 0.3;
  // Schlick's Fresnel reflectance at normal incidence (Cook-Torrance only): 1 leaves the
  // lobe without Fresnel (a perfect conductor), 0.04 is a typical dielectric.
  double f0 = 1.0;
};

// Phong exponent of a roughness (see Brdf::roughness).
double phong_exponent(double roughness);

// b(v, s) (1/sr), 0 when either direction is below the horizon.
//   phong:         (a + 2) / (2 pi) max(r . s, 0)^a, r = 2 (n . v) n - v the mirror
//                  direction, a = phong_exponent(m): normalised so that the albedo at normal
//                  view is exactly 1;
//   cook_torrance: D G F / (4 (n . s)(n . v)), D Beckmann, G Cook-Torrance's V-groove
//                  shadowing min(1, 2 (n.h)(n.v)/(v.h), 2 (n.h)(n.s)/(v.h)), F Schlick's.
double brdf_value(const Brdf& brdf, const Eigen::Vector3d& v, const Eigen::Vector3d& s);

// Quadrature of Eq. 14 over the hemisphere: Gauss-Legendre in cos(theta) with
// `cos_nodes` nodes times `azimuths` equally spaced azimuths.
struct HemisphereRule {
  int cos_nodes = 128;
  int azimuths = 256;
};

// [4] Eq. 14: B_ij = integral over z >= 0 of b(v_i, s) y_j(s) s_z ds for the G^2 view
// samples v_i (i = b * G + a: the centre of texel (a, b) of the u(v) map,
// shtool/glossy.h) and the order^2 SH basis functions. Both BRDFs are isotropic
// (b(R v, R s) = b(v, s) for R about the normal), and the concentric map puts the texel
// centres of each square ring of the map on one circle of the hemisphere: B is
// integrated once per ring, at azimuth 0, and each texel's row is that row turned to the
// texel's azimuth by the exact SH rotation about z. G / 2 rings (rounded up) instead of
// G^2 integrals. Rows in parallel on `threads`.
Eigen::MatrixXd brdf_matrix(const Brdf& brdf, int order, int view_resolution, int threads,
                            const HemisphereRule& rule = {});

// The reference: every row integrated at its own view direction. Agrees with brdf_matrix
// to the quadrature's error on the turned integrand (tests/offline/test_glossy.cpp).
Eigen::MatrixXd brdf_matrix_direct(const Brdf& brdf, int order, int view_resolution, int threads,
                                   const HemisphereRule& rule = {});

// B ~ U~ Sigma~ V~ with the `terms` largest singular values ([4] Eq. 14-15).
struct BrdfFactors {
  Eigen::MatrixXd view_factors;  // U~: G^2 x n_b, orthonormal columns (u(v) at the texel centres)
  Eigen::MatrixXd rows;          // Sigma~ V~: n_b x order^2; M' = rows * T
  Eigen::VectorXd singular_values;  // all of them, descending
};

// Signs are fixed so that each column of U~ has its largest-magnitude entry positive
// (the SVD leaves them free). Precondition (std::invalid_argument otherwise): 1 <= terms
// <= min(rows, columns) of b.
BrdfFactors factor_brdf(const Eigen::MatrixXd& b, int terms);

}  // namespace shtool::glossy
