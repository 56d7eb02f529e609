// gen-tensors: the reduced SH <-> Fourier tensors ([3] Sec. 3.2.3-3.2.4, 4.3) as a
// "sh-fourier-tensors" table. The values come from the runtime's own construction
// (ShFourierTensors::compute: exact sampling + discrete cosine/sine transforms in long
// double, stable at any l), so a table and an on-the-fly build agree bit for bit.
#pragma once

#include <nlohmann/json.hpp>

#include "shtool/fourier_tensors.h"
#include "shtool/table.h"

namespace shtool {

// Inputs of the largest multiple product a default table covers (the CLI's limit).
inline constexpr int kFourierTableDefaultInputs = 8;

// Table for bands 0..order-1, with to_sh up to frequency max_inputs * (order - 1), the
// degree of a product of max_inputs functions (Eq. 29).
// Preconditions: 1 <= order <= kMaxOrder, 1 <= max_inputs <= 16.
Table sh_fourier_tensors_table(int order, int max_inputs, const nlohmann::json& generator);

// The "sh-fourier-tensors" table of `f` (schemas/sh-fourier-tensors.schema.json).
Table to_table(const ShFourierTensors& f, const nlohmann::json& generator);

}  // namespace shtool
