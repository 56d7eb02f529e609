#include "lobes/search_lobes_job.h"

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/finite.h"
#include "common/job_outputs.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/table_writer.h"
#include "shtool/sh.h"

namespace shtool::lobes {

std::vector<int> parse_band_range(const std::string& text) {
  const auto dash = text.find('-');
  int a = 0, b = 0;
  try {
    std::size_t used = 0;
    if (dash == std::string::npos) {
      a = b = std::stoi(text, &used);
      if (used != text.size()) throw std::invalid_argument("trailing");
    } else {
      const std::string sa = text.substr(0, dash), sb = text.substr(dash + 1);
      a = std::stoi(sa, &used);
      if (used != sa.size()) throw std::invalid_argument("trailing");
      b = std::stoi(sb, &used);
      if (used != sb.size()) throw std::invalid_argument("trailing");
    }
  } catch (const std::exception&) {
    throw InputError("--bands: expected 'a-b' or a single band, got '" + text + "'");
  }
  if (a < 1 || b < a || b >= kMaxOrder)
    throw InputError("--bands: need 1 <= a <= b < " + std::to_string(kMaxOrder) + ", got '" + text + "'");
  std::vector<int> v;
  for (int l = a; l <= b; ++l) v.push_back(l);
  return v;
}

SearchLobesReport run_search_lobes(SearchLobesRequest r, const SearchLobesCallbacks& cb) {
  SearchOptions& s = r.search;
  if (r.paper) {
    s.secondary = false;
    s.local_search = false;
    if (!r.restarts_given) s.restarts = 1;
    if (!r.theta_given) s.theta = ThetaCandidates::pooled;
  }
  if (r.shared) {
    if (!r.bands.empty()) throw InputError("--shared takes --order, not --band/--bands");
    if (r.order < 3 || r.order > kMaxOrder)
      throw InputError("--shared needs --order N with 3 <= N <= " + std::to_string(kMaxOrder));
  } else {
    if (r.order) throw InputError("--order is for --shared; per-band searches take --band or --bands");
    if (r.bands.empty()) throw InputError("give --band l, --bands a-b, or --shared --order N");
    for (int l : r.bands)
      if (l < 1 || l >= kMaxOrder)
        throw InputError("band " + std::to_string(l) + ": bands are 1.." + std::to_string(kMaxOrder - 1));
  }
  // Fail before a long search, not after it.
  JobOutputs io;
  io.output(r.out, "--out");
  io.output(r.json, "--json");
  s.progress = cb.progress;

  const nlohmann::json params = {
      {"mode", r.shared ? "shared" : "band"},
      {"bands", r.shared ? nlohmann::json(nullptr) : nlohmann::json(r.bands)},
      {"order", r.shared ? r.order : 0},
      {"seed", s.seed},
      {"population", s.population},
      {"crossover", s.crossover},
      {"mutation", s.mutation > 0 ? nlohmann::json(s.mutation) : nlohmann::json("1/v")},
      {"elitism", s.elitism},
      {"stall", s.stall},
      {"max_generations", s.max_generations},
      {"restarts", s.restarts},
      {"local_search", s.local_search},
      {"secondary_score", s.secondary},
      {"theta_candidates", s.theta == ThetaCandidates::pooled ? "pooled" : "band"},
      {"max_cond", s.max_cond},
      {"paper", r.paper}};
  // Threads are deliberately not recorded: results do not depend on them.

  SearchLobesReport report;
  const auto t0 = std::chrono::steady_clock::now();
  if (r.shared) {
    report.results.push_back(search_shared(r.order, s));
  } else {
    for (int l : r.bands) {
      const auto tb = std::chrono::steady_clock::now();
      report.results.push_back(search_band(l, s));
      if (cb.band_done)
        cb.band_done(report.results.back(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count());
    }
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report.summary = lobes_summary_json(report.results);

  if (io.requested("--out")) {
    const Table t = make_lobes_table(report.results, generator_record("shtool search-lobes", params), s);
    io.set("--out", encode_table(t, r.out.extension() == ".json" ? TableEncoding::json : TableEncoding::binary));
  }
  if (io.requested("--json")) io.set("--json", dump_finite(report.summary, "--json", 2) + "\n");
  io.commit();
  return report;
}

}  // namespace shtool::lobes
