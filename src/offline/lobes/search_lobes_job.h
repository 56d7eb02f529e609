// search-lobes as a library job: the genetic search of [1] Sec. 5-6 per band or shared
// across bands, its zhf-lobes table and JSON summary written all together or not at all.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lobes/lobes.h"

namespace shtool::lobes {

struct SearchLobesRequest {
  std::vector<int> bands;  // per-band searches (each independently); empty with `shared`
  bool shared = false;     // shared lobes for `order` (2N-1 nested directions, [1] Sec. 6)
  int order = 0;
  SearchOptions search;    // seed and threads included; `progress` is set from the callbacks
  bool paper = false;      // the literal algorithm of [1] Sec. 5 (see run_search_lobes)
  bool restarts_given = false, theta_given = false;  // explicit values survive `paper`
  std::filesystem::path out;   // zhf-lobes table (".json" extension: JSON encoding); may be empty
  std::filesystem::path json;  // JSON summary; may be empty
};

struct SearchLobesCallbacks {
  // Status lines (persistent = false: a transient line that the next one replaces).
  std::function<void(const std::string& line, bool persistent)> progress;
  // After each per-band search, with its wall time.
  std::function<void(const SearchResult& result, double seconds)> band_done;
};

struct SearchLobesReport {
  std::vector<SearchResult> results;
  nlohmann::json summary;  // what --json holds (and the CLI prints when nothing is written)
  double seconds = 0;
};

// Checks the request (InputError) and every output path before the search, runs it,
// writes the outputs. With `paper`: one run, no secondary score, no local search, theta
// candidates pooled over bands 1..l (unless restarts / theta were given explicitly).
SearchLobesReport run_search_lobes(SearchLobesRequest request, const SearchLobesCallbacks& callbacks = {});

// The bands of "--bands a-b" (or one band "l"): InputError unless 1 <= a <= b < kMaxOrder.
std::vector<int> parse_band_range(const std::string& text);

}  // namespace shtool::lobes
