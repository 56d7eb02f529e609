// A 3D Gaussian Splatting scene in memory, whatever file it came from (docs/splats.md):
// the values 3DGS trains and its PLY stores, one array per attribute. Each format's
// reader decodes into it and each writer encodes from it (splat_ply.h, spz.h,
// splat_gltf.h); frames are turned by transform_splat_scene.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "shtool/orthogonal_map.h"

namespace shtool::interop {

// The colour space of the colours the SH reconstruct (KHR_gaussian_splatting's
// `colorSpace`): 3DGS trains in BT.709 sRGB, display-referred, the only one PLY and spz
// hold.
enum class SplatColourSpace { srgb_rec709_display, lin_rec709_display };
// The extension's name of a colour space ("srgb_rec709_display"); parse: null when unknown.
const char* splat_colour_space_name(SplatColourSpace space);
std::optional<SplatColourSpace> parse_splat_colour_space(std::string_view name);

struct SplatScene {
  std::size_t count = 0;
  int degree = 0;                // SH degree 0..3
  std::vector<float> position;   // 3 per splat
  std::vector<float> log_scale;  // 3 per splat: sigma = exp(log_scale)
  std::vector<float> rotation;   // 4 per splat, w x y z, not necessarily unit
  std::vector<float> opacity;    // 1 per splat, logit: alpha = sigmoid(opacity)
  // 3 (deg+1)^2 per splat: coefficient-major, RGB inner (sh[i*stride + 3*k + c],
  // k = l(l+1)+m, k = 0 the DC), 3DGS's basis (Condon-Shortley phase), colour =
  // 0.5 + sum_k sh_k y_k(d).
  std::vector<float> sh;
  SplatColourSpace colour_space = SplatColourSpace::srgb_rec709_display;

  std::size_t sh_stride() const { return 3 * static_cast<std::size_t>((degree + 1) * (degree + 1)); }
  void resize(std::size_t n, int deg) {
    count = n;
    degree = deg;
    position.assign(3 * n, 0.0f);
    log_scale.assign(3 * n, 0.0f);
    rotation.assign(4 * n, 0.0f);
    opacity.assign(n, 0.0f);
    sh.assign(sh_stride() * n, 0.0f);
  }
  // Keeps bands 0..deg (the L2-nearest function of that degree over the sphere, the
  // basis being orthonormal) or pads with zero bands.
  void set_degree(int deg);
};

enum class SplatFormat { ply, spz, gltf, glb };
// By extension (.ply, .spz, .gltf, .glb, any case); InputError naming `what` otherwise.
SplatFormat splat_format_of(const std::filesystem::path& path, const std::string& what);
const char* splat_format_name(SplatFormat format);

// The first splat value that is not finite, in splat order: the splat and what the value
// is ("position", "scale", "rotation", "opacity", "SH colour"); nullopt when all are.
struct NonFiniteValue {
  std::size_t splat = 0;
  const char* what = "";
};
std::optional<NonFiniteValue> first_non_finite(const SplatScene& scene);

// InputError naming `name` when a value that every format needs finite is not (the
// first one found, in splat order).
void check_scene_finite(const SplatScene& scene, const std::string& name);

// A splat's rotation (w x y z, any length) divided by its length, computed in double:
// in float, components past 1.8e19 square to infinity and those below 1e-19 lose their
// squares to underflow. A zero quaternion gives the identity.
std::array<float, 4> unit_rotation(const float* wxyz);

// One orthogonal map of SH colours for many splats (a whole scene turned by one matrix):
// the reference rotation's band blocks, OrthogonalMap's own, applied to kLanes splats at
// once in the lanes of SIMD vectors. Each coefficient is the same products summed in the
// same order as OrthogonalMap::apply(in, out, 3) makes it, so the results are its bits; the odd
// bands are negated for a reflection.
class SplatShLanes {
 public:
  static constexpr int kLanes = 8;
  explicit SplatShLanes(const OrthogonalMap& map);
  int order() const { return order_; }
  // The coefficients of bands 1.. (k >= 1) of kLanes splats, channel-major as PLY's
  // f_rest: value j = c (N^2 - 1) + k - 1 of lane s at [j kLanes + s]; in and out of
  // 3 (N^2 - 1) kLanes values, not overlapping. Band 0 is left to the caller (it stays).
  void apply(const double* in, double* out) const;

 private:
  int order_;
  bool reflects_;
  std::vector<double> blocks_;  // band l's (2l+1)^2 values, row-major, from l(4l^2-1)/3
};

// What p -> s M p + t (M orthogonal, det +1 or -1) does to one splat's values, each
// computed in double: every path of transform-splats (PLY rewritten in place or streamed,
// scenes of any format) and Python's transform_splat_arrays apply it, so they agree to
// the bit. Orientations turn by the proper part P = det(M) M, since the covariance
// M Sigma M^T = P Sigma P^T (q -> q_P q, the stored length kept), or by the user's own
// quaternion when M was made from one (no round trip through the matrix); normals turn
// by M; log-scales shift by log s. Positions stay bit for bit (signed zeros included)
// when the map is the identity.
struct SplatMotion {
  SplatMotion(const Eigen::Matrix3d& m, double scale, const Eigen::Vector3d& t,
              const std::optional<std::array<double, 4>>& quaternion = std::nullopt);

  Eigen::Vector3d position(const Eigen::Vector3d& p) const { return moves ? Eigen::Vector3d(scale * (m * p) + t) : p; }
  Eigen::Vector3d normal(const Eigen::Vector3d& n) const { return m * n; }
  Eigen::Quaterniond orientation(const Eigen::Quaterniond& q) const { return turn * q; }  // turn is unit
  double log_scale(double v) const { return log_s != 0 ? v + log_s : v; }                 // -0 kept at s = 1

  Eigen::Matrix3d m;
  double scale;
  Eigen::Vector3d t;
  Eigen::Quaterniond turn;
  double log_s;  // log scale
  bool moves;    // positions change
};

// SplatMotion(M, s, t) on every splat of a scene, its SH colours by the orthogonal map of
// M (shtool/orthogonal_map.h), so that a splat seen along d before looks the same along
// M d after; InputError when M is not orthogonal to 1e-6.
void transform_splat_scene(SplatScene& scene, const Eigen::Matrix3d& m, double scale, const Eigen::Vector3d& t,
                           int threads);

}  // namespace shtool::interop
