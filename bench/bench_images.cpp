// Reading an environment image against projecting it: project-env's phases on random
// float RGB images, encoded once in memory by shtool's own writers.
//
//   BM_DecodeExr/T        decode_image of a 4096 x 2048 float ZIP OpenEXR (100 MB) on T
//                         threads (OpenEXR's pool; 0: every core)
//   BM_DecodeExrCppLibrary/T  the same bytes decoded by OpenEXR's C++ library, its pool at T
//   BM_Crc32              input_crc32 of the same bytes (what read_image hashes)
//   BM_ReadFile           read_input_file of that file (page cache to memory)
//   BM_ReadImage/T        read_image of that file: read once, decoded on T threads, hashed
//   BM_DecodePng          decode_image of the 8-bit PNG (exact sRGB decode)
//   BM_Project/N          project_equirect of the decoded image, order N (one thread)
//   BM_ProjectEnvExr/T    the whole `project-env` job on the EXR file (order 3, JSON out)
//   BM_ProjectEnvEquirect, BM_ProjectEnvCross
//                         the whole job at order 6 on a 2048 x 1024 equirect and on a
//                         2048 x 1536 horizontal cross of 512^2 faces (float ZIP EXR,
//                         every core); items_per_second: projected texels per second
//
//   build/bench/bench_images --benchmark_min_time=0.1 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <benchmark/benchmark.h>

#include <ImfThreading.h>

#include "common/input_file.h"
#include "lighting/exr_cpp_library.h"
#include "lighting/image_io.h"
#include "lighting/project_env_job.h"
#include "shtool/env_projection.h"

namespace {

shtool::lighting::Image random_image(int width, int height, unsigned seed) {
  shtool::lighting::Image i;
  i.width = width;
  i.height = height;
  i.texels.resize(static_cast<std::size_t>(i.width) * i.height * 3);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 4);
  for (float& v : i.texels) v = u(rng);
  return i;
}

const shtool::lighting::Image& image() {
  static const shtool::lighting::Image img = random_image(4096, 2048, 1);
  return img;
}

const std::string& exr_bytes() {
  static const std::string bytes = shtool::lighting::encode_exr(image());
  return bytes;
}

// A folder of this process's files, removed at exit (the handler is registered once the
// path exists, so that it runs before the path's destructor).
const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d = std::filesystem::temp_directory_path() / ("shtool_bench_images_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  static const bool cleanup = std::atexit([] { std::filesystem::remove_all(folder()); }) == 0;
  (void)cleanup;
  return dir;
}

std::filesystem::path write_file(const std::string& name, const std::string& bytes) {
  const std::filesystem::path p = folder() / name;
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p;
}

void BM_DecodeExr(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const std::string& bytes = exr_bytes();
  for (auto _ : state)
    benchmark::DoNotOptimize(shtool::lighting::decode_image(bytes, "bench.exr", shtool::lighting::kMaxImageTexels, threads));
  state.counters["MB"] = exr_bytes().size() / 1e6;
}
BENCHMARK(BM_DecodeExr)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

// The peer: OpenEXR's C++ library decoding the same bytes into the same layout, its
// global pool at T workers (0: none, the calling thread decodes).
void BM_DecodeExrCppLibrary(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  Imf::setGlobalThreadCount(threads);
  for (auto _ : state)
    benchmark::DoNotOptimize(shtool::lighting::decode_exr_with_cpp_library(exr_bytes(), {"R", "G", "B"}, threads));
  Imf::setGlobalThreadCount(0);
}
BENCHMARK(BM_DecodeExrCppLibrary)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Crc32(benchmark::State& state) {
  const std::string& bytes = exr_bytes();
  for (auto _ : state) benchmark::DoNotOptimize(shtool::input_crc32(bytes));
}
BENCHMARK(BM_Crc32)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadFile(benchmark::State& state) {
  static const std::filesystem::path path = write_file("read.exr", exr_bytes());
  for (auto _ : state) benchmark::DoNotOptimize(shtool::read_input_file(path, "image"));
}
BENCHMARK(BM_ReadFile)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadImage(benchmark::State& state) {
  static const std::filesystem::path path = write_file("read.exr", exr_bytes());
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(shtool::lighting::read_image(path, "image", threads));
}
BENCHMARK(BM_ReadImage)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

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

void run_job(benchmark::State& state, const std::filesystem::path& path, int order, int threads,
             std::size_t projected_texels) {
  shtool::lighting::ProjectEnvRequest r;
  r.image = path;
  r.order = order;
  r.threads = threads;
  r.json = folder() / (path.stem().string() + ".json");
  for (auto _ : state) benchmark::DoNotOptimize(shtool::lighting::run_project_env(r));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * projected_texels));
}

void BM_ProjectEnvExr(benchmark::State& state) {
  static const std::filesystem::path path = write_file("job.exr", exr_bytes());
  run_job(state, path, 3, static_cast<int>(state.range(0)), std::size_t{4096} * 2048);
}
BENCHMARK(BM_ProjectEnvExr)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ProjectEnvEquirect(benchmark::State& state) {
  static const std::filesystem::path path =
      write_file("equirect.exr", shtool::lighting::encode_exr(random_image(2048, 1024, 2)));
  run_job(state, path, 6, 0, std::size_t{2048} * 1024);
}
BENCHMARK(BM_ProjectEnvEquirect)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ProjectEnvCross(benchmark::State& state) {
  static const std::filesystem::path path =
      write_file("cross.exr", shtool::lighting::encode_exr(random_image(2048, 1536, 3)));
  run_job(state, path, 6, 0, std::size_t{6} * 512 * 512);
}
BENCHMARK(BM_ProjectEnvCross)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
