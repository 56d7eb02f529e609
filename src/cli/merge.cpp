// shtool merge: the partial tables of fit-zh --shard K/N joined into one table, byte for
// byte the one a single process writes. The job is fit::merge_zh_fit_parts
// (src/offline/fit/zh_fit_merge.h); this file parses and prints.
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "common/input_error.h"
#include "common/stopwatch.h"
#include "fit/zh_fit_merge.h"
#include "probes/probe_grid_table.h"

namespace shtool::cli {

void setup_merge(CLI::App* sub) {
  auto opt = std::make_shared<fit::MergeRequest>();
  sub->add_option("parts", opt->parts, "partial tables, every shard 0..N-1 once, in any order")->required();
  sub->add_option("--out", opt->out, "the merged table")->required();
  add_table_format_option(sub, opt->encoding);
  auto json = std::make_shared<std::filesystem::path>();
  auto threejs = std::make_shared<std::filesystem::path>();
  sub->add_option("--json", *json, "probe-grid parts: also the grid as JSON, as bake-probes --json writes it");
  sub->add_option("--threejs", *threejs,
                  "probe-grid parts: also three.js's probes.json and probes.bin in this folder, as bake-probes "
                  "--threejs writes them");
  sub->callback([opt, json, threejs]() {
    const auto t0 = std::chrono::steady_clock::now();
    // The first part's kind decides (the merge then checks that every part has it).
    if (probes::is_probe_grid_file(opt->parts.front())) {
      const probes::ProbeMergeReport r =
          probes::merge_probe_grid_parts(opt->parts, opt->out, opt->encoding, *json, *threejs);
      std::ostringstream summary;
      summary.precision(3);
      summary << "merge: " << r.parts << " parts, " << r.probes << " probes, " << seconds_since(t0) << " s, wrote "
              << opt->out.string();
      if (!json->empty()) summary << ", " << json->string();
      if (!threejs->empty()) summary << ", " << (*threejs / "probes.json").string() << ", probes.bin";
      summary << '\n';
      std::cerr << summary.str();
      return;
    }
    if (!json->empty() || !threejs->empty())
      throw InputError(std::string(!json->empty() ? "--json" : "--threejs") +
                       ": only for the parts of bake-probes --shard (fit-zh's parts join into the table alone)");
    const fit::MergeReport r = fit::merge_zh_fit_parts(*opt);
    std::ostringstream summary;
    summary.precision(3);
    summary << "merge: " << r.parts << " parts, " << r.vertices << " vertices, " << seconds_since(t0)
            << " s, wrote " << opt->out.string() << '\n';
    std::cerr << summary.str();
  });
}

}  // namespace shtool::cli
