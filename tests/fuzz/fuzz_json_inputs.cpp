// The JSON inputs of the command line: fit-zh --transfer, product --in, rotate --in.
// Accepted input is finite and of the promised shape; everything else is InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "common/input_error.h"
#include "common/sh_inputs.h"
#include "fit/transfer_file.h"
#include "shtool/sh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    int order = 0;
    const auto v = shtool::fit::parse_transfer_json(text, "fuzz.json", order);
    if (order < 1 || order > shtool::kMaxOrder || v.empty() || v.size() % shtool::sh_count(order)) __builtin_trap();
    for (double x : v)
      if (!std::isfinite(x)) __builtin_trap();
  } catch (const shtool::InputError&) {
  }
  try {
    const auto f = shtool::parse_product_inputs(text, "stdin", 3, 2, 8);
    if (f.size() < 2 || f.size() > 8) __builtin_trap();
    for (const auto& g : f)
      if (g.size() != 9) __builtin_trap();
  } catch (const shtool::InputError&) {
  }
  try {
    (void)shtool::parse_coefficients_json(text, "stdin");
  } catch (const shtool::InputError&) {
  }
  return 0;
}
