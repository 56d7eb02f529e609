// Reading an environment image against projecting it: project-env's two phases on one
// 4096 x 2048 random float RGB image, encoded once in memory by shtool's own writers.
//
//   BM_DecodeExr      decode_image of the float ZIP OpenEXR (100 MB)
//   BM_DecodePng      decode_image of the 8-bit PNG (exact sRGB decode)
//   BM_Project/N      project_equirect of the decoded image, order N (one thread)
//
//   build/bench/bench_images --benchmark_min_time=0.1 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <random>
#include <string>

#include <benchmark/benchmark.h>

#include "lighting/image_io.h"
#include "shtool/env_projection.h"

namespace {

const shtool::lighting::Image& image() {
  static const shtool::lighting::Image img = [] {
    shtool::lighting::Image i;
    i.width = 4096;
    i.height = 2048;
    i.texels.resize(static_cast<std::size_t>(i.width) * i.height * 3);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0, 4);
    for (float& v : i.texels) v = u(rng);
    return i;
  }();
  return img;
}

void BM_DecodeExr(benchmark::State& state) {
  static const std::string bytes = shtool::lighting::encode_exr(image());
  for (auto _ : state) benchmark::DoNotOptimize(shtool::lighting::decode_image(bytes, "bench.exr"));
  state.counters["MB"] = bytes.size() / 1e6;
}
BENCHMARK(BM_DecodeExr)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DecodePng(benchmark::State& state) {
  static const std::string bytes = shtool::lighting::encode_png(image());
  for (auto _ : state) benchmark::DoNotOptimize(shtool::lighting::decode_image(bytes, "bench.png"));
  state.counters["MB"] = bytes.size() / 1e6;
}
BENCHMARK(BM_DecodePng)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Project(benchmark::State& state) {
  const shtool::FloatImageView view = image().view();
  for (auto _ : state) benchmark::DoNotOptimize(shtool::project_equirect(view, static_cast<int>(state.range(0))));
}
BENCHMARK(BM_Project)->Arg(3)->Arg(10)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
