// Wall time of a job's phases, for its report (never for its results).
#pragma once

#include <chrono>

namespace shtool {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Phases timed one after another: lap() is the seconds since the previous lap (or since
// construction) and starts the next phase.
class PhaseTimer {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return seconds;
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace shtool
