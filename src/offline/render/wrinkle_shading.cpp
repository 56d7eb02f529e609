#include "render/wrinkle_shading.h"

#include <charconv>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "common/input_error.h"
#include "common/input_file.h"
#include "common/parallel_for.h"

namespace shtool::render {
namespace {

// A number with the digits that tell it from its neighbours (1.0000001 against a bound
// of 1): the shortest text that reads back as the same double.
std::string exact_text(double v) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, v).ptr;
  return std::string(text, end);
}

}  // namespace

GrooveCoordinates read_groove_coordinates(const std::filesystem::path& path, const fit::Mesh& mesh,
                                          double max_depth) {
  const std::string what = "--wrinkle-map " + path.string();
  const std::size_t v = mesh.positions.size();
  const nlohmann::json doc = read_json_input(path, "--wrinkle-map");
  GrooveCoordinates out;
  for (const char* key : {"x", "d"}) {
    if (!doc.is_object() || !doc.contains(key) || !doc[key].is_array() || doc[key].size() != v)
      throw InputError(what + ": expected {\"x\": [...], \"d\": [...]} with " + std::to_string(v) +
                       " numbers each, one per mesh vertex; '" + key + "' " +
                       (doc.is_object() && doc.contains(key) && doc[key].is_array()
                            ? "has " + std::to_string(doc[key].size())
                            : std::string("is missing or not an array")));
    std::vector<double>& values = key[0] == 'x' ? out.x : out.d;
    values.resize(v);
    for (std::size_t k = 0; k < v; ++k) {
      const nlohmann::json& e = doc[key][k];
      if (!e.is_number()) throw InputError(what + ": " + key + "[" + std::to_string(k) + "] is not a number");
      values[k] = e.get<double>();
    }
  }
  for (std::size_t k = 0; k < v; ++k) {
    if (!std::isfinite(out.x[k])) throw InputError(what + ": x[" + std::to_string(k) + "] is not finite");
    // The map holds depths 0..max_depth only; shading a deeper groove as the deepest one
    // would hide a mistake in the coordinates.
    if (!(out.d[k] >= 0 && out.d[k] <= max_depth))
      throw InputError(what + ": d[" + std::to_string(k) + "] = " + exact_text(out.d[k]) +
                       " is outside the map's depths [0, " + exact_text(max_depth) + "]");
  }
  return out;
}

std::vector<Eigen::Matrix3d> groove_frames(const fit::Mesh& mesh, const std::vector<double>& x) {
  const std::size_t v = mesh.positions.size();
  std::vector<Eigen::Vector3d> gradient(v, Eigen::Vector3d::Zero());
  std::vector<double> scale(v, 0.0);  // sum of |weighted gradient|: what "vanishes" is relative to
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d e1 = mesh.positions[t[1]] - mesh.positions[t[0]];
    const Eigen::Vector3d e2 = mesh.positions[t[2]] - mesh.positions[t[0]];
    const Eigen::Vector3d nrm = e1.cross(e2);
    const double n2 = nrm.squaredNorm();
    if (!(n2 > 0)) continue;
    for (int corner = 0; corner < 3; ++corner) {
      const int a = t[corner];
      // x relative to this corner, the short way round the period.
      auto rel = [&](int b) {
        const double dx = x[b] - x[a];
        return dx - std::floor(dx + 0.5);
      };
      const double dx1 = rel(t[1]) - rel(t[0]), dx2 = rel(t[2]) - rel(t[0]);
      // The linear function with g . e1 = dx1, g . e2 = dx2 in the triangle's plane.
      const Eigen::Vector3d g = (dx2 * nrm.cross(e1) + dx1 * e2.cross(nrm)) / n2;
      // Weighted by area (|nrm| / 2, the half dropped): large triangles speak louder.
      const double area = std::sqrt(n2);
      gradient[a] += area * g;
      scale[a] += area * g.norm();
    }
  }
  std::vector<Eigen::Matrix3d> frames(v);
  for (std::size_t k = 0; k < v; ++k) {
    const Eigen::Vector3d n = mesh.normals[k];
    const Eigen::Vector3d across = gradient[k] - n * n.dot(gradient[k]);
    // Relative threshold: a gradient cancelled to rounding noise has no direction.
    if (!(across.norm() > 1e-9 * scale[k]) || !(scale[k] > 0))
      throw InputError("--wrinkle-map: x does not change across the surface at mesh vertex " + std::to_string(k) +
                       " (OBJ vertex " + std::to_string(mesh.source_index[k] + 1) +
                       "): the groove's across direction is undefined there");
    const Eigen::Vector3d a = across.normalized();
    frames[k].col(0) = a;
    frames[k].col(1) = n.cross(a);
    frames[k].col(2) = n;
  }
  return frames;
}

std::vector<double> wrinkle_radiance(const WrinkleMap<double>& map, const std::vector<Eigen::Matrix3d>& frames,
                                     const GrooveCoordinates& coords, const std::array<std::vector<double>, 3>& light,
                                     int threads) {
  const std::size_t v = frames.size();
  std::vector<double> out(v * 3, 0.0);
  parallel_for(v, threads, [&](std::size_t k) {
    WrinkleLobes<double> lobes;
    map.lobes_at(coords.x[k], coords.d[k], lobes);
    for (int c = 0; c < 3; ++c) out[k * 3 + c] = shade_wrinkle_lobes<double>(light[c], frames[k], lobes);
  });
  return out;
}

}  // namespace shtool::render
