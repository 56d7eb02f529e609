// fit-zh side by side: transfer simulation, ZH fitting and shading.
//
//   BM_Transfer/rays:R          shadowed order-6 transfer of data/spot.obj on ONE thread
//                               (compute_transfer, cosine-weighted rays); per_vertex = time
//                               per vertex.
//   BM_EmbreeOcclusion/<query>/rays:R
//                               Embree alone: the occlusion rays a shadowed transfer of the
//                               Stanford bunny (shared/meshes beside the checkout, CMake's
//                               SHTOOL_BENCH_MESHES) casts
//                               with R rays per vertex, every vertex, ONE thread, directions
//                               made before timing; rays_per_s = occlusion queries per CPU
//                               second. Queries: single (rtcOccluded1, what compute_transfer
//                               casts), packet4 (rtcOccluded4: 4 consecutive rays of a
//                               vertex, native width of the SSE4.2 kernels the device is
//                               pinned to), stream_coherent / stream_incoherent
//                               (rtcOccluded1M over a vertex's rays with the context flag).
//                               blocked = fraction occluded (equal for every query).
//   BM_TransferBunny/rays:R/streams:S/bounces:B
//                               compute_transfer (order 6) on the same bunny and rays, ONE
//                               thread: the loop Embree's rate bounds, with ray making, SH
//                               evaluation and accumulation; the scene build is inside
//                               (BM_EmbreeBuild times it alone). B = 0: shadowed; B > 0:
//                               interreflected with B bounces (closest hits, albedo 0.8).
//                               S = 0: one rtcOccluded1 / rtcIntersect1 per ray; S = 1: a
//                               stream per vertex (default). rays_per_s counts every pass.
//   BM_EmbreeBuild              build_scene of the bunny (Embree's own threads build it).
//   BM_Fit/method:M/lobes:N/effort:E/starts:S/set:X
//                               fit_zh of the vectors of the fit fixture
//                               (tests/offline/data/zh_fit_best_known.json): X = 0 the 20
//                               random unit order-6 vectors (coefficients uniform in
//                               [-1, 1], normalised), X = 1 40 shadowed transfer vectors of
//                               data/spot.obj; M = 0 variable projection (the default),
//                               1 joint (the reference); --effort E; S >= 0 overrides the
//                               starts. per_vector = time per fit, nrms = sqrt(sum
//                               residual^2 / sum |t|^2); vs_best_mean / vs_best_max =
//                               residual over the fixture's best known fit of the vector;
//                               mean_vs_best = the mean residual over the best knowns' mean.
//   --write-best-known=PATH     computes that fixture (vectors, best-known residuals for
//                               N = 1, 2, 4; minutes on 2 cores) and writes it, then exits;
//                               an existing PATH keeps its vectors and lowers its best knowns.
//   BM_Shade/<type>/<method>/lobes:N[/res:R]
//                               one shaded point = N lobes against one order-6 light;
//                               4096 points with random axes per iteration (random table
//                               access: the cache-unfriendly case); per_shade = time per
//                               point. Methods:
//                                 table         ZhLightTable::shade (Eq. 25, bilinear cube
//                                               map of resolution R)
//                                 exact         zh_shade_exact (band sums of Eq. 24 at s)
//                                 sh_dot        n^2 dot product of a full transfer vector
//                                               with the light (transfer already rotated)
//                                 sh_rotate_dot ShRotation set (automatic method, random
//                                               rotation) + apply + n^2 dot: what a point
//                                               costs when SH transfer is rotated instead
//   BM_EvalSh/<type>/N          the order-N SH basis at one direction (eval_sh), the inner
//                               step of the transfer simulation; 1024 random directions
//                               per iteration, per_eval = time per direction.
//   BM_TableBuild/<type>/res:R  building the light table (per lighting change); counters
//                               err_band1/err_band5: worst look-up error over 50,000 random
//                               directions relative to the band's largest value.
//
// Run (CPU times; the machine is shared, compare within one run):
//   build/bench/bench_fit --benchmark_counters_tabular=true
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "fit/embree_scene.h"
#include "fit/mesh.h"
#include "fit/transfer.h"
#include "fit/zh_fit.h"
#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/zh_shading.h"
#include "tensors/rotation_helpers_gen.h"

