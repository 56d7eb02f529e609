// Wall time of a job's phases, for its report (never for its results).
#pragma once

#include <chrono>

namespace shtool {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace shtool
