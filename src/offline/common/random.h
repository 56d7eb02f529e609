// The offline jobs' random draws, all defined here so that every result is the same on
// every platform and thread count. Streams are seeded from (seed, job-specific indices)
// through splitmix64's finaliser, so no draw depends on which thread made it. The
// standard distributions are not used: their algorithms are implementation-defined, and
// the same seed would give other tables under another standard library.
#pragma once

#include <cstdint>
#include <random>

namespace shtool {

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// A double in [0, 1) from the top 53 bits of a hash.
inline double unit_double(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }

// How a sample point's set of ray directions is turned: a rotation about the normal and
// a shift of the stratification, each a fraction in [0, 1), hashed from (seed, point
// index), so that neighbouring points do not share one pattern.
struct RayTurn {
  double rotation, shift;
};
inline RayTurn ray_turn(std::uint64_t seed, std::uint64_t index) {
  const std::uint64_t h = splitmix64(seed ^ splitmix64(index));
  return {unit_double(h), unit_double(splitmix64(h))};
}

// A stream of doubles in [0, 1): splitmix64 iterated from `state`.
struct SplitMixStream {
  std::uint64_t state;
  double uniform() {
    state = splitmix64(state);
    return unit_double(state);
  }
};

// Draws from std::mt19937_64 (whose output the standard fixes bit for bit) with fixed
// algorithms. They are the ones libstdc++ uses for uniform_int_distribution and
// uniform_real_distribution<double> on a 64-bit engine, so the shipped lobe tables,
// first made with those, keep their bytes.

// Uniform integer in [0, n), n >= 1: Lemire's nearly divisionless method (ACM TOMACS
// 29(1), 2019) with a 128-bit product.
inline std::uint64_t uniform_below(std::mt19937_64& g, std::uint64_t n) {
  unsigned __int128 product = static_cast<unsigned __int128>(g()) * n;
  std::uint64_t low = static_cast<std::uint64_t>(product);
  if (low < n) {
    const std::uint64_t threshold = (0 - n) % n;
    while (low < threshold) {
      product = static_cast<unsigned __int128>(g()) * n;
      low = static_cast<std::uint64_t>(product);
    }
  }
  return static_cast<std::uint64_t>(product >> 64);
}

// Uniform double in [0, 1): one 64-bit draw divided by 2^64 (rounded to nearest), and
// the largest double below 1 if that rounds up to 1.
inline double uniform_01(std::mt19937_64& g) {
  const double u = static_cast<double>(g()) / 18446744073709551616.0;
  return u >= 1.0 ? 0x1.fffffffffffffp-1 : u;
}

}  // namespace shtool
