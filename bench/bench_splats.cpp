// transform-splats on synthetic 3D Gaussian Splatting scenes: the whole job (read the
// file, transform every splat, write the file), as the command runs it.
//
//   BM_TransformSplats/splats:S/threads:T   S degree-3 splats in the reference
//                                           implementation's binary layout (62 floats
//                                           each), rotation + scale + translation;
//                                           counter splats_per_s, and the file size.
//   BM_CopyFile/splats:S                    read the same file and write it back
//                                           (read_input_file, write_file_atomically).
//   BM_ConvertSplats/format:F/splats:S      the job from format F to F (1: spz v4,
//                                           2: glb) with the same rotation, through
//                                           the scene, 2 threads.
//   BM_BareCodec/format:F/splats:S          the floor of that: read the file, decode
//                                           it, encode it, write it, no transform.
//                                           Format 0, PLY, is the floor of the PLY job
//                                           through its own I/O calls: the file mapped,
//                                           its header parsed, the records written in
//                                           pieces from 2 threads (rewrite_binary_ply
//                                           without an edit), the same commit.
//
// The files are made once per size in the temporary folder and removed at exit. The
// job and its floor run in one process, one after the other (the same page cache, about
// the same machine load); "Time" is the wall time, "CPU" the process's CPU time over all
// threads (user + system), the work done, which a machine loaded by others disturbs
// less. At 6 M splats (1.5 GB of PLY):
//   build/bench/bench_splats --benchmark_filter='splats:6291456'
//   build/bench/bench_splats --benchmark_counters_tabular=true
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/atomic_file.h"
#include "common/input_file.h"
#include "common/job_outputs.h"
#include "interop/ply.h"
#include "interop/splat_gltf.h"
#include "interop/splat_ply.h"
#include "interop/splats_job.h"
#include "interop/spz.h"

