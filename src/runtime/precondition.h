// Internal to the runtime: what happens when a documented precondition is violated (an
// order, size or count outside what a function accepts). The runtime reports input
// that can fail, such as a table file, through Result (shtool/result.h); everything else
// is a precondition, checked where it is cheap. Built with exceptions, a violation
// throws the standard exception named below, with a message (the tests check them);
// built with -fno-exceptions, the message goes to stderr and the program aborts. The
// library itself builds both ways.
#pragma once

#include <cstddef>
#include <string>

namespace shtool::detail {

// std::invalid_argument: the caller passed something the function's contract excludes.
[[noreturn]] void precondition_failed(const std::string& message);
// std::logic_error: an internal invariant does not hold (a bug in shtool).
[[noreturn]] void invariant_failed(const std::string& message);
// std::runtime_error: a library the runtime uses failed (FFTW could not plan).
[[noreturn]] void dependency_failed(const std::string& message);
// std::bad_alloc.
[[noreturn]] void allocation_failed();

// precondition_failed unless a span `what` of `call` holds at least `needed` values: a
// per-call comparison, so the entry points that take spans of coefficients check them
// (a short span would otherwise be read or written past its end).
inline void check_span_size(const char* call, const char* what, std::size_t given, std::size_t needed) {
  if (given < needed)
    precondition_failed(std::string(call) + ": " + what + " holds " + std::to_string(given) + " values, " +
                        std::to_string(needed) + " needed");
}

}  // namespace shtool::detail
