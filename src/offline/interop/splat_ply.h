// 3D Gaussian Splatting PLY files (graphdeco-inria's layout) and SplatScene: the
// properties found by name, read into a scene, and a scene written in the reference
// layout (docs/splats.md).
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/atomic_file.h"
#include "interop/ply.h"
#include "interop/splat_scene.h"

namespace shtool::interop {

// The splat properties of a vertex element (indices into its properties), found by
// name: x y z, nx ny nz, rot_0..3 (w x y z), scale_0..2 (log), f_dc_0..2, f_rest_*
// (channel-major: all of R, then G, then B), opacity (logit).
struct SplatLayout {
  std::array<std::size_t, 3> position{};
  std::optional<std::array<std::size_t, 3>> normal;
  std::optional<std::array<std::size_t, 4>> rotation;
  std::optional<std::array<std::size_t, 3>> scale;
  std::optional<std::array<std::size_t, 3>> dc;
  std::optional<std::size_t> opacity;
  std::vector<std::size_t> rest;  // f_rest_0 .. f_rest_{K-1}
  int degree = 0;
};

// InputError naming `name` when a property is missing, not float, or the f_rest set is
// not that of degree 0..3.
SplatLayout find_splat_layout(const PlyElement& vertex, const std::filesystem::path& name);

// The properties that hold splat values (position, rotation, scale, f_dc, f_rest,
// opacity), ascending: the ones that must be finite. Normals and other properties are not
// splat data: they are carried (normals turned) whatever they hold.
std::vector<std::size_t> splat_value_properties(const SplatLayout& layout);

// The whole scene (every splat property required but the normals); InputError naming
// `name` on a missing property or a value that is not finite.
SplatScene read_ply_splats(const PlyFile& ply, const std::filesystem::path& name, int threads);

// A binary PLY copied from its bytes (a mapped file) into `out` as it is read: the
// records of `element` in pieces of kPlyPiece records, on `threads` threads, each piece
// copied into a buffer of its thread, changed there by `edit` (when given) and written at
// its place (PendingFile::write_at); the bytes before and after the element as they are.
// edit(records, first, count) changes records first..first+count-1 and returns a problem
// ("" when none): after it no later piece is edited, and the problem of the earliest
// piece is thrown as InputError, the same whatever the threads. Without an edit this is
// the bare PLY decode + encode the job is measured against (bench_splats).
inline constexpr std::size_t kPlyPiece = 2048;
using PlyRecordEdit = std::function<std::string(char* records, std::size_t first, std::size_t count)>;
void rewrite_binary_ply(std::string_view bytes, const PlyElement& element, PendingFile& out, int threads,
                        const PlyRecordEdit& edit);

// The reference layout, binary little endian float: x y z nx ny nz (zeros) f_dc_0..2
// f_rest_* opacity scale_0..2 rot_0..3.
std::string write_ply_splats(const SplatScene& scene);

}  // namespace shtool::interop
