// shtool eval --order N --dir x,y,z : all N^2 real SH values at a direction.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "common/sh_inputs.h"
#include "shtool/sh.h"

namespace shtool::cli {
namespace {

struct EvalOptions {
  int order = 3;
  std::string dir;
};

void run_eval(const EvalOptions& opt) {
  if (!is_supported_order(opt.order))
    throw InputError("--order " + std::to_string(opt.order) + " is not supported (1.." +
                    std::to_string(kMaxOrder) + ")");
  const std::vector<double> d = parse_number_list(opt.dir, "--dir");
  if (d.size() != 3)
    throw InputError("--dir needs 3 components x,y,z, got " + std::to_string(d.size()));
  Vec3<double> w(d[0], d[1], d[2]);
  if (!normalize_direction(w)) throw InputError("--dir must be a non-zero vector, got '" + opt.dir + "'");
  std::vector<double> values(sh_count(opt.order));
  eval_sh<double>(opt.order, w, values);
  print_json({{"order", opt.order}, {"values", values}});
}

}  // namespace

void setup_eval(CLI::App* sub) {
  auto opt = std::make_shared<EvalOptions>();
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->required();
  sub->add_option("--dir", opt->dir, "direction x,y,z (normalised before evaluation)")->required();
  sub->callback([opt]() { run_eval(*opt); });
}

}  // namespace shtool::cli
