// shtool product --order N [--method auto|tripling|fourier|grid] [--recursive] --in FILE
// Reads {"inputs": [[N^2 numbers], ...]} (2 to 8 inputs; FILE or '-' for stdin) and
// prints {"order": N, "coefficients": [N^2 numbers]}: the product of all inputs
// truncated to order N, accurate unless --recursive (paper 003; docs/products.md).
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "shtool/product.h"
#include "shtool/sh.h"

namespace shtool::cli {
namespace {

constexpr int kMinInputs = 2;
constexpr int kMaxInputs = 8;  // the issue asks for k - 1 <= 8 inputs

struct ProductOptions {
  int order = 0;
  std::string method = "auto";
  bool recursive = false;
  std::string in;
};

std::string read_input(const std::string& path) {
  if (path == "-") {
    std::ostringstream ss;
    ss << std::cin.rdbuf();
    return ss.str();
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw UserError("--in: cannot open '" + path + "'");
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) throw UserError("--in: error reading '" + path + "'");
  return text;
}

std::vector<std::vector<double>> parse_inputs(const std::string& text, const std::string& where,
                                              int order) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // syntax errors, and numbers beyond double
    throw UserError(where + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!doc.is_object() || !doc.contains("inputs"))
    throw UserError(where + ": expected a JSON object {\"inputs\": [[...], ...]}");
  const nlohmann::json& inputs = doc["inputs"];
  if (!inputs.is_array()) throw UserError(where + ": \"inputs\" must be an array of arrays");
  const int count = static_cast<int>(inputs.size());
  if (count < kMinInputs || count > kMaxInputs)
    throw UserError(where + ": " + std::to_string(count) + " inputs given; a product takes " +
                    std::to_string(kMinInputs) + " to " + std::to_string(kMaxInputs));
  const std::size_t expected = static_cast<std::size_t>(sh_count(order));
  std::vector<std::vector<double>> f(count);
  for (int i = 0; i < count; ++i) {
    const nlohmann::json& v = inputs[i];
    const std::string name = "input " + std::to_string(i + 1);
    if (!v.is_array()) throw UserError(where + ": " + name + " is not an array of numbers");
    if (v.size() != expected)
      throw UserError(where + ": " + name + " has " + std::to_string(v.size()) +
                      " coefficients; order " + std::to_string(order) + " needs " +
                      std::to_string(expected) + " (N^2)");
    f[i].reserve(expected);
    for (std::size_t j = 0; j < v.size(); ++j) {
      // null is how JSON writers spell NaN and infinity; strings and the like are errors too.
      if (!v[j].is_number())
        throw UserError(where + ": " + name + ", coefficient " + std::to_string(j) +
                        " is not a number (" + v[j].dump() + ")");
      const double x = v[j].get<double>();
      if (!std::isfinite(x))
        throw UserError(where + ": " + name + ", coefficient " + std::to_string(j) +
                        " is not finite");
      f[i].push_back(x);
    }
  }
  return f;
}

void run_product(const ProductOptions& opt) {
  if (opt.order < 1 || opt.order > kMaxFourierProductOrder)
    throw UserError("--order " + std::to_string(opt.order) + " is not supported (1.." +
                    std::to_string(kMaxFourierProductOrder) + ")");
  ProductMethod method = ProductMethod::automatic;
  if (opt.method == "tripling")
    method = ProductMethod::tripling;
  else if (opt.method == "fourier")
    method = ProductMethod::fourier;
  else if (opt.method == "grid")
    method = ProductMethod::grid;
  else if (opt.method != "auto")
    throw UserError("--method must be auto, tripling, fourier or grid, got '" + opt.method + "'");
  if (method == ProductMethod::tripling && opt.order > kMaxTriplingOrder)
    throw UserError("--method tripling supports orders up to " + std::to_string(kMaxTriplingOrder) +
                    "; use --method fourier");
  const std::string where = opt.in == "-" ? "stdin" : "'" + opt.in + "'";
  const std::vector<std::vector<double>> f = parse_inputs(read_input(opt.in), where, opt.order);
  const int count = static_cast<int>(f.size());
  if (method == ProductMethod::tripling && count > 2 && !opt.recursive &&
      tripling_order_needed(opt.order, count) > kMaxTriplingOrder)
    throw UserError("--method tripling: an accurate product of " + std::to_string(count) +
                    " inputs of order " + std::to_string(opt.order) + " needs tripling tensors of order " +
                    std::to_string(tripling_order_needed(opt.order, count)) + " (supported up to " +
                    std::to_string(kMaxTriplingOrder) + "); use --method fourier");
  ShProduct<double> product(opt.order, method);
  std::vector<std::span<const double>> spans(f.begin(), f.end());
  std::vector<double> g(sh_count(opt.order));
  if (opt.recursive)
    product.recursive(spans, g);
  else if (method == ProductMethod::tripling && count > 2)
    tripling_multiple_product<double>(opt.order, spans, g);  // accurate, by chained exact steps
  else
    product.multiple(spans, g);
  for (double x : g)
    if (!std::isfinite(x))
      throw UserError("the product overflows double precision (inputs too large)");
  print_json({{"order", opt.order}, {"coefficients", g}});
}

}  // namespace

void setup_product(CLI::App& app) {
  auto opt = std::make_shared<ProductOptions>();
  CLI::App* sub = app.add_subcommand(
      "product",
      "Product of 2 to 8 SH functions truncated to order N (JSON in, JSON out). Input: "
      "{\"inputs\": [[N^2 coefficients], ...]}; output: {\"order\": N, \"coefficients\": [...]}");
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->required();
  sub->add_option("--method", opt->method,
                  "auto (fastest at this order: tripling below order 6, grid from 6 on), tripling "
                  "(sparse tripling tensor; more than 2 inputs are chained at growing orders, up to "
                  "order 32), fourier (paper 003's FFT method) or grid (Gauss-Legendre quadrature)")
      ->capture_default_str();
  sub->add_flag("--recursive", opt->recursive,
                "recursive triple-product approximation (paper 003, Eq. 11): truncates after "
                "every step, so it is NOT the exact product of 3 or more inputs");
  sub->add_option("--in", opt->in, "input JSON file, or - for stdin")->required();
  sub->callback([opt]() { run_product(*opt); });
}

}  // namespace shtool::cli
