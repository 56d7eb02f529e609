// shtool fit-wrinkles: the wrinkle model of [4] Sec. 4.2 (docs/ldprt.md, "Wrinkles").
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "wrinkles/wrinkle_job.h"

namespace shtool::cli {

void setup_fit_wrinkles(CLI::App* sub) {
  auto req = std::make_shared<wrinkles::WrinkleRequest>();
  // Every option has a working default: --help shows each.
  sub->option_defaults()->always_capture_default();
  sub->add_option("--order", req->order, "SH order n (3..8)");
  sub->add_option("--lobes", req->lobes, "ZH lobes per point (1..4)");
  sub->add_option("--grid", req->grid, "nodes per axis of the (x, d) map");
  sub->add_option("--samples", req->samples, "simulated samples per cell and axis");
  sub->add_option("--max-depth", req->max_depth, "largest groove depth, in periods");
  sub->add_option("--rays", req->rays, "rays per sample");
  add_seed_option(sub, req->seed, "seed of the ray directions and of the per-point fits' starts");
  add_threads_option(sub, req->threads);
  sub->add_option("--max-evaluations", req->max_evaluations, "objective evaluations of the global L-BFGS fit");
  add_enum_option(sub, "--optimizer", req->optimizer,
                  {{"lbfgs", wrinkles::WrinkleOptimizer::lbfgs}, {"cg", wrinkles::WrinkleOptimizer::cg}},
                  "the global fit's optimiser: L-BFGS, or conjugate gradients (for comparison)", "lbfgs");
  sub->add_option("--out", req->out, "wrinkle-zh table to write")->required();
  sub->add_option("--json", req->json, "also a JSON summary of the fit errors");
  sub->callback([req]() {
    const wrinkles::WrinkleReport r = wrinkles::run_fit_wrinkles(*req);
    std::cerr << "fit-wrinkles: " << r.samples << " samples simulated in " << r.simulation_seconds << " s; "
              << r.parameters << " parameters fitted in " << r.fit_seconds << " s (" << r.evaluations
              << " evaluations)\n"
              << "normalized RMS: global " << r.errors.global << ", per-point " << r.errors.per_point
              << ", node fits interpolated " << r.errors.node_fits << ", start " << r.errors.start
              << "\nwrote " << req->out.string() << "\n";
  });
}

}  // namespace shtool::cli
