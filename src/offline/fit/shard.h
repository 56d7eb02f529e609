// Splitting a bake over processes: shard K of N (0-based) fits the K-th of N contiguous
// vertex ranges, the same partition parallel_for uses for threads. Every per-vertex draw
// depends on (seed, vertex) only, so the rows of a shard are the rows a one-process run
// computes for those vertices, bit for bit.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace shtool::fit {

struct Shard {
  std::size_t index = 0;  // K, 0 <= K < N
  std::size_t count = 1;  // N >= 1
};

// Shard counts above this are refused (far more than any cluster runs, and it keeps
// count * index products of 2^32-vertex meshes inside 64 bits).
inline constexpr std::size_t kMaxShards = 1u << 20;

// "K/N" in decimal, 0-based. Throws InputError naming `option` and what is wrong.
Shard parse_shard(std::string_view text, std::string_view option = "--shard");

struct VertexRange {
  std::size_t begin = 0, end = 0;  // [begin, end)
};

// [total * K / N, total * (K + 1) / N).
VertexRange shard_range(std::size_t total, const Shard& shard);

}  // namespace shtool::fit
