// The "zh-fit" table (schemas/zh-fit.schema.json): per vertex (or input vector) N lobes
// (unit axis, order coefficients g*_l), the fit's residual and the transfer's norm.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "shtool/table.h"
#include "shtool/zh_fit_table.h"

namespace shtool::fit {

// Normalised RMS over all fits: sqrt(sum residual^2 / sum norm^2) ([4] Fig. 3).
double normalized_rms(const ZhFitTable<double>& fits);

// The table of a flat fit set (its vertex_index, when not empty, maps each row back to
// its OBJ vertex); `meta` gets the summary values added.
Table zh_fit_table(const ZhFitTable<double>& fits, nlohmann::json meta, const nlohmann::json& generator);

// The fits as fit-zh --json writes them: {"order", "lobes", "fits": [{"lobes": [{"axis",
// "coeffs"}], "residual", "norm", "direct"?}]}.
std::string fits_json(const ZhFitTable<double>& fits);

}  // namespace shtool::fit
