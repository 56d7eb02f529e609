// Whole fit-zh bakes at scale: how time and memory grow with the vertex count.
//
//   BM_BakeSphere/rows:R/cols:C
//       run_fit_zh (what `shtool fit-zh SPHERE.obj` runs: OBJ read, shadowed order-6
//       transfer with 1024 rays, 4-lobe fit at the default effort, table written) on a
//       unit sphere of 2 + (R - 1) C vertices that scripts/make_sphere.py writes before
//       the timing, on every core. One iteration (a bake is minutes at 2M vertices).
//       Counters: vertices; sim_s and fit_s, the job's own split; peak_rss_MiB, the
//       process's resident high-water mark after the bake (getrusage), and
//       peak_bytes_per_vertex = peak_rss / vertices. The high-water mark never goes
//       down, so the cases are registered smallest first: each reports its own peak as
//       long as it is the largest run so far. For one case alone:
//         build/bench/bench_bake --benchmark_filter='BM_BakeSphere/rows:1000/'
//       (1000 x 2000: 1,998,002 vertices).
#include <sys/resource.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include <benchmark/benchmark.h>

#include "fit/fit_zh_job.h"

#ifndef SHTOOL_SOURCE_DIR
#error "bench_bake needs SHTOOL_SOURCE_DIR (set in bench/CMakeLists.txt)"
#endif

namespace {

namespace fs = std::filesystem;

double peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return 1024.0 * static_cast<double>(usage.ru_maxrss);  // Linux reports KiB
}

// The sphere as the documented script writes it, so the benchmark bakes exactly what a
// user reproducing the figure bakes.
fs::path sphere_obj(const fs::path& dir, long rows, long cols) {
  const fs::path obj = dir / ("sphere-" + std::to_string(rows) + "x" + std::to_string(cols) + ".obj");
  const std::string command = "python3 '" SHTOOL_SOURCE_DIR "/scripts/make_sphere.py' " + std::to_string(rows) + " " +
                              std::to_string(cols) + " '" + obj.string() + "'";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  return obj;
}

void BM_BakeSphere(benchmark::State& state) {
  const long rows = state.range(0), cols = state.range(1);
  const fs::path dir = fs::temp_directory_path() / ("shtool-bench-bake-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  shtool::fit::FitZhRequest request;
  shtool::fit::FitZhReport report;
  try {
    request.mesh = sphere_obj(dir, rows, cols);
    request.out = dir / "sphere.zh.shtb";
    for (auto _ : state) report = shtool::fit::run_fit_zh(request, {});
  } catch (const std::exception& e) {
    fs::remove_all(dir);
    return state.SkipWithError(e.what());
  }
  const double peak = peak_rss_bytes();
  fs::remove_all(dir);
  state.counters["vertices"] = static_cast<double>(report.count);
  state.counters["sim_s"] = report.simulate_seconds;
  state.counters["fit_s"] = report.fit_seconds;
  state.counters["nrms"] = report.normalized_rms;
  state.counters["peak_rss_MiB"] = peak / (1024.0 * 1024.0);
  state.counters["peak_bytes_per_vertex"] = peak / static_cast<double>(report.count);
}
BENCHMARK(BM_BakeSphere)
    ->ArgNames({"rows", "cols"})
    ->Args({100, 200})     // 19,802 vertices
    ->Args({316, 632})     // 199,082
    ->Args({1000, 2000})   // 1,998,002
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
