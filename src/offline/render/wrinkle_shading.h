// render --shading wrinkle: [4] Sec. 4.2's wrinkle map (a wrinkle-zh table, shtool/wrinkle_map.h)
// mapped onto a mesh by per-vertex groove coordinates (x across the groove, period 1; d its
// depth), shaded per vertex in the frame (across, along, normal) and interpolated like the
// other per-vertex shadings. docs/ldprt.md, "Shading with the wrinkle map".
#pragma once

#include <array>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "fit/mesh.h"
#include "shtool/wrinkle_map.h"

namespace shtool::render {

// Per kept mesh vertex: the groove coordinate x (any finite number, period 1) and depth d.
struct GrooveCoordinates {
  std::vector<double> x, d;
};

// Reads {"x": [...], "d": [...]}, one value per mesh vertex each; throws InputError naming
// `path` and the first bad entry (wrong count, not a number, x not finite, d outside
// [0, max_depth]).
GrooveCoordinates read_groove_coordinates(const std::filesystem::path& path, const fit::Mesh& mesh,
                                          double max_depth);

// Per vertex the rotation from the groove frame to the mesh's: columns (a, n x a, n), n the
// vertex normal, a the across direction: the area-weighted mean of the gradients of x over
// the triangles that use the vertex, projected into the plane normal to n. Within a
// triangle x is unwrapped relative to the vertex (each difference taken modulo 1 into
// [-1/2, 1/2)), so a triangle may straddle x = 1 but an edge must span less than half a
// period. Throws InputError naming the vertex when that gradient vanishes (x constant
// around it, or its gradient along the normal).
std::vector<Eigen::Matrix3d> groove_frames(const fit::Mesh& mesh, const std::vector<double>& x);

// RGB exit radiance per vertex: the map's blended lobes at the vertex's own (x, d), turned
// into its frame and shaded against each channel's lighting (order^2 values each, the
// map's order). Each vertex on its own, so the bytes do not depend on `threads`.
std::vector<double> wrinkle_radiance(const WrinkleMap<double>& map, const std::vector<Eigen::Matrix3d>& frames,
                                     const GrooveCoordinates& coords, const std::array<std::vector<double>, 3>& light,
                                     int threads);

}  // namespace shtool::render
