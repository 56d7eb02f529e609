#include "tensors/fourier_tables.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/input_error.h"
#include "common/table_writer.h"
#include "shtool/sh.h"

namespace shtool {

Table sh_fourier_tensors_table(int order, int max_inputs, const nlohmann::json& generator) {
  if (!is_supported_order(order))
    throw InputError("sh-fourier-tensors: unsupported order " + std::to_string(order));
  if (max_inputs < 1 || max_inputs > 16)
    throw InputError("sh-fourier-tensors: max_inputs " + std::to_string(max_inputs) +
                            " outside 1..16");
  const int degree = std::max(order - 1, max_inputs * (order - 1));
  Table t = to_table(ShFourierTensors::compute(order, degree), generator);
  nlohmann::json meta = nlohmann::json::parse(t.meta);
  meta["max_inputs"] = max_inputs;
  t.meta = meta.dump();
  return t;
}

Table to_table(const ShFourierTensors& f, const nlohmann::json& generator) {
  const nlohmann::json meta = {{"degree", f.degree},
            {"layout",
             "to_fourier[l][m][s]: Theta_l^m(t) = sum_s to_fourier * (m even ? cos(s t) : sin(s t)); "
             "to_sh[l][m][s] = integral_0^pi (m even ? cos(s t) : sin(s t)) Theta_l^m(t) sin t dt; "
             "Theta_l^m = sqrt(2 pi) K_l^m P_l^m(cos t), 0 <= m <= l"}};
  Table t = new_table(kShFourierTensorsKind, f.order, generator, meta);
  const std::int64_t n = f.order;
  t.arrays.push_back(TableArray::from<double>("to_fourier", {n, n, n}, f.to_fourier));
  t.arrays.push_back(TableArray::from<double>("to_sh", {n, n, std::int64_t{f.degree} + 1}, f.to_sh));
  return t;
}

}  // namespace shtool
