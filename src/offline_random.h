// The one hash the offline jobs derive their random streams from: splitmix64's
// finaliser. Seeding every stream from (seed, job-specific indices) through it makes
// results independent of thread count and identical on every platform (unlike the
// standard distributions, whose algorithms are implementation-defined).
#pragma once

#include <cstdint>

namespace shtool {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace shtool
