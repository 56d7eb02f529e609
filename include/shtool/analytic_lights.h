// Analytic lights as radiance SH coefficients (docs/lighting.md). Each function adds one
// light to coefficients[i * channels + c] (order N = sqrt(coefficients.size() / channels)),
// `color` holding `channels` values. Directions are unit vectors in shtool's frame.
//   directional  a delta of integral `color` along d: color y_i(d);
//   cone         radiance `color` inside the cone of half-angle a around d (a disk or
//                sphere light seen from its centre): the ZH of the spherical cap,
//                2 pi integral_{cos a}^1 P_l(z) dz = 2 pi (P_{l-1} - P_{l+1})(cos a) / (2l+1)
//                times y_l^m(d) (1 - cos a for l = 0); it tends to color * solid angle
//                * y_i(d), the directional light, as a -> 0;
//   hemisphere   `sky` on the side of d, `ground` on the other (a cone of 90 degrees
//                over a constant);
//   constant     `color` everywhere: c_00 = color sqrt(4 pi).
// Each has a float and a double overload (the cap's zonal coefficients are formed in
// double either way).
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

namespace shtool {

void add_directional_light(const Eigen::Vector3d& direction, std::span<const double> color, int channels,
                           std::span<double> coefficients);
void add_directional_light(const Eigen::Vector3f& direction, std::span<const float> color, int channels,
                           std::span<float> coefficients);
void add_cone_light(const Eigen::Vector3d& direction, double half_angle, std::span<const double> color,
                    int channels, std::span<double> coefficients);
void add_cone_light(const Eigen::Vector3f& direction, float half_angle, std::span<const float> color,
                    int channels, std::span<float> coefficients);
void add_hemisphere_light(const Eigen::Vector3d& direction, std::span<const double> sky,
                          std::span<const double> ground, int channels, std::span<double> coefficients);
void add_hemisphere_light(const Eigen::Vector3f& direction, std::span<const float> sky,
                          std::span<const float> ground, int channels, std::span<float> coefficients);
void add_constant_light(std::span<const double> color, int channels, std::span<double> coefficients);
void add_constant_light(std::span<const float> color, int channels, std::span<float> coefficients);

// The zonal coefficients 2 pi integral_{cos a}^1 P_l(z) dz, l = 0..order-1, of a cap of
// half-angle a (radiance 1 inside).
std::vector<double> cap_zonal_coefficients(double half_angle, int order);

}  // namespace shtool
