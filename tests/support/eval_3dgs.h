// The 3D Gaussian Splatting reference implementation's eval_sh (graphdeco-inria,
// utils/sh_utils.py) for one channel, degree <= 3: the independent colour model the splat
// tests compare shtool's transforms against. sh[k], k = 0..(deg+1)^2-1, k = 0 the DC; the
// colour's clamp(eval + 0.5) is left out (it hides nothing at the tests' values).
#pragma once

#include <string>

#include <Eigen/Core>

namespace shtool::test {

inline double eval_3dgs(int deg, const double* sh, const Eigen::Vector3d& d) {
  constexpr double C0 = 0.28209479177387814, C1 = 0.4886025119029199;
  constexpr double C2[5] = {1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792,
                            0.5462742152960396};
  constexpr double C3[7] = {-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154,
                            -0.4570457994644658, 1.445305721320277, -0.5900435899266435};
  double r = C0 * sh[0];
  if (deg < 1) return r;
  const double x = d.x(), y = d.y(), z = d.z();
  r += -C1 * y * sh[1] + C1 * z * sh[2] - C1 * x * sh[3];
  if (deg < 2) return r;
  const double xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
  r += C2[0] * xy * sh[4] + C2[1] * yz * sh[5] + C2[2] * (2 * zz - xx - yy) * sh[6] + C2[3] * xz * sh[7] +
       C2[4] * (xx - yy) * sh[8];
  if (deg < 3) return r;
  r += C3[0] * y * (3 * xx - yy) * sh[9] + C3[1] * xy * z * sh[10] + C3[2] * y * (4 * zz - xx - yy) * sh[11] +
       C3[3] * z * (2 * zz - 3 * xx - 3 * yy) * sh[12] + C3[4] * x * (4 * zz - xx - yy) * sh[13] +
       C3[5] * z * (xx - yy) * sh[14] + C3[6] * x * (xx - 3 * yy) * sh[15];
  return r;
}

// The reference implementation's PLY properties, all float: x y z nx ny nz f_dc_0..2
// f_rest_* (channel major) opacity scale_0..2 rot_0..3, one "property" line each.
inline std::string ply_3dgs_properties(int deg) {
  const int rest = (deg + 1) * (deg + 1) - 1;
  std::string h;
  for (const char* n : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    h += std::string("property float ") + n + "\n";
  for (int k = 0; k < 3 * rest; ++k) h += "property float f_rest_" + std::to_string(k) + "\n";
  for (const char* n : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    h += std::string("property float ") + n + "\n";
  return h;
}

}  // namespace shtool::test
