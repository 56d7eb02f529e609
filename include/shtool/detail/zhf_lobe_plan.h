// Private to ZhfRotation and ZhfTailoredSignal (shtool/zhf_rotation.h): the walk over
// the lobe directions that both objects keep. Not an interface.
#pragma once

#include <vector>

namespace shtool {

struct ZhfLobes;

namespace detail {

// How the evaluators walk the lobe directions. The SH recurrence runs for all directions
// at once, structure-of-arrays (the direction loop is the innermost one, so it vectorises):
// band l's recurrence is needed for the directions that some band >= l uses, a range that
// only shrinks with l; band l's own values are those of its 2l+1 directions
// band_offset[l] .. band_offset[l] + 2l (shared lobes: directions 0..2l of 2N-1).
struct ZhfLobePlan {
  int order = 0;
  int directions = 0;
  std::vector<int> band_offset;           // per band: its first direction
  std::vector<int> active_lo, active_hi;  // per band l: directions [lo, hi) needing band l
  std::vector<int> block_offset;          // band l's (2l+1)^2 block in a band-major buffer
  ZhfLobePlan() = default;
  ZhfLobePlan(const ZhfLobes& lobes, int order);
};

}  // namespace detail

}  // namespace shtool
