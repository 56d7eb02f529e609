// What every mesh a loader accepts must be, whatever the bytes: vertices with normals and
// file indices, triangle corners inside them, finite positions, unit normals. A fuzz
// target traps (a finding) when one is not.
#pragma once

#include <cmath>
#include <cstddef>

#include "fit/mesh.h"

inline void trap_unless_mesh_is_whole(const shtool::fit::Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (mesh.normals.size() != n || mesh.source_index.size() != n) __builtin_trap();
  for (const auto& t : mesh.triangles)
    for (int c = 0; c < 3; ++c)
      if (t[c] < 0 || static_cast<std::size_t>(t[c]) >= n) __builtin_trap();
  for (std::size_t i = 0; i < n; ++i) {
    if (!mesh.positions[i].allFinite()) __builtin_trap();
    if (!(std::abs(mesh.normals[i].norm() - 1.0) < 1e-6)) __builtin_trap();
  }
}
