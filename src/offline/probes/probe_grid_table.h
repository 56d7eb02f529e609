// The "probe-grid" table (schemas/probe-grid.schema.json, docs/table-format.md) of a bake:
// whole, or the partial table of one shard (bake-probes --shard K/N) and the join of the
// parts (shtool merge), which gives the one-process table byte for byte.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit/shard.h"
#include "probes/probe_bake.h"
#include "shtool/table.h"

namespace shtool::probes {

// The whole grid. `meta` brings the scene's values (mesh_up, triangles, lights); the grid's
// own (quantity, resolution, bounds, invalid and unfilled counts, layout) are added here.
Table probe_grid_table(const ProbeGridSpec& spec, const ProbeBake& bake, const nlohmann::json& generator,
                       nlohmann::json meta);
// --json: {"order", "quantity", "channels", "resolution", "bounds", "probes": [{"index",
// "position", "valid", "coefficients"}]} in index order.
nlohmann::json probe_grid_json(const ProbeGridSpec& spec, const ProbeBake& bake);

// Shard `shard` of the grid: probes [range.begin, range.end) before the fill, arrays
// `bounds` [2, 3], `coefficients` [R, N^2, 3], `valid` [R], meta "shard" {index, count,
// first_probe, end_probe, probes}. The runtime loader refuses it.
Table probe_grid_part_table(const ProbeGridSpec& spec, const ProbeBake& part, const fit::Shard& shard,
                            const fit::VertexRange& range, const nlohmann::json& generator, nlohmann::json meta);

// The parts of one bake (in any order) joined, the invalid probes filled: the table a
// one-process run writes. Throws InputError naming the part: not a partial probe-grid
// table, another bake's (generator records or meta differ), a shard missing or twice,
// shapes that disagree with the shard record.
Table merge_probe_grid_tables(const std::vector<std::pair<std::string, Table>>& parts);

// Whether a table file holds a probe-grid (merge dispatches on it).
bool is_probe_grid_file(const std::filesystem::path& path);

struct ProbeMergeReport {
  std::size_t parts = 0, probes = 0;
};
// Reads every part (checksums included), joins, writes `out` atomically (InputError
// before anything is written).
ProbeMergeReport merge_probe_grid_parts(const std::vector<std::filesystem::path>& parts,
                                        const std::filesystem::path& out, TableEncoding encoding);

}  // namespace shtool::probes
