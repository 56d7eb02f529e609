// Transfer vectors as a file: what fit-zh --save-transfer writes and fit-zh --transfer
// and render --transfer read, {"order": n, "mesh_up": "y" | "z", "vectors": [[n^2
// numbers], ...]} (docs/fit-zh.md).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "common/mesh_frame.h"

namespace shtool::fit {

// The vectors of `text` (the contents of `path`), one after the other; `order` receives
// the file's order and `mesh_up`, if given, its "mesh_up" record (empty: none). Throws
// InputError naming the file: not of that layout, an order outside 1..kMaxOrder, a vector
// of the wrong length, a value not finite or beyond 1e100 in magnitude.
std::vector<double> parse_transfer_json(std::string_view text, const std::filesystem::path& path, int& order,
                                        std::string* mesh_up = nullptr);

// The file of `transfer` (rows of order^2 numbers), recording the mesh's up axis.
std::string transfer_json(const std::vector<double>& transfer, int order, UpAxis up);

}  // namespace shtool::fit