#ifndef SHTOOL_SOURCE_DIR
#error "bench_fit needs SHTOOL_SOURCE_DIR (set in bench/CMakeLists.txt)"
#endif
#ifndef SHTOOL_BENCH_MESHES
#error "bench_fit needs SHTOOL_BENCH_MESHES (set in bench/CMakeLists.txt)"
#endif

namespace {

constexpr int kOrder = 6;
constexpr int kPoints = 4096;     // shaded points per iteration
constexpr int kFitVectors = 20;   // random vectors of the fit fixture

using benchmark::Counter;

// Time per item: the rate counter inverted (seconds per item, printed with a unit).
Counter per_item(double items) { return Counter(items, Counter::kIsRate | Counter::kInvert); }

const shtool::fit::Mesh& spot() {
  static const shtool::fit::Mesh mesh = shtool::fit::load_obj(SHTOOL_SOURCE_DIR "/data/spot.obj");
  return mesh;
}

void BM_Transfer(benchmark::State& state) {
  const shtool::fit::Mesh& mesh = spot();
  shtool::fit::TransferOptions options;
  options.order = kOrder;
  options.rays = static_cast<int>(state.range(0));
  options.mode = shtool::fit::TransferMode::shadowed;
  options.threads = 1;
  for (auto _ : state) {
    std::vector<double> t = shtool::fit::compute_transfer(mesh, options);
    benchmark::DoNotOptimize(t.data());
  }
  const double vertices = static_cast<double>(mesh.positions.size());
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * vertices));
  state.counters["per_vertex"] = per_item(state.iterations() * vertices);
  state.counters["vertices"] = vertices;
}

// The medium test mesh; benchmarks that need it skip without it.
const shtool::fit::Mesh* bunny() {
  static const std::unique_ptr<shtool::fit::Mesh> mesh = []() -> std::unique_ptr<shtool::fit::Mesh> {
    const char* path = SHTOOL_BENCH_MESHES "/stanford-bunny.obj";
    if (!std::filesystem::exists(path)) return nullptr;
    return std::make_unique<shtool::fit::Mesh>(shtool::fit::load_obj(path));
  }();
  return mesh.get();
}

// compute_transfer's defaults for the bench's order and R rays, one thread.
shtool::fit::TransferOptions bunny_options(int rays) {
  shtool::fit::TransferOptions options;
  options.order = kOrder;
  options.rays = rays;
  options.mode = shtool::fit::TransferMode::shadowed;
  options.threads = 1;
  return options;
}

enum class OcclusionQuery { single, packet4, stream_coherent, stream_incoherent };

