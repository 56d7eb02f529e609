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
#include "shtool/probe_encoding.h"
#include "shtool/table.h"

namespace shtool::probes {

// What a grid's probes store (bake-probes --encoding, --zh3-fit, --zh3-axis); the ZH3
// choices mean something for zh3 only.
struct GridEncoding {
  ProbeEncoding encoding = ProbeEncoding::l2;
  Zh3Axis zh3_axis = Zh3Axis::luminance;
  Zh3Fit zh3_fit = Zh3Fit::explicit_fit;

  bool stores_zonal() const { return encoding == ProbeEncoding::zh3 && zh3_fit == Zh3Fit::explicit_fit; }
};

// A whole grid's probes as its encoding stores them (docs/probe-encodings.md): l2, the
// bake's coefficients of its order; l1 and hallucinated zh3, bands 0 and 1 (order 2);
// explicit zh3, bands 0 and 1 (order 2) and per probe the explicit fit's zonal coefficient
// of r, g, b along the axis.
struct EncodedProbes {
  GridEncoding encoding;
  int order = 0;                       // the table's order
  std::vector<double> coefficients;    // probe-major, then SH index (order^2), then r, g, b
  std::vector<double> zonal;           // explicit zh3: probe-major, then r, g, b; empty otherwise
  std::vector<std::uint8_t> valid;
  std::size_t unfilled = 0;
};

// The lowest bake order an encoding needs: l1 and hallucinated zh3 2 (bands 0 and 1),
// explicit zh3 3 (band 2 is fitted), l2 1.
int lowest_bake_order(const GridEncoding& encoding);

// Each probe of a whole, filled bake of order `order` (>= lowest_bake_order) encoded on
// its own: the encoding is applied after the invalid probes are filled, so a grid's l1 or
// zh3 table is exactly the encoding of its l2 table.
EncodedProbes encode_probes(const ProbeBake& bake, int order, const GridEncoding& encoding);

// The whole grid. `meta` brings the scene's values (mesh_up, triangles, lights); the grid's
// own (quantity, encoding, resolution, bounds, invalid and unfilled counts, layout) are
// added here.
Table probe_grid_table(const ProbeGridSpec& spec, const EncodedProbes& probes, const nlohmann::json& generator,
                       nlohmann::json meta);
// --json: {"order", "quantity", "channels", "resolution", "bounds", "probes": [{"index",
// "position", "valid", "coefficients"}]} in index order; an l1 or zh3 grid adds
// "encoding" (and zh3 "zh3_axis", "zh3_fit", and with the explicit fit each probe's
// "zonal": [r, g, b]).
nlohmann::json probe_grid_json(const ProbeGridSpec& spec, const EncodedProbes& probes);

// Shard `shard` of the grid: probes [range.begin, range.end) before the fill and before any
// encoding (the generator record's "encoding" is applied by the join), arrays
// `bounds` [2, 3], `coefficients` [R, N^2, 3], `valid` [R], meta "shard" {index, count,
// first_probe, end_probe, probes}. The runtime loader refuses it.
Table probe_grid_part_table(const ProbeGridSpec& spec, const ProbeBake& part, const fit::Shard& shard,
                            const fit::VertexRange& range, const nlohmann::json& generator, nlohmann::json meta);

// The encoding a generator record's parameters name ("encoding"; "zh3_axis" and "zh3_fit"
// for zh3, absent in parts of kind_version 1.0: luminance, explicit); InputError naming
// `name` otherwise.
GridEncoding generator_encoding(const nlohmann::json& parameters, const std::string& name);

// The parts of one bake (in any order) joined, the invalid probes filled, the probes
// encoded as the generator record says: the table a one-process run writes. Throws
// InputError naming the part: not a partial probe-grid table, another bake's (generator
// records or meta differ), a shard missing or twice, shapes that disagree with the shard
// record, an unknown encoding.
struct MergedProbeGrid {
  ProbeGridSpec spec;
  EncodedProbes probes;
  Table table;
};
MergedProbeGrid merge_probe_grid(const std::vector<std::pair<std::string, Table>>& parts);
Table merge_probe_grid_tables(const std::vector<std::pair<std::string, Table>>& parts);

// Whether a table file holds a probe-grid (merge dispatches on it).
bool is_probe_grid_file(const std::filesystem::path& path);

// The order-3 radiance coefficients three.js's LightProbeGridWebGL takes for an encoded
// grid: l2's own (bands above 2 dropped by the writer), zh3's L1 band with the band 2 its
// zonal coefficient stands for (zh3_band2 along the grid's axis, of the stored f or, for
// the hallucinated variant, of the f each probe's L1 band gives; three's linear irradiance
// of them is exactly the ZH3 irradiance at the probe). l1 has none: its non-linear
// reconstruction is not a linear function of SH coefficients (InputError naming `option`).
std::vector<double> three_coefficients(const EncodedProbes& probes, int& order, const std::string& option);

struct ProbeMergeReport {
  std::size_t parts = 0, probes = 0;
};
// Reads every part (checksums included), joins, writes `out` and, when not empty, `json`
// (as bake-probes --json) and the three.js files in `threejs` (as --threejs) together
// (InputError before anything is written).
ProbeMergeReport merge_probe_grid_parts(const std::vector<std::filesystem::path>& parts,
                                        const std::filesystem::path& out, TableEncoding encoding,
                                        const std::filesystem::path& json = {},
                                        const std::filesystem::path& threejs = {});

}  // namespace shtool::probes
