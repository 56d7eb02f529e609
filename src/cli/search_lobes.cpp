// shtool search-lobes: genetic search for sparse ZHF lobe directions ([1] Sec. 5-6).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "lobes/lobes.h"
#include "common/atomic_file.h"
#include "common/generator_record.h"
#include "common/table_writer.h"

namespace shtool::cli {
namespace {

struct SearchLobesOptions {
  int band = 0;
  std::string bands;
  bool shared = false;
  int order = 0;
  std::uint64_t seed = 1;
  lobes::SearchOptions search;
  std::string theta = "band";
  bool paper = false;
  bool theta_given = false, restarts_given = false;
  std::string out, json;
  bool quiet = false;
};

std::vector<int> band_list(const SearchLobesOptions& o) {
  if (o.band && !o.bands.empty()) throw InputError("give either --band or --bands, not both");
  if (o.band) {
    if (o.band < 1 || o.band >= kMaxOrder) throw InputError("--band must be in 1.." + std::to_string(kMaxOrder - 1));
    return {o.band};
  }
  const auto dash = o.bands.find('-');
  int a = 0, b = 0;
  try {
    std::size_t used = 0;
    if (dash == std::string::npos) {
      a = b = std::stoi(o.bands, &used);
      if (used != o.bands.size()) throw std::invalid_argument("trailing");
    } else {
      const std::string sa = o.bands.substr(0, dash), sb = o.bands.substr(dash + 1);
      a = std::stoi(sa, &used);
      if (used != sa.size()) throw std::invalid_argument("trailing");
      b = std::stoi(sb, &used);
      if (used != sb.size()) throw std::invalid_argument("trailing");
    }
  } catch (const std::exception&) {
    throw InputError("--bands: expected 'a-b' or a single band, got '" + o.bands + "'");
  }
  if (a < 1 || b < a || b >= kMaxOrder)
    throw InputError("--bands: need 1 <= a <= b < " + std::to_string(kMaxOrder) + ", got '" + o.bands + "'");
  std::vector<int> v;
  for (int l = a; l <= b; ++l) v.push_back(l);
  return v;
}

void run_search_lobes(SearchLobesOptions o) {
  lobes::SearchOptions& s = o.search;
  if (o.theta != "band" && o.theta != "pooled")
    throw InputError("--theta-candidates must be 'band' or 'pooled', got '" + o.theta + "'");
  if (o.paper) {
    // The literal algorithm of [1] Sec. 5: one GA run, zeros of A^ only, no local
    // step, theta candidates pooled over bands 1..l (unless given explicitly).
    s.secondary = false;
    s.local_search = false;
    if (!o.restarts_given) s.restarts = 1;
    if (!o.theta_given) o.theta = "pooled";
  }
  s.theta = o.theta == "pooled" ? lobes::ThetaCandidates::pooled : lobes::ThetaCandidates::band;
  s.seed = o.seed;
  std::vector<int> bands;
  if (o.shared) {
    if (o.band || !o.bands.empty()) throw InputError("--shared takes --order, not --band/--bands");
    if (o.order < 3 || o.order > kMaxOrder)
      throw InputError("--shared needs --order N with 3 <= N <= " + std::to_string(kMaxOrder));
  } else {
    if (o.order) throw InputError("--order is for --shared; per-band searches take --band or --bands");
    if (!o.band && o.bands.empty()) throw InputError("give --band l, --bands a-b, or --shared --order N");
    bands = band_list(o);
  }
  // Fail before a long search, not after it.
  if (!o.out.empty()) check_output_path(o.out, "--out");
  if (!o.json.empty()) check_output_path(o.json, "--json");

  const bool tty = isatty(fileno(stderr)) && !o.quiet;
  s.progress = [tty, quiet = o.quiet](const std::string& line, bool persistent) {
    if (quiet) return;
    if (tty) std::cerr << "\r\033[K" << line << (persistent ? "\n" : "") << std::flush;
    else if (persistent) std::cerr << line << '\n';
  };

  const nlohmann::json params = {
      {"mode", o.shared ? "shared" : "band"},
      {"bands", o.shared ? nlohmann::json(nullptr) : nlohmann::json(bands)},
      {"order", o.shared ? o.order : 0},
      {"seed", o.seed},
      {"population", s.population},
      {"crossover", s.crossover},
      {"mutation", s.mutation > 0 ? nlohmann::json(s.mutation) : nlohmann::json("1/v")},
      {"elitism", s.elitism},
      {"stall", s.stall},
      {"max_generations", s.max_generations},
      {"restarts", s.restarts},
      {"local_search", s.local_search},
      {"secondary_score", s.secondary},
      {"theta_candidates", o.theta},
      {"max_cond", s.max_cond},
      {"paper", o.paper}};
  // Threads are deliberately not recorded: results do not depend on them.

  std::vector<lobes::SearchResult> results;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (o.shared) {
      results.push_back(lobes::search_shared(o.order, s));
    } else {
      for (int l : bands) {
        const auto tb = std::chrono::steady_clock::now();
        results.push_back(lobes::search_band(l, s));
        const auto& r = results.back();
        if (!o.quiet)
          std::fprintf(stderr, "search-lobes: band %d: sparsity %.1f%% (%d/%d), cond %.3g, gap %.2g / %.2g, %.1f s\n",
                       l, 100 * r.sparsity, r.zeros, r.entries, r.bands[0].cond, r.bands[0].largest_zero,
                       r.bands[0].smallest_nonzero,
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count());
      }
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.shared && !o.quiet) {
    const auto& r = results[0];
    double worst = 0;
    for (const auto& b : r.bands) worst = std::max(worst, b.cond);
    std::fprintf(stderr, "search-lobes: shared N=%d: sparsity %.1f%% (%d/%d), max cond %.3g, %.1f s\n", o.order,
                 100 * r.sparsity, r.zeros, r.entries, worst, secs);
  } else if (!o.quiet) {
    std::fprintf(stderr, "search-lobes: total %.1f s\n", secs);
  }

  const nlohmann::json summary = lobes::lobes_summary_json(results);
  std::vector<std::string> bytes;
  bytes.reserve(2);  // outputs hold views of these
  std::vector<OutputFile> outputs;
  if (!o.out.empty()) {
    const Table t = lobes::make_lobes_table(results, generator_record("shtool search-lobes", params), s);
    const bool json = std::filesystem::path(o.out).extension() == ".json";
    bytes.push_back(encode_table(t, json ? TableEncoding::json : TableEncoding::binary));
    outputs.push_back({o.out, bytes.back()});
  }
  if (!o.json.empty()) {
    bytes.push_back(summary.dump(2) + "\n");
    outputs.push_back({o.json, bytes.back()});
  }
  write_files_atomically(outputs);
  if (o.out.empty() && o.json.empty()) print_json(summary);
}

}  // namespace

void setup_search_lobes(CLI::App& app) {
  auto o = std::make_shared<SearchLobesOptions>();
  CLI::App* sub = app.add_subcommand(
      "search-lobes",
      "Genetic search for sparse zonal-harmonic factorisations ([1]): lobe directions whose "
      "A^_l = Y_l^-1 has many zeros, per band or shared across bands. See docs/lobes.md.");
  sub->add_option("--band", o->band, "search one band l");
  sub->add_option("--bands", o->bands, "search bands a-b (each independently)");
  sub->add_flag("--shared", o->shared, "shared lobes for an order N (2N-1 nested directions, Sec. 6)");
  sub->add_option("--order", o->order, "order N for --shared");
  sub->add_option("--seed", o->seed, "random seed (results do not depend on --threads)")->capture_default_str();
  sub->add_option("--population", o->search.population, "GA population")->capture_default_str();
  sub->add_option("--crossover", o->search.crossover, "fraction of children made by uniform crossover")
      ->capture_default_str();
  sub->add_option("--mutation", o->search.mutation, "per-gene mutation rate (default 1/v)")
      ->check(CLI::Range(1e-9, 1.0));
  sub->add_option("--elitism", o->search.elitism, "individuals carried over unchanged")->capture_default_str();
  sub->add_option("--stall", o->search.stall, "stop a run after this many generations without improvement")
      ->capture_default_str();
  sub->add_option("--max-generations", o->search.max_generations, "hard cap on generations per run")
      ->capture_default_str();
  sub->add_option("--restarts", o->search.restarts, "independent runs; the best is kept")
      ->capture_default_str()
      ->each([o](const std::string&) { o->restarts_given = true; });
  sub->add_option("--threads", o->search.threads, "fitness threads")->capture_default_str();
  sub->add_option("--theta-candidates", o->theta, "band (zeros of P_l^m, m<l, plus poles) or pooled (bands 1..l)")
      ->capture_default_str()
      ->each([o](const std::string&) { o->theta_given = true; });
  sub->add_option("--max-cond", o->search.max_cond, "largest accepted cond_2(Y_l)")->capture_default_str();
  sub->add_flag("--no-local-search", [o](std::int64_t) { o->search.local_search = false; },
                "skip the greedy local search step");
  sub->add_flag("--no-secondary", [o](std::int64_t) { o->search.secondary = false; },
                "fitness counts zeros of A^ only (no Y_l-zeros slope)");
  sub->add_flag("--paper", o->paper,
                "the literal paper algorithm: one run, no secondary score, no local search, pooled theta "
                "candidates (unless --restarts / --theta-candidates are given)");
  sub->add_option("--out", o->out, "write a zhf-lobes table (.json extension: JSON encoding)");
  sub->add_option("--json", o->json, "write a JSON summary");
  sub->add_flag("--quiet", o->quiet, "no progress or summary on stderr");
  sub->callback([o]() { run_search_lobes(*o); });
}

}  // namespace shtool::cli
