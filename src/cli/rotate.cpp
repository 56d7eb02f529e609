// shtool rotate: rotate an SH vector, g(w) = f(R^-1 w), by any runtime method.
#include <cmath>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "common/input_file.h"
#include "common/sh_inputs.h"
#include "lobes/lobes.h"
#include "tensors/rotation_helpers_gen.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/zhf_rotation.h"

namespace shtool::cli {
namespace {

struct RotateOptions {
  int order = 0;
  std::string method = "auto";
  double tol = kDefaultRotationTolerance;
  std::string quat, matrix, zyz, coeffs, in, tables;
};

std::vector<double> read_coefficients(const RotateOptions& opt) {
  if (!opt.coeffs.empty()) return parse_number_list(opt.coeffs, "--coeffs");
  const std::string text = opt.in == "-" ? read_standard_input("--in") : read_input_file(opt.in, "--in");
  return parse_coefficients_json(text, opt.in);
}

Mat3<double> read_rotation(const RotateOptions& opt) {
  const int given = !opt.quat.empty() + !opt.matrix.empty() + !opt.zyz.empty();
  if (given != 1) throw InputError("give exactly one of --quat, --matrix, --zyz");
  if (!opt.quat.empty()) {
    const std::vector<double> q = parse_number_list(opt.quat, "--quat");
    if (q.size() != 4) throw InputError("--quat needs 4 numbers w,x,y,z, got " + std::to_string(q.size()));
    return checked_quaternion_matrix({q[0], q[1], q[2], q[3]}, "--quat");
  }
  if (!opt.zyz.empty()) {
    const std::vector<double> a = parse_number_list(opt.zyz, "--zyz");
    if (a.size() != 3) throw InputError("--zyz needs 3 angles a,b,c in radians, got " + std::to_string(a.size()));
    return matrix_from_zyz<double>({a[0], a[1], a[2]});
  }
  const std::vector<double> m = parse_number_list(opt.matrix, "--matrix");
  if (m.size() != 9) throw InputError("--matrix needs 9 numbers r00,r01,...,r22, got " + std::to_string(m.size()));
  Mat3<double> r;
  r << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return checked_rotation_matrix(r, "--matrix");
}

void run_rotate(const RotateOptions& opt) {
  if (!is_supported_order(opt.order))
    throw InputError("--order " + std::to_string(opt.order) + " is not supported (1.." +
                    std::to_string(kMaxOrder) + ")");
  const bool zhf = opt.method == "zhf" || opt.method == "zhf-tailored";
  const std::optional<RotationMethod> method = rotation_method_from_name(opt.method);
  if (!zhf && !method)
    throw InputError("--method: unknown method '" + opt.method +
                    "' (auto, reference, zxzxz, taylor1, taylor1.5, taylor2, zhf, zhf-tailored)");
  if (!(opt.tol > 0) || !std::isfinite(opt.tol)) throw InputError("--tol must be a positive number");
  const Mat3<double> r = read_rotation(opt);
  const std::vector<double> coeffs = read_coefficients(opt);
  if (coeffs.size() != static_cast<std::size_t>(sh_count(opt.order)))
    throw InputError("expected " + std::to_string(sh_count(opt.order)) + " coefficients for order " +
                    std::to_string(opt.order) + ", got " + std::to_string(coeffs.size()));
  for (double c : coeffs)
    if (!std::isfinite(c)) throw InputError("coefficients must be finite numbers");

  std::vector<double> out(coeffs.size());
  if (zhf) {
    // Zonal-harmonic factorisation ([1] Eq. 10 and 11) with a shared-lobe table.
    const auto lobes = lobes::zhf_lobes_for(opt.order, opt.tables);
    if (opt.method == "zhf") {
      ZhfRotation<double> rotation(opt.order, lobes);
      rotation.set(r);
      rotation.apply(coeffs, out);
    } else {
      ZhfTailoredSignal<double> signal(lobes, coeffs);
      signal.set(r);
      signal.apply(out);
    }
    for (double c : out)
      if (!std::isfinite(c)) throw InputError("the rotated coefficients overflow double precision (inputs too large)");
    print_json({{"order", opt.order}, {"method", opt.method}, {"coefficients", out}});
    return;
  }

  std::shared_ptr<const RotationHelpers> helpers;
  if (*method != RotationMethod::reference) helpers = rotation_helpers_for(opt.order, opt.tables);
  ShRotation<double> rotation(opt.order, helpers);
  if (!rotation.set(r, *method, opt.tol)) throw InputError("rotation method unavailable for this order");
  rotation.apply(coeffs, out);
  for (double c : out)
    if (!std::isfinite(c)) throw InputError("the rotated coefficients overflow double precision (inputs too large)");
  print_json({{"order", opt.order},
              {"method", std::string(rotation_method_name(rotation.method()))},
              {"coefficients", out}});
}

}  // namespace

void setup_rotate(CLI::App* sub) {
  auto opt = std::make_shared<RotateOptions>();
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->required();
  sub->add_option("--method", opt->method,
                  "auto|reference|zxzxz|taylor1|taylor1.5|taylor2|zhf|zhf-tailored")
      ->capture_default_str();
  sub->add_option("--tol", opt->tol,
                  "auto: largest error allowed for a unit-length vector (spectral norm)")
      ->capture_default_str();
  sub->add_option("--quat", opt->quat, "unit quaternion w,x,y,z (Hamilton)");
  sub->add_option("--matrix", opt->matrix, "rotation matrix r00,r01,...,r22 (row-major)");
  sub->add_option("--zyz", opt->zyz, "Euler angles a,b,c: R = Rz(a) Ry(b) Rz(c), radians");
  sub->add_option("--coeffs", opt->coeffs, "N^2 coefficients c0,c1,...");
  sub->add_option("--in", opt->in, "JSON file {\"coefficients\": [...]}, or - for stdin");
  sub->add_option("--tables", opt->tables,
                  "rotation-helpers table, or zhf-lobes table for zhf methods (default: the shipped one; "
                  "helpers computed for an order the shipped table does not cover)");
  sub->callback([opt]() {
    if (opt->coeffs.empty() == opt->in.empty()) throw InputError("give exactly one of --coeffs, --in");
    run_rotate(*opt);
  });
}

}  // namespace shtool::cli
