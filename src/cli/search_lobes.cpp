// shtool search-lobes: genetic search for sparse ZHF lobe directions ([1] Sec. 5-6). The
// job is lobes::run_search_lobes (src/offline/lobes/search_lobes_job.h); this file parses
// the options and prints progress and the summary.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "lobes/search_lobes_job.h"
#include "shtool/sh.h"

namespace shtool::cli {
namespace {

struct SearchLobesOptions {
  lobes::SearchLobesRequest request;
  std::optional<int> band;
  std::string bands;
  bool quiet = false;
};

// --band l or --bands a-b (or a single band).
std::vector<int> band_list(const SearchLobesOptions& o) {
  if (!o.band && o.bands.empty()) return {};
  if (o.band && !o.bands.empty()) throw InputError("give either --band or --bands, not both");
  if (o.band) {
    if (*o.band < 1 || *o.band >= kMaxOrder) throw InputError("--band must be in 1.." + std::to_string(kMaxOrder - 1));
    return {*o.band};
  }
  return lobes::parse_band_range(o.bands);
}

void run(SearchLobesOptions o) {
  lobes::SearchLobesRequest& r = o.request;
  r.bands = band_list(o);
  const bool tty = isatty(fileno(stderr)) && !o.quiet;
  lobes::SearchLobesCallbacks cb;
  cb.progress = [tty, quiet = o.quiet](const std::string& line, bool persistent) {
    if (quiet) return;
    if (tty) std::cerr << "\r\033[K" << line << (persistent ? "\n" : "") << std::flush;
    else if (persistent) std::cerr << line << '\n';
  };
  if (!o.quiet)
    cb.band_done = [](const lobes::SearchResult& res, double seconds) {
      std::fprintf(stderr, "search-lobes: band %d: sparsity %.1f%% (%d/%d), cond %.3g, gap %.2g / %.2g, %.1f s\n",
                   res.bands[0].l, 100 * res.sparsity, res.zeros, res.entries, res.bands[0].cond,
                   res.bands[0].largest_zero, res.bands[0].smallest_nonzero, seconds);
    };
  const lobes::SearchLobesReport report = lobes::run_search_lobes(r, cb);
  if (r.shared && !o.quiet) {
    const auto& res = report.results[0];
    double worst = 0;
    for (const auto& b : res.bands) worst = std::max(worst, b.cond);
    std::fprintf(stderr, "search-lobes: shared N=%d: sparsity %.1f%% (%d/%d), max cond %.3g, %.1f s\n", r.order,
                 100 * res.sparsity, res.zeros, res.entries, worst, report.seconds);
  } else if (!o.quiet) {
    std::fprintf(stderr, "search-lobes: total %.1f s\n", report.seconds);
  }
  if (r.out.empty() && r.json.empty()) print_json(report.summary);
}

}  // namespace

void setup_search_lobes(CLI::App* sub) {
  auto o = std::make_shared<SearchLobesOptions>();
  sub->add_option("--band", o->band,
                  "search one band l (1..127; the candidate table grows as l^5: about 3 GiB at l = 50, "
                  "91 GiB at l = 100, refused beyond half the machine's memory)");
  sub->add_option("--bands", o->bands, "search bands a-b (each independently)");
  sub->add_flag("--shared", o->request.shared, "shared lobes for an order N (2N-1 nested directions, Sec. 6)");
  sub->add_option("--order", o->request.order, "order N for --shared");
  add_seed_option(sub, o->request.search.seed, "random seed (results do not depend on --threads)");
  sub->add_option("--population", o->request.search.population, "GA population")->capture_default_str();
  sub->add_option("--crossover", o->request.search.crossover, "fraction of children made by uniform crossover")
      ->capture_default_str();
  sub->add_option("--mutation", o->request.search.mutation, "per-gene mutation rate (default 1/v)")
      ->check(CLI::Range(1e-9, 1.0));
  sub->add_option("--elitism", o->request.search.elitism, "individuals carried over unchanged")->capture_default_str();
  sub->add_option("--stall", o->request.search.stall, "stop a run after this many generations without improvement")
      ->capture_default_str();
  sub->add_option("--max-generations", o->request.search.max_generations, "hard cap on generations per run")
      ->capture_default_str();
  sub->add_option("--restarts", o->request.search.restarts, "independent runs; the best is kept")
      ->capture_default_str()
      ->each([o](const std::string&) { o->request.restarts_given = true; });
  sub->add_option("--threads", o->request.search.threads, "fitness threads (0: every core)")->capture_default_str();
  add_enum_option(sub, "--theta-candidates", o->request.search.theta,
                  {{"band", lobes::ThetaCandidates::band}, {"pooled", lobes::ThetaCandidates::pooled}},
                  "band (zeros of P_l^m, m<l, plus poles) or pooled (bands 1..l)", "band")
      ->each([o](const std::string&) { o->request.theta_given = true; });
  sub->add_option("--max-cond", o->request.search.max_cond, "largest accepted cond_2(Y_l)")->capture_default_str();
  sub->add_flag("--no-local-search", [o](std::int64_t) { o->request.search.local_search = false; },
                "skip the greedy local search step");
  sub->add_flag("--no-secondary", [o](std::int64_t) { o->request.search.secondary = false; },
                "fitness counts zeros of A^ only (no Y_l-zeros slope)");
  sub->add_flag("--paper", o->request.paper,
                "the literal paper algorithm: one run, no secondary score, no local search, pooled theta "
                "candidates (unless --restarts / --theta-candidates are given)");
  sub->add_option("--out", o->request.out, "write a zhf-lobes table (.json extension: JSON encoding)");
  sub->add_option("--json", o->request.json, "write a JSON summary");
  sub->add_flag("--quiet", o->quiet, "no progress or summary on stderr");
  sub->callback([o]() { run(*o); });
}

}  // namespace shtool::cli
