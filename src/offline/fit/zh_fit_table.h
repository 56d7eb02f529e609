// The "zh-fit" table (schemas/zh-fit.schema.json): per vertex (or input vector) N lobes
// (unit axis, order coefficients g*_l), the fit's residual and the transfer's norm.
#pragma once

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit/zh_fit.h"
#include "shtool/table.h"

namespace shtool::fit {

// Normalised RMS over all fits: sqrt(sum residual^2 / sum norm^2) ([4] Fig. 3).
double normalized_rms(const std::vector<ZhFit>& fits);

// Every fit must have `lobes` lobes of `order` coefficients. `vertex_index` (may be
// empty) maps each row back to its OBJ vertex; `meta` gets the summary values added.
Table zh_fit_table(const std::vector<ZhFit>& fits, int order, int lobes,
                   const std::vector<std::uint32_t>& vertex_index, nlohmann::json meta,
                   const nlohmann::json& generator);

}  // namespace shtool::fit
