// shtool product --order N [--method auto|tripling|fourier|grid] [--recursive] --in FILE
// Reads {"inputs": [[N^2 numbers], ...]} (2 to 8 inputs; FILE or '-' for stdin) and
// prints {"order": N, "coefficients": [N^2 numbers]}: the product of all inputs
// truncated to order N, accurate unless --recursive ([3]; docs/products.md).
#include <cmath>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "common/input_file.h"
#include "common/sh_inputs.h"
#include "tensors/fourier_tables.h"
#include "shtool/product.h"
#include "shtool/sh.h"

namespace shtool::cli {
namespace {

constexpr int kMinInputs = 2;
// The inputs the default sh-fourier-tensors table covers (gen-tensors --inputs).
constexpr int kMaxInputs = kFourierTableDefaultInputs;

struct ProductOptions {
  int order = 0;
  std::string method = "auto";
  bool recursive = false;
  std::string in;
};

std::string read_input(const std::string& path) {
  if (path == "-") return read_standard_input("--in");
  return read_input_file(path, "--in");
}

void run_product(const ProductOptions& opt) {
  if (opt.order < 1 || opt.order > kMaxFourierProductOrder)
    throw InputError("--order " + std::to_string(opt.order) + " is not supported (1.." +
                    std::to_string(kMaxFourierProductOrder) + ")");
  const std::optional<ProductMethod> parsed = product_method_from_name(opt.method);
  if (!parsed) throw InputError("--method must be auto, tripling, fourier or grid, got '" + opt.method + "'");
  const ProductMethod method = *parsed;
  if (method == ProductMethod::tripling && opt.order > kMaxTriplingOrder)
    throw InputError("--method tripling supports orders up to " + std::to_string(kMaxTriplingOrder) +
                    "; use --method fourier");
  const std::string where = opt.in == "-" ? "stdin" : "'" + opt.in + "'";
  const std::vector<std::vector<double>> f = parse_product_inputs(read_input(opt.in), where, opt.order, kMinInputs, kMaxInputs);
  const int count = static_cast<int>(f.size());
  if (method == ProductMethod::tripling && count > 2 && !opt.recursive &&
      tripling_order_needed(opt.order, count) > kMaxTriplingOrder)
    throw InputError("--method tripling: an accurate product of " + std::to_string(count) +
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
      throw InputError("the product overflows double precision (inputs too large)");
  print_json({{"order", opt.order}, {"coefficients", g}});
}

}  // namespace

void setup_product(CLI::App* sub) {
  auto opt = std::make_shared<ProductOptions>();
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->required();
  sub->add_option("--method", opt->method,
                  "auto (fastest at this order: tripling below order 7, grid from 7 on), tripling "
                  "(sparse tripling tensor; more than 2 inputs are chained at growing orders, up to "
                  "order 32), fourier (the FFT method of [3]) or grid (Gauss-Legendre quadrature)")
      ->capture_default_str();
  sub->add_flag("--recursive", opt->recursive,
                "recursive triple-product approximation ([3] Eq. 11): truncates after "
                "every step, so it is NOT the exact product of 3 or more inputs");
  sub->add_option("--in", opt->in, "input JSON file, or - for stdin")->required();
  sub->callback([opt]() { run_product(*opt); });
}

}  // namespace shtool::cli
