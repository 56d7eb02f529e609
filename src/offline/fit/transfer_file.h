// Transfer vectors as a file: what fit-zh --save-transfer writes and fit-zh --transfer
// and render --transfer read, {"order": n, "mesh_up": "y" | "z", "mesh_crc32": c,
// "normals": "auto" | "file" | "computed", "vectors": [[n^2 numbers], ...]}
// (docs/fit-zh.md); only order and vectors are required.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/mesh_frame.h"

namespace shtool::fit {

// What a transfer file says of the mesh it was simulated on (each empty when absent).
struct TransferMeshRecord {
  std::string mesh_up;                      // "y" or "z"
  std::optional<std::uint32_t> mesh_crc32;  // loaded_mesh_crc32 of the mesh
  std::string normals;                      // the --normals it was loaded with
};

// The vectors of `text` (the contents of `path`), one after the other; `order` receives
// the file's order and `record`, if given, what it says of its mesh. Throws InputError
// naming the file: not of that layout, an order outside 1..kMaxOrder, a vector of the
// wrong length, a value not finite or beyond 1e100 in magnitude, a malformed record.
std::vector<double> parse_transfer_json(std::string_view text, const std::filesystem::path& path, int& order,
                                        TransferMeshRecord* record = nullptr);

// The file of `transfer` (rows of order^2 numbers), recording the mesh's up axis,
// checksum and normals.
std::string transfer_json(const std::vector<double>& transfer, int order, UpAxis up, std::uint32_t mesh_crc32,
                          std::string_view normals);

}  // namespace shtool::fit
