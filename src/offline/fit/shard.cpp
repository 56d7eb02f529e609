#include "fit/shard.h"

#include <charconv>

#include "common/input_error.h"

namespace shtool::fit {

Shard parse_shard(std::string_view text, std::string_view option) {
  const std::string quoted = std::string(option) + " '" + std::string(text) + "'";
  const std::size_t slash = text.find('/');
  auto number = [&](std::string_view part, std::size_t& out) {
    // from_chars alone would take a leading '-' or stop before trailing junk.
    if (part.empty() || part.size() > 9) return false;
    for (char c : part)
      if (c < '0' || c > '9') return false;
    return std::from_chars(part.data(), part.data() + part.size(), out).ec == std::errc();
  };
  Shard s;
  if (slash == std::string_view::npos || !number(text.substr(0, slash), s.index) ||
      !number(text.substr(slash + 1), s.count))
    throw InputError(quoted + ": expected K/N, shard K (0-based) of N, e.g. 0/4");
  if (s.count < 1 || s.count > kMaxShards)
    throw InputError(quoted + ": N must be in 1.." + std::to_string(kMaxShards));
  if (s.index >= s.count)
    throw InputError(quoted + ": K must be below N (shards are numbered 0.." + std::to_string(s.count - 1) + ")");
  return s;
}

VertexRange shard_range(std::size_t total, const Shard& shard) {
  return {total * shard.index / shard.count, total * (shard.index + 1) / shard.count};
}

}  // namespace shtool::fit
