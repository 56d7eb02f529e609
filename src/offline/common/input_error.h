// The offline side's one error type for bad input: a malformed option, an unreadable or
// invalid file, an output that cannot be written. Library code and the CLI alike throw
// it; main() maps it once to "shtool: error: <message>" on stderr and exit code 1.
// Anything else that escapes is a bug in shtool (exit 3).
#pragma once

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace shtool {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws InputError "<file>: <problem>", the form every reader's refusal takes.
[[noreturn]] inline void fail_input(const std::filesystem::path& file, const std::string& problem) {
  throw InputError(file.string() + ": " + problem);
}

// An integer option within [lo, hi], or InputError "<option> must be in lo..hi, got v".
inline void check_option_range(const char* option, long long value, long long lo, long long hi) {
  if (value < lo || value > hi)
    throw InputError(std::string(option) + " must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
                     std::to_string(value));
}

// A number as a message shows it: six significant digits, an exponent where it is large
// or small ("0.25", "1e+30", "3.5e-07"), where std::to_string gives "0.000000" for 3.5e-07
// and 31 digits for 1e30.
inline std::string message_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

}  // namespace shtool
