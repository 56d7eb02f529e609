#include "common/sh_inputs.h"

#include <cmath>

#include <Eigen/LU>
#include <nlohmann/json.hpp>

#include "common/input_error.h"
#include "common/input_file.h"
#include "shtool/sh.h"

namespace shtool {

std::optional<ProductMethod> product_method_from_name(std::string_view name) {
  if (name == "auto") return ProductMethod::automatic;
  if (name == "tripling") return ProductMethod::tripling;
  if (name == "fourier") return ProductMethod::fourier;
  if (name == "grid") return ProductMethod::grid;
  return std::nullopt;
}

Mat3<double> checked_rotation_matrix(const Mat3<double>& r, const std::string& what) {
  if (is_rotation_matrix<double>(r)) return r;
  if (!r.allFinite()) throw InputError(what + " has a non-finite entry");
  const double defect = orthonormality_defect<double>(r);
  if (defect > kRotationInputTolerance)
    throw InputError(what + " is not orthonormal (max |R^T R - I| = " + std::to_string(defect) + ")");
  if (r.determinant() < 0) throw InputError(what + " has determinant -1 (a reflection, not a rotation)");
  return r;
}

Mat3<double> checked_quaternion_matrix(const std::array<double, 4>& q, const std::string& what) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(std::abs(norm - 1.0) <= kRotationInputTolerance))
    throw InputError(what + " is not a unit quaternion (|q| = " + std::to_string(norm) + ")");
  return matrix_from_quaternion<double>(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
}

std::vector<double> parse_coefficients_json(std::string_view text, const std::string& where) {
  const nlohmann::json doc = parse_json_input(text, where, "--in");
  if (!doc.is_object() || !doc.contains("coefficients") || !doc["coefficients"].is_array())
    throw InputError("--in: expected a JSON object {\"coefficients\": [numbers]}");
  std::vector<double> c;
  for (const auto& v : doc["coefficients"]) {
    if (!v.is_number()) throw InputError("--in: \"coefficients\" must contain only numbers");
    c.push_back(v.get<double>());
  }
  return c;
}

std::vector<std::vector<double>> parse_product_inputs(std::string_view text, const std::string& where, int order,
                                                      int min_inputs, int max_inputs) {
  // Syntax errors, numbers beyond double and absurd nesting are refused here. `where` is
  // "stdin" or a quoted file name.
  const bool quoted = where.size() >= 2 && where.front() == '\'' && where.back() == '\'';
  const nlohmann::json doc = parse_json_input(text, quoted ? where.substr(1, where.size() - 2) : where, "--in");
  if (!doc.is_object() || !doc.contains("inputs"))
    throw InputError(where + ": expected a JSON object {\"inputs\": [[...], ...]}");
  const nlohmann::json& inputs = doc["inputs"];
  if (!inputs.is_array()) throw InputError(where + ": \"inputs\" must be an array of arrays");
  const int count = static_cast<int>(inputs.size());
  if (count < min_inputs || count > max_inputs)
    throw InputError(where + ": " + std::to_string(count) + " inputs given; a product takes " +
                    std::to_string(min_inputs) + " to " + std::to_string(max_inputs));
  const std::size_t expected = static_cast<std::size_t>(sh_count(order));
  std::vector<std::vector<double>> f(count);
  for (int i = 0; i < count; ++i) {
    const nlohmann::json& v = inputs[i];
    const std::string name = "input " + std::to_string(i + 1);
    if (!v.is_array()) throw InputError(where + ": " + name + " is not an array of numbers");
    if (v.size() != expected)
      throw InputError(where + ": " + name + " has " + std::to_string(v.size()) +
                      " coefficients; order " + std::to_string(order) + " needs " +
                      std::to_string(expected) + " (N^2)");
    f[i].reserve(expected);
    for (std::size_t j = 0; j < v.size(); ++j) {
      // null is how JSON writers spell NaN and infinity; strings and the like are errors too.
      if (!v[j].is_number())
        throw InputError(where + ": " + name + ", coefficient " + std::to_string(j) +
                        " is not a number (" + v[j].type_name() + ")");
      const double x = v[j].get<double>();
      if (!std::isfinite(x))
        throw InputError(where + ": " + name + ", coefficient " + std::to_string(j) +
                        " is not finite");
      f[i].push_back(x);
    }
  }
  return f;
}

}  // namespace shtool
