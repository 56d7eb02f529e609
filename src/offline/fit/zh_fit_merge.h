// `shtool merge`: the partial zh-fit tables of a sharded bake (fit-zh --shard K/N) joined
// into the table a one-process run writes, byte for byte.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "shtool/table.h"

namespace shtool::fit {

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
