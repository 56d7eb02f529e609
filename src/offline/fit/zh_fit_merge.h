// `shtool merge`: the partial zh-fit tables of a sharded bake (fit-zh --shard K/N) joined
// into the table a one-process run writes, byte for byte.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "shtool/table.h"
#include "shtool/zh_fit_table.h"

namespace shtool::fit {

// A partial table and what messages call it (its path, or "rank 3").
struct NamedTable {
  std::string name;
  Table table;
};

struct MergedFits {
  Table table;              // what a one-process run writes
  ZhFitTable<double> fits;  // its rows, for the outputs made from fits (--json)
};

// The checks and the join of merge_zh_fit_parts on tables already read (the MPI ranks'
// partial tables reach rank 0 as bytes). Throws InputError naming the part.
MergedFits merge_zh_fit_tables(std::vector<NamedTable> parts);

struct MergeRequest {
  std::vector<std::filesystem::path> parts;  // in any order
  std::filesystem::path out;
  TableEncoding encoding = TableEncoding::binary;
};

struct MergeReport {
  std::size_t parts = 0, vertices = 0;
};

// Checks before writing anything, and throws InputError naming the file and the problem:
// every part reads as a zh-fit table (checksums included) and is partial; all come from
// the same bake (generator records equal: tool version, command, every option, seed,
// input and mesh CRCs, Embree version and ISA; the same order, lobes, arrays and mesh
// counters); every shard 0..N-1 is there exactly once with the rows its range
// prescribes. Then writes `out` atomically.
MergeReport merge_zh_fit_parts(const MergeRequest& request);

}  // namespace shtool::fit
