// The JSON inputs of the runtime commands (rotate --in, product --in), parsed in the
// library so that tests and fuzz targets reach the same code as the command line.
// Every function throws InputError naming the input and the problem.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace shtool {

// {"coefficients": [numbers]} (rotate --in); `where` names the input.
std::vector<double> parse_coefficients_json(std::string_view text, const std::string& where);

// {"inputs": [[N^2 numbers], ...]} with min_inputs..max_inputs finite vectors of order N
// (product --in).
std::vector<std::vector<double>> parse_product_inputs(std::string_view text, const std::string& where, int order,
                                                      int min_inputs, int max_inputs);

}  // namespace shtool
