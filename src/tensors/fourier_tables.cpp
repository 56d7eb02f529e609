#include "tensors/fourier_tables.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "shtool/sh.h"

namespace shtool {

Table sh_fourier_tensors_table(int order, int max_inputs, const nlohmann::json& generator) {
  if (!is_supported_order(order))
    throw std::out_of_range("sh-fourier-tensors: unsupported order " + std::to_string(order));
  if (max_inputs < 1 || max_inputs > 16)
    throw std::out_of_range("sh-fourier-tensors: max_inputs " + std::to_string(max_inputs) +
                            " outside 1..16");
  const int degree = std::max(order - 1, max_inputs * (order - 1));
  Table t = ShFourierTensors::compute(order, degree).to_table(generator);
  t.meta["max_inputs"] = max_inputs;
  return t;
}

}  // namespace shtool
