#include "view/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/input_error.h"

namespace shtool::view {

void check_view_options(int width, int height, double fov_degrees, double exposure) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InputError("--width and --height must be between 1 and 16384, got " + std::to_string(width) + " x " +
                     std::to_string(height));
  // Narrower than 0.01 degrees, the rays' spread vanishes in Embree's float arithmetic.
  if (!(fov_degrees >= 0.01 && fov_degrees <= 179)) throw InputError("--fov must be between 0.01 and 179 degrees");
  if (!(std::abs(exposure) <= 64)) throw InputError("--exposure must be between -64 and 64");
}

void check_camera(const std::optional<Camera>& camera) {
  if (!camera) return;
  using Vec = Eigen::Vector3d;
  const Vec eye = as_vector(camera->eye), target = as_vector(camera->target), up = as_vector(camera->up);
  // Embree traces in float and refuses (asserts on) a ray whose origin lies beyond about
  // 1.8e18; the bound of mesh coordinates keeps every ray well inside it.
  for (const Vec& v : {eye, target, up})
    if (!v.allFinite() || v.cwiseAbs().maxCoeff() > fit::kMaxCoordinate)
      throw InputError(
          "--camera: every coordinate must be a finite number of magnitude at most 1e15, the range "
          "single-precision ray tracing reaches");
  if ((target - eye).norm() == 0 || (target - eye).normalized().cross(up).norm() < 1e-9)
    throw InputError("--camera: eye and target must differ and up must not be parallel to the view");
}

MeshBounds mesh_bounds(const fit::Mesh& mesh) {
  using Vec = Eigen::Vector3d;
  Vec lo = mesh.positions.front(), hi = lo;
  for (const Vec& p : mesh.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec centre = 0.5 * (lo + hi);
  double radius = 0;
  for (const Vec& p : mesh.positions) radius = std::max(radius, (p - centre).norm());
  return {lo, hi, centre, radius};
}

Camera frame_mesh(const fit::Mesh& mesh, double fov_degrees, double aspect) {
  using Vec = Eigen::Vector3d;
  const MeshBounds bounds = mesh_bounds(mesh);
  const Vec& centre = bounds.centre;
  const double radius = bounds.radius;
  const double half = 0.5 * fov_degrees * std::numbers::pi / 180.0;
  const double narrow = aspect < 1 ? std::atan(std::tan(half) * aspect) : half;
  const double distance = 1.05 * radius / std::sin(narrow);
  // 35 degrees round from the front towards the model's left (the viewer's right), 20 up.
  const double azimuth = 35 * std::numbers::pi / 180, elevation = 20 * std::numbers::pi / 180;
  const Vec front(mesh.front.x(), mesh.front.y(), 0);
  const Vec side = Vec::UnitZ().cross(front);
  const Vec toward_eye = std::cos(elevation) * (std::cos(azimuth) * front + std::sin(azimuth) * side) +
                         std::sin(elevation) * Vec::UnitZ();
  const Vec eye = centre + distance * toward_eye;
  return {{eye.x(), eye.y(), eye.z()}, {centre.x(), centre.y(), centre.z()}, {0, 0, 1}};
}

}  // namespace shtool::view
