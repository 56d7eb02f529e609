// No output of shtool holds NaN or infinity: a computation that overflows on finite input
// is an error naming the quantity, never an inf, a NaN or a JSON null with exit 0. The
// writers call these before they write.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "common/input_error.h"

namespace shtool {

// Whether a writer refuses NaN and infinity (every output of shtool does) or keeps them
// (the formats can hold them bit for bit: their own tests, and tests that craft bad
// inputs for the readers).
enum class NonFinite { refuse, keep };

// InputError "<quantity> <index> is not finite (...)" for the first value that is not.
template <typename T>
void check_finite(std::span<const T> values, std::string_view quantity) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw InputError(std::string(quantity) + " " + std::to_string(i) +
                       " is not finite (a computation overflowed: no output holds NaN or infinity)");
}

// Whether a double survives the conversion to float (written as float32) as a finite value.
inline bool finite_as_float(double v) {
  return std::isfinite(v) && std::abs(v) <= static_cast<double>(std::numeric_limits<float>::max());
}

// Whether a JSON value holds a NaN or an infinity anywhere in it.
inline bool has_non_finite(const nlohmann::json& j) {
  if (j.is_number_float()) return !std::isfinite(j.get<double>());
  if (j.is_array() || j.is_object())
    for (const nlohmann::json& value : j)
      if (has_non_finite(value)) return true;
  return false;
}

// The JSON text of `doc` (nlohmann's dump with `indent`), refusing a NaN or an infinity
// anywhere in it: nlohmann would write null. `what` names the output in the message.
inline std::string dump_finite(const nlohmann::json& doc, std::string_view what, int indent = -1) {
  if (has_non_finite(doc))
    throw InputError(std::string(what) + ": a value is not finite (a computation overflowed: no output holds NaN or "
                     "infinity)");
  return doc.dump(indent);
}

}  // namespace shtool