namespace {

namespace fs = std::filesystem;

const fs::path& scene(std::size_t splats) {
  static std::map<std::size_t, fs::path> made;
  auto it = made.find(splats);
  if (it != made.end()) return it->second;
  const fs::path path = fs::temp_directory_path() / ("shtool_bench_splats_" + std::to_string(splats) + ".ply");
  std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(splats) + "\n";
  for (const char* n : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    header += std::string("property float ") + n + "\n";
  for (int k = 0; k < 45; ++k) header += "property float f_rest_" + std::to_string(k) + "\n";
  for (const char* n : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    header += std::string("property float ") + n + "\n";
  header += "end_header\n";
  std::ofstream out(path, std::ios::binary);
  out << header;
  std::mt19937 rng(1);
  std::normal_distribution<float> g;
  std::vector<float> record(62);
  for (std::size_t i = 0; i < splats; ++i) {
    for (float& v : record) v = g(rng);
    out.write(reinterpret_cast<const char*>(record.data()), static_cast<std::streamsize>(record.size() * 4));
  }
  return made.emplace(splats, path).first->second;
}

void BM_TransformSplats(benchmark::State& state) {
  const std::size_t splats = static_cast<std::size_t>(state.range(0));
  shtool::interop::TransformSplatsRequest r;
  r.in = scene(splats);
  r.out = fs::temp_directory_path() / "shtool_bench_splats_out.ply";
  r.quaternion = std::array<double, 4>{0.8, -0.3, 0.4, 0.33};
  r.scale = 2;
  r.translate = {1, 2, 3};
  r.threads = static_cast<int>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(shtool::interop::run_transform_splats(r));
  state.counters["splats_per_s"] = benchmark::Counter(static_cast<double>(splats), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MiB"] = static_cast<double>(fs::file_size(r.in)) / (1 << 20);
  fs::remove(r.out);
}
BENCHMARK(BM_TransformSplats)
    ->ArgsProduct({{1 << 20, 6 << 20}, {1, 2}})
    ->ArgNames({"splats", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->MeasureProcessCPUTime()->UseRealTime();

void BM_CopyFile(benchmark::State& state) {
  const fs::path in = scene(static_cast<std::size_t>(state.range(0)));
  const fs::path out = fs::temp_directory_path() / "shtool_bench_splats_copy.ply";
  for (auto _ : state) shtool::write_file_atomically(out, shtool::read_input_file(in, "input"));
  fs::remove(out);
}
BENCHMARK(BM_CopyFile)->Arg(1 << 20)->Arg(6 << 20)->ArgName("splats")->Unit(benchmark::kMillisecond)->Iterations(1)->MeasureProcessCPUTime()->UseRealTime();

// The scene of scene(splats) in format 1 (spz v4) or 2 (glb), made once; format 0 is
// the PLY itself.
const fs::path& scene_as(int format, std::size_t splats) {
  if (format == 0) return scene(splats);
  static std::map<std::pair<int, std::size_t>, fs::path> made;
  const auto key = std::make_pair(format, splats);
  auto it = made.find(key);
  if (it != made.end()) return it->second;
  shtool::interop::TransformSplatsRequest r;
  r.in = scene(splats);
  r.out = fs::temp_directory_path() / ("shtool_bench_splats_" + std::to_string(splats) + (format == 1 ? ".spz" : ".glb"));
  shtool::interop::run_transform_splats(r);
  return made.emplace(key, r.out).first->second;
}

void BM_ConvertSplats(benchmark::State& state) {
  const int format = static_cast<int>(state.range(0));
  const std::size_t splats = static_cast<std::size_t>(state.range(1));
  shtool::interop::TransformSplatsRequest r;
  r.in = scene_as(format, splats);
  r.out = fs::temp_directory_path() / (std::string("shtool_bench_splats_out") + (format == 1 ? ".spz" : ".glb"));
  r.quaternion = std::array<double, 4>{0.8, -0.3, 0.4, 0.33};
  r.threads = 2;
  for (auto _ : state) benchmark::DoNotOptimize(shtool::interop::run_transform_splats(r));
  state.counters["splats_per_s"] = benchmark::Counter(static_cast<double>(splats), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MiB"] = static_cast<double>(fs::file_size(r.in)) / (1 << 20);
  fs::remove(r.out);
}
BENCHMARK(BM_ConvertSplats)
    ->ArgsProduct({{1, 2}, {1 << 20, 6 << 20}})
    ->ArgNames({"format", "splats"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->MeasureProcessCPUTime()->UseRealTime();

void BM_BareCodec(benchmark::State& state) {
  const int format = static_cast<int>(state.range(0));
  const std::size_t splats = static_cast<std::size_t>(state.range(1));
  const fs::path in = scene_as(format, splats);
  const fs::path out = fs::temp_directory_path() /
                       (std::string("shtool_bench_splats_bare") + (format == 0 ? ".ply" : format == 1 ? ".spz" : ".glb"));
  for (auto _ : state) {
    if (format == 0) {
      shtool::JobOutputs io;
      io.input(in, "the input scene");
      io.output(out, "--out");
      const shtool::MappedInput mapped(in, "input");
      const shtool::interop::PlyFile header = shtool::interop::PlyFile::parse_header(mapped.bytes(), in);
      shtool::PendingFile file(out);
      shtool::interop::rewrite_binary_ply(mapped.bytes(), *header.element("vertex"), file, 2, {});
      io.set_written("--out", std::move(file));
      io.commit();
      continue;
    }
    const std::string bytes = shtool::read_input_file(in, "input");
    if (format == 1) {
      const shtool::interop::SplatScene s = shtool::interop::read_spz(bytes, in.string(), nullptr, 2);
      shtool::write_file_atomically(out, shtool::interop::write_spz(s, {}, 2));
    } else {
      const shtool::interop::SplatScene s = shtool::interop::read_gltf_splats(bytes, in);
      shtool::write_file_atomically(out, shtool::interop::write_gltf_splats(s, true));
    }
  }
  fs::remove(out);
}
BENCHMARK(BM_BareCodec)
    ->ArgsProduct({{0, 1, 2}, {1 << 20, 6 << 20}})
    ->ArgNames({"format", "splats"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->MeasureProcessCPUTime()->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  for (std::size_t s : {std::size_t(1) << 20, std::size_t(6) << 20})
    for (const char* ext : {".ply", ".spz", ".glb"})
      fs::remove(fs::temp_directory_path() / ("shtool_bench_splats_" + std::to_string(s) + ext));
  return 0;
}
