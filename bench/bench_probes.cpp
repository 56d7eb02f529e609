// bake-probes' light transport against a bare Embree loop over the same scene, in the
// same run:
//
//   BM_BakeProbes        bake_probe_grid (what `shtool bake-probes` runs after loading)
//                        on a 4 x 4 x 4 grid, 256 directions per probe, 3 bounces, on
//                        every core. Counter rays_per_s: the bake's rays (first hits,
//                        continuations and shadow rays) per second.
//   BM_BareEmbreeRays    rtcIntersect1 of as many rays, from the same probe positions in
//                        uniformly random directions, nothing else, on every core.
//
// The scene is scripts/make_probe_interior.py's interior (SHTOOL_PROBE_SCENE names another
// OBJ, z up): written to a temporary folder before the timing. Run:
//   build/bench/bench_probes
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include <benchmark/benchmark.h>

#include "common/parallel_for.h"
#include "common/random.h"
#include "probes/probe_bake.h"
#include "scene/scene.h"

#ifndef SHTOOL_SOURCE_DIR
#error "bench_probes needs SHTOOL_SOURCE_DIR (set in bench/CMakeLists.txt)"
#endif

namespace {

namespace fs = std::filesystem;
using namespace shtool;

const scene::Scene& interior() {
  static std::unique_ptr<scene::Scene> s = [] {
    fs::path path;
    if (const char* env = std::getenv("SHTOOL_PROBE_SCENE")) {
      path = env;
    } else {
      path = fs::temp_directory_path() / "shtool_bench_probes_interior.obj";
      const std::string cmd = std::string("python3 ") + SHTOOL_SOURCE_DIR + "/scripts/make_probe_interior.py " +
                              path.string() + " 250000 > /dev/null";
      if (std::system(cmd.c_str()) != 0) throw std::runtime_error("make_probe_interior.py failed");
    }
    return std::make_unique<scene::Scene>(scene::load_scene(path, UpAxis::z));
  }();
  return *s;
}

probes::ProbeGridSpec bench_grid(const scene::Scene& s) {
  probes::ProbeGridSpec spec;
  spec.resolution = {4, 4, 4};
  spec.lower = s.lower();
  spec.upper = s.upper();
  spec.order = 3;
  spec.samples = 256;
  spec.bounces = 3;
  spec.threads = 0;
  return spec;
}

std::uint64_t baked_rays = 0;

void BM_BakeProbes(benchmark::State& state) {
  const scene::Scene& s = interior();
  const probes::ProbeGridSpec spec = bench_grid(s);
  std::uint64_t rays = 0;
  for (auto _ : state) {
    const probes::ProbeBake b = probes::bake_probe_grid(s, spec, {});
    rays += b.rays;
    baked_rays = b.rays;
    benchmark::DoNotOptimize(b.coefficients.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
  state.counters["triangles"] = static_cast<double>(s.mesh.triangles.size());
}
BENCHMARK(BM_BakeProbes)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

void BM_BareEmbreeRays(benchmark::State& state) {
  const scene::Scene& s = interior();
  const probes::ProbeGridSpec spec = bench_grid(s);
  const std::size_t probes_count = spec.probe_count();
  const std::uint64_t per_probe = baked_rays ? baked_rays / probes_count : 1024;
  std::uint64_t rays = 0;
  for (auto _ : state) {
    std::vector<int> hits(probes_count, 0);
    parallel_for(probes_count, resolve_threads(0), [&](std::size_t p) {
      const Eigen::Vector3d origin = spec.position(p);
      SplitMixStream rng{splitmix64(p + 1)};
      int h = 0;
      for (std::uint64_t j = 0; j < per_probe; ++j) {
        const double z = 1 - 2 * rng.uniform(), phi = 2 * 3.141592653589793 * rng.uniform();
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        RTCRayHit rh{};
        rh.ray = s.embree->ray(origin, Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z));
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        rtcIntersect1(s.embree->scene, &ctx, &rh);
        h += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      }
      hits[p] = h;
    });
    rays += per_probe * probes_count;
    benchmark::DoNotOptimize(hits.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BareEmbreeRays)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