void BM_EmbreeOcclusion(benchmark::State& state, OcclusionQuery query) {
  const shtool::fit::Mesh* mesh = bunny();
  if (!mesh) return state.SkipWithError("no stanford-bunny.obj in " SHTOOL_BENCH_MESHES);
  const int rays = static_cast<int>(state.range(0));
  const shtool::fit::TransferOptions options = bunny_options(rays);
  const std::size_t vertices = mesh->positions.size();
  // The rays compute_transfer casts, each vertex's in order.
  std::vector<RTCRay> cast(vertices * rays);
  const double offset = options.offset_scale * mesh->bbox_diagonal();
  const std::unique_ptr<shtool::fit::EmbreeScene> scene = shtool::fit::build_scene(*mesh);
  for (std::size_t v = 0; v < vertices; ++v) {
    const shtool::fit::VertexRays vr(*mesh, v, options.seed, rays, offset);
    for (int k = 0; k < rays; ++k) cast[v * rays + k] = scene->ray(vr.origin(), vr.direction(k));
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  if (query == OcclusionQuery::stream_coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  std::vector<RTCRay> batch(rays);
  std::size_t blocked = 0;
  for (auto _ : state) {
    blocked = 0;
    for (std::size_t v = 0; v < vertices; ++v) {
      const RTCRay* first = cast.data() + v * rays;
      switch (query) {
        case OcclusionQuery::single:
          for (int k = 0; k < rays; ++k) {
            RTCRay ray = first[k];
            rtcOccluded1(scene->scene, &context, &ray);
            blocked += ray.tfar < 0.0f;
          }
          break;
        case OcclusionQuery::packet4:
          for (int k = 0; k < rays; k += 4) {
            alignas(16) int valid[4];
            alignas(16) RTCRay4 packet;
            for (int j = 0; j < 4; ++j) {
              valid[j] = k + j < rays ? -1 : 0;
              const RTCRay& r = first[std::min(k + j, rays - 1)];
              packet.org_x[j] = r.org_x, packet.org_y[j] = r.org_y, packet.org_z[j] = r.org_z;
              packet.dir_x[j] = r.dir_x, packet.dir_y[j] = r.dir_y, packet.dir_z[j] = r.dir_z;
              packet.tnear[j] = r.tnear, packet.tfar[j] = r.tfar, packet.time[j] = r.time;
              packet.mask[j] = r.mask, packet.id[j] = 0, packet.flags[j] = 0;
            }
            rtcOccluded4(valid, scene->scene, &context, &packet);
            for (int j = 0; j < 4 && k + j < rays; ++j) blocked += packet.tfar[j] < 0.0f;
          }
          break;
        case OcclusionQuery::stream_coherent:
        case OcclusionQuery::stream_incoherent:
          std::copy(first, first + rays, batch.begin());
          rtcOccluded1M(scene->scene, &context, batch.data(), rays, sizeof(RTCRay));
          for (const RTCRay& r : batch) blocked += r.tfar < 0.0f;
          break;
      }
    }
    benchmark::DoNotOptimize(blocked);
  }
  const double cast_count = static_cast<double>(cast.size());
  state.counters["rays_per_s"] = Counter(state.iterations() * cast_count, Counter::kIsRate);
  state.counters["blocked"] = blocked / cast_count;
}

void BM_TransferBunny(benchmark::State& state) {
  const shtool::fit::Mesh* mesh = bunny();
  if (!mesh) return state.SkipWithError("no stanford-bunny.obj in " SHTOOL_BENCH_MESHES);
  shtool::fit::TransferOptions options = bunny_options(static_cast<int>(state.range(0)));
  options.ray_streams = state.range(1) != 0;
  if (state.range(2) > 0) {
    options.mode = shtool::fit::TransferMode::interreflected;
    options.bounces = static_cast<int>(state.range(2));
  }
  for (auto _ : state) {
    std::vector<double> t = shtool::fit::compute_transfer(*mesh, options);
    benchmark::DoNotOptimize(t.data());
  }
  const double cast_count = static_cast<double>(mesh->positions.size()) * options.rays * (1 + state.range(2));
  state.counters["rays_per_s"] = Counter(state.iterations() * cast_count, Counter::kIsRate);
}

void BM_EmbreeBuild(benchmark::State& state) {
  const shtool::fit::Mesh* mesh = bunny();
  if (!mesh) return state.SkipWithError("no stanford-bunny.obj in " SHTOOL_BENCH_MESHES);
  for (auto _ : state) {
    std::unique_ptr<shtool::fit::EmbreeScene> scene = shtool::fit::build_scene(*mesh);
    benchmark::DoNotOptimize(scene.get());
  }
}

std::vector<double> random_unit_vectors(int count, int order, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(static_cast<std::size_t>(count) * shtool::sh_count(order));
  for (int k = 0; k < count; ++k) {
    double n = 0;
    double* t = v.data() + static_cast<std::size_t>(k) * shtool::sh_count(order);
    for (int i = 0; i < shtool::sh_count(order); ++i) {
      t[i] = u(rng);
      n += t[i] * t[i];
    }
    for (int i = 0; i < shtool::sh_count(order); ++i) t[i] /= std::sqrt(n);
  }
  return v;
}

shtool::fit::ZhFitOptions fit_options(int method, int lobes) {
  shtool::fit::ZhFitOptions options;
  options.order = kOrder;
  options.lobes = lobes;
  options.method = method == 0 ? shtool::fit::ZhFitMethod::varpro : shtool::fit::ZhFitMethod::joint;
  return options;
}

// The fit-quality fixture: two sets of order-6 vectors with the best residual known for
// each lobe count, read by the quality test and by BM_Fit, written by --write-best-known.
const char* const kBestKnownPath = SHTOOL_SOURCE_DIR "/tests/offline/data/zh_fit_best_known.json";
constexpr int kBestKnownLobes[] = {1, 2, 4};

struct FitSet {
  std::string name;
  std::vector<double> vectors;                // count x order^2
  std::map<int, std::vector<double>> best;    // by lobe count
  std::size_t count() const { return vectors.size() / shtool::sh_count(kOrder); }
};

// "random": random unit vectors (coefficients uniform in [-1, 1], normalised; no few
// lobes fit them well); "spot": shadowed transfer of data/spot.obj at 256 rays, every
// kSpotStride-th vertex (smooth, mostly well fitted).
constexpr int kSpotStride = 74;  // 40 vectors
std::vector<FitSet> make_fit_sets() {
  std::vector<FitSet> sets(2);
  sets[0].name = "random";
  sets[0].vectors = random_unit_vectors(kFitVectors, kOrder, 2005);
  sets[1].name = "spot";
  shtool::fit::TransferOptions to;
  to.order = kOrder;
  to.rays = 256;
  to.threads = 1;
  const std::vector<double> transfer = shtool::fit::compute_transfer(spot(), to);
  const std::size_t n2 = shtool::sh_count(kOrder);
  for (std::size_t v = 0; v < spot().positions.size(); v += kSpotStride)
    sets[1].vectors.insert(sets[1].vectors.end(), transfer.begin() + v * n2, transfer.begin() + (v + 1) * n2);
  return sets;
}

// Far more search than any effort level. N = 1: every grid maximum of 65,536 axes
// refined; N >= 2: the lowest residual of variable projection with 4096 random starts,
// the joint method with 256 (each run whatever the residual, the winner polished to
// 1e-12) and the default method at --effort 3 and 4 (whose winners, polished from
// other starts, are sometimes lower).
constexpr int kReferenceSingleLobeAxes = 65536;
constexpr int kBestKnownVarProStarts = 4096;
constexpr int kBestKnownJointStarts = 256;
std::vector<double> best_known_residuals(const std::vector<double>& vectors, int lobes) {
  const std::size_t n2 = shtool::sh_count(kOrder), count = vectors.size() / n2;
  std::vector<double> best(count, std::numeric_limits<double>::infinity());
  std::vector<shtool::fit::ZhFitOptions> searches;
  for (int method : {0, 1}) {
    shtool::fit::ZhFitOptions o = fit_options(method, lobes);
    o.single_lobe_axes = kReferenceSingleLobeAxes;
    o.single_lobe_maxima = 0;
    o.starts = method == 0 ? kBestKnownVarProStarts : kBestKnownJointStarts;
    o.restart_above = 0;
    o.polish_ftol_rel = 1e-12;
    o.split_polish_ftol_rel = 1e-12;
    o.split_polish_evaluations = 2000;
    o.max_evaluations = 2000;
    searches.push_back(o);
  }
  for (int effort : {3, 4}) {
    searches.push_back(fit_options(0, lobes));
    shtool::fit::apply_effort(searches.back(), effort);
  }
  // Both methods take the same single-lobe search.
  if (lobes == 1) searches.resize(1);
  for (const shtool::fit::ZhFitOptions& o : searches) {
    const shtool::ZhFitTable<double> fits = shtool::fit::fit_zh_all(vectors, o, 0);
    for (std::size_t v = 0; v < count; ++v) best[v] = std::min(best[v], fits.residual[v]);
  }
  return best;
}

std::vector<FitSet> read_fit_sets(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("bench_fit: cannot read " + path);
  const nlohmann::json doc = nlohmann::json::parse(in);
  std::vector<FitSet> out;
  for (const auto& [name, set] : doc.at("sets").items()) {
    FitSet s;
    s.name = name;
    for (const auto& v : set.at("vectors")) {
      const std::vector<double> t = v.get<std::vector<double>>();
      s.vectors.insert(s.vectors.end(), t.begin(), t.end());
    }
    for (const auto& [lobes, r] : set.at("best_residual").items())
      s.best[std::stoi(lobes)] = r.get<std::vector<double>>();
    out.push_back(std::move(s));
  }
  return out;
}

const std::vector<FitSet>& fit_sets() {
  static const std::vector<FitSet> sets = read_fit_sets(kBestKnownPath);
  return sets;
}

void BM_Fit(benchmark::State& state) {
  const FitSet& set = fit_sets().at(static_cast<std::size_t>(state.range(4)));
  shtool::fit::ZhFitOptions options = fit_options(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  if (state.range(2) >= 0) shtool::fit::apply_effort(options, static_cast<int>(state.range(2)));
  if (state.range(3) >= 0) options.starts = static_cast<int>(state.range(3));
  const auto best = set.best.find(options.lobes);
  const std::size_t n2 = shtool::sh_count(kOrder);
  double residual2 = 0, norm2 = 0, ratio_sum = 0, ratio_max = 0, residual_sum = 0, best_sum = 0;
  std::size_t k = 0;
  for (auto _ : state) {
    const std::size_t v = k % set.count();
    const std::span<const double> t(set.vectors.data() + v * n2, n2);
    const shtool::fit::ZhFit fit = shtool::fit::fit_zh(t, options, v);
    residual2 += fit.residual * fit.residual;
    norm2 += fit.norm * fit.norm;
    if (best != set.best.end()) {
      const double ratio = fit.residual / best->second[v];
      ratio_sum += ratio;
      ratio_max = std::max(ratio_max, ratio);
      residual_sum += fit.residual;
      best_sum += best->second[v];
    }
    ++k;
  }
  state.SetLabel(set.name);
  state.SetItemsProcessed(state.iterations());
  state.counters["per_vector"] = per_item(static_cast<double>(state.iterations()));
  state.counters["nrms"] = std::sqrt(residual2 / norm2);
  if (best != set.best.end()) {
    state.counters["vs_best_mean"] = ratio_sum / static_cast<double>(k);
    state.counters["vs_best_max"] = ratio_max;
    state.counters["mean_vs_best"] = residual_sum / best_sum;
  }
}

// --write-best-known=PATH: the fixture above, vectors and best-known residuals.
int write_best_known(const std::string& path) {
  const std::size_t n2 = shtool::sh_count(kOrder);
  // An existing fixture keeps its vectors (the tests' and docs' figures are measured on
  // them, and a change to the simulation would otherwise replace the transfer set), and
  // each best known is lowered where this search finds lower.
  const std::vector<FitSet> sets = std::ifstream(path) ? read_fit_sets(path) : make_fit_sets();
  std::ofstream out(path);
  out.precision(17);
  out << "{\"comment\": \"order-6 vectors (random unit; shadowed transfer of data/spot.obj) and the best residual "
         "known per lobe count (a search far longer than any effort level); written by bench_fit "
         "--write-best-known\",\n \"order\": "
      << kOrder << ",\n \"sets\": {";
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const FitSet& set = sets[s];
    out << (s ? ",\n" : "\n") << "  \"" << set.name << "\": {\"vectors\": [";
    for (std::size_t v = 0; v < set.count(); ++v) {
      out << (v ? ",\n   [" : "\n   [");
      for (std::size_t i = 0; i < n2; ++i) out << (i ? ", " : "") << set.vectors[v * n2 + i];
      out << "]";
    }
    out << "],\n   \"best_residual\": {";
    bool first = true;
    for (int lobes : kBestKnownLobes) {
      out << (first ? "" : ",") << "\n    \"" << lobes << "\": [";
      first = false;
      std::vector<double> best = best_known_residuals(set.vectors, lobes);
      if (const auto known = set.best.find(lobes); known != set.best.end())
        for (std::size_t v = 0; v < best.size(); ++v) best[v] = std::min(best[v], known->second.at(v));
      for (std::size_t v = 0; v < best.size(); ++v) out << (v ? ", " : "") << best[v];
      out << "]";
    }
    out << "}}";
  }
  out << "}}\n";
  return out ? 0 : 1;
}

// Shading data in type T: one light, kPoints points of N lobes, each point's full SH
// transfer vector (the lobes summed, for sh_dot) and a rotation per point.
template <class T>
struct ShadeData {
  std::vector<double> light_d;
  std::vector<T> light;
  std::vector<shtool::Vec3<T>> axes;  // kPoints * N
  std::vector<T> coeffs;              // kPoints * N * order
  std::vector<T> transfer;            // kPoints * order^2
  std::vector<shtool::Mat3<T>> rotations;

  explicit ShadeData(int lobes) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::normal_distribution<double> g;
    light_d = random_unit_vectors(1, kOrder, 7);
    light.assign(light_d.begin(), light_d.end());
    for (int p = 0; p < kPoints; ++p) {
      for (int i = 0; i < lobes; ++i) {
        Eigen::Vector3d a(g(rng), g(rng), g(rng));
        axes.push_back(a.normalized().cast<T>());
        for (int l = 0; l < kOrder; ++l) coeffs.push_back(static_cast<T>(u(rng)));
      }
      for (int j = 0; j < shtool::sh_count(kOrder); ++j) transfer.push_back(static_cast<T>(u(rng)));
      Eigen::Vector4d q(g(rng), g(rng), g(rng), g(rng));
      q.normalize();
      rotations.push_back(shtool::matrix_from_quaternion<T>(static_cast<T>(q[0]), static_cast<T>(q[1]),
                                                            static_cast<T>(q[2]), static_cast<T>(q[3])));
    }
  }
};

enum class ShadeMethod { table, exact, sh_dot, sh_rotate_dot };

template <class T>
void BM_Shade(benchmark::State& state, ShadeMethod method) {
  const int lobes = static_cast<int>(state.range(0));
  const int resolution = state.range(1) > 0 ? static_cast<int>(state.range(1)) : shtool::kDefaultZhLightResolution;
  const ShadeData<T> d(lobes);
  const shtool::ZhLightTable<T> table(kOrder, d.light_d, resolution);
  const std::size_t n2 = shtool::sh_count(kOrder);
  static const auto helpers =
      std::make_shared<const shtool::RotationHelpers>(shtool::compute_rotation_helpers(kOrder));
  shtool::ShRotation<T> rotation(kOrder, helpers);
  std::vector<T> rotated(n2);
  const std::span<const shtool::Vec3<T>> axes(d.axes);
  const std::span<const T> coeffs(d.coeffs);
  const std::span<const T> light(d.light);
  const std::size_t per_point = static_cast<std::size_t>(lobes) * kOrder;

  for (auto _ : state) {
    T sum = 0;
    for (int p = 0; p < kPoints; ++p) {
      switch (method) {
        case ShadeMethod::table:
          sum += table.shade(axes.subspan(p * lobes, lobes), coeffs.subspan(p * per_point, per_point));
          break;
        case ShadeMethod::exact:
          sum += shtool::zh_shade_exact<T>(light, axes.subspan(p * lobes, lobes),
                                           coeffs.subspan(p * per_point, per_point));
          break;
        case ShadeMethod::sh_dot: {
          const T* t = d.transfer.data() + p * n2;
          T r = 0;
          for (std::size_t i = 0; i < n2; ++i) r += t[i] * d.light[i];
          sum += r;
          break;
        }
        case ShadeMethod::sh_rotate_dot: {
          rotation.set(d.rotations[p]);
          rotation.apply(std::span<const T>(d.transfer.data() + p * n2, n2), rotated);
          T r = 0;
          for (std::size_t i = 0; i < n2; ++i) r += rotated[i] * d.light[i];
          sum += r;
          break;
        }
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.counters["per_shade"] = per_item(static_cast<double>(state.iterations()) * kPoints);
  if (method == ShadeMethod::table) state.counters["table_KB"] = table.bytes() / 1024.0;
}

template <class T>
void BM_TableBuild(benchmark::State& state) {
  const std::vector<double> light = random_unit_vectors(1, kOrder, 7);
  const int resolution = static_cast<int>(state.range(0));
  for (auto _ : state) {
    shtool::ZhLightTable<T> table(kOrder, light, resolution);
    benchmark::DoNotOptimize(table.nodes().data());
  }
  const shtool::ZhLightTable<T> table(kOrder, light, resolution);
  state.counters["table_KB"] = table.bytes() / 1024.0;
  // Accuracy of the look-up (docs/fit-zh.md, "Accuracy"): worst error of band l over
  // random directions, relative to the largest value the band can take,
  // sqrt((2l+1)/(4 pi)) |L_l| (Cauchy-Schwarz with the addition theorem).
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  std::vector<T> fast(kOrder), exact(kOrder);
  std::vector<double> worst(kOrder, 0.0);
  const std::vector<T> light_t(light.begin(), light.end());
  for (int k = 0; k < 50000; ++k) {
    const shtool::Vec3<T> axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized().cast<T>();
    table.lookup(axis, fast);
    shtool::zh_light_bands<T>(light_t, axis, exact);
    for (int l = 0; l < kOrder; ++l) worst[l] = std::max(worst[l], std::abs(double(fast[l]) - double(exact[l])));
  }
  for (int l : {1, kOrder - 1}) {
    double band = 0;
    for (int m = -l; m <= l; ++m) band += light[shtool::sh_index(l, m)] * light[shtool::sh_index(l, m)];
    const double scale = std::sqrt((2 * l + 1) / (4 * std::numbers::pi) * band);
    state.counters["err_band" + std::to_string(l)] = worst[l] / scale;
  }
}

template <class T>
void BM_EvalSh(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss;
  std::vector<shtool::Vec3<T>> dirs(1024);
  for (auto& d : dirs) d = shtool::Vec3<double>(gauss(rng), gauss(rng), gauss(rng)).normalized().cast<T>();
  std::vector<T> out(static_cast<std::size_t>(order * order));
  for (auto _ : state) {
    for (const auto& d : dirs) {
      shtool::eval_sh<T>(order, d, out);
      benchmark::DoNotOptimize(out.data());
    }
    benchmark::ClobberMemory();
  }
  state.counters["per_eval"] = benchmark::Counter(static_cast<double>(state.iterations() * dirs.size()),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

template <class T>
void register_shading(const std::string& type) {
  const std::vector<long> lobe_counts = {1, 2, 4, 6};
  auto add = [&](const std::string& name, ShadeMethod method) {
    return benchmark::RegisterBenchmark(("BM_Shade/" + type + "/" + name).c_str(),
                                        [method](benchmark::State& s) { BM_Shade<T>(s, method); });
  };
  auto* table = add("table", ShadeMethod::table)->ArgNames({"lobes", "res"});
  for (long n : lobe_counts) table->Args({n, shtool::kDefaultZhLightResolution});
  // Resolution trade-off at N = 4: table size against cache (random axes).
  for (long r : {8, 16, 64, 128}) table->Args({4, r});
  auto* exact = add("exact", ShadeMethod::exact)->ArgNames({"lobes", "res"});
  for (long n : lobe_counts) exact->Args({n, 0});
  add("sh_dot", ShadeMethod::sh_dot)->ArgNames({"lobes", "res"})->Args({0, 0});
  add("sh_rotate_dot", ShadeMethod::sh_rotate_dot)->ArgNames({"lobes", "res"})->Args({0, 0});
  benchmark::RegisterBenchmark(("BM_EvalSh/" + type).c_str(), BM_EvalSh<T>)->Arg(2)->Arg(4)->Arg(6)->Arg(8)->Arg(16);
  auto* build = benchmark::RegisterBenchmark(("BM_TableBuild/" + type).c_str(), BM_TableBuild<T>);
  build->ArgName("res")->Unit(benchmark::kMicrosecond);
  for (long r : {8, 16, 32, 64, 128}) build->Arg(r);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("BM_Transfer", BM_Transfer)
      ->ArgName("rays")
      ->Arg(256)
      ->Arg(1024)
      ->Unit(benchmark::kMillisecond)
      ->MinTime(1.0);
  const std::pair<const char*, OcclusionQuery> queries[] = {{"single", OcclusionQuery::single},
                                                           {"packet4", OcclusionQuery::packet4},
                                                           {"stream_coherent", OcclusionQuery::stream_coherent},
                                                           {"stream_incoherent", OcclusionQuery::stream_incoherent}};
  for (const auto& [name, query] : queries)
    benchmark::RegisterBenchmark((std::string("BM_EmbreeOcclusion/") + name).c_str(),
                                 [query](benchmark::State& s) { BM_EmbreeOcclusion(s, query); })
        ->ArgName("rays")
        ->Arg(64)
        ->Unit(benchmark::kMillisecond)
        ->MinTime(2.0);
  benchmark::RegisterBenchmark("BM_TransferBunny", BM_TransferBunny)
      ->ArgNames({"rays", "streams", "bounces"})
      ->Args({64, 0, 0})
      ->Args({64, 1, 0})
      ->Args({64, 0, 1})
      ->Args({64, 1, 1})
      ->Unit(benchmark::kMillisecond)
      ->MinTime(2.0);
  benchmark::RegisterBenchmark("BM_EmbreeBuild", BM_EmbreeBuild)->Unit(benchmark::kMillisecond);
  for (long set = 0; set < 2; ++set) {
    auto* fit = benchmark::RegisterBenchmark("BM_Fit", BM_Fit)
                    ->ArgNames({"method", "lobes", "effort", "starts", "set"})
                    ->Unit(benchmark::kMillisecond)
                    ->Iterations(set == 0 ? kFitVectors : 2 * kFitVectors);
    for (long n : {1, 2, 4, 6}) {
      for (long e : {1, 2, 3, 4}) fit->Args({0, n, e, -1, set});
      fit->Args({1, n, 2, -1, set});  // the reference method at default effort
    }
  }
  register_shading<float>("float");
  register_shading<double>("double");

  for (int i = 1; i < argc; ++i)
    if (std::string_view(argv[i]).starts_with("--write-best-known="))
      return write_best_known(std::string(argv[i] + std::strlen("--write-best-known=")));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
