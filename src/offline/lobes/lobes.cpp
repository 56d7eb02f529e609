// Sparse ZHF lobe search ([1] Sec. 4-6). See lobes.h and docs/lobes.md.
#include "lobes/lobes.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <condition_variable>
#include <mutex>
#include <unordered_map>
#include <utility>

#include <unistd.h>

#include <Eigen/LU>
#include <Eigen/SVD>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/random.h"
#include "lobes/legendre_zeros.h"
#include "shtool/legendre.h"

namespace shtool::lobes {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Candidate angles closer than this are the same angle computed two ways (the Legendre
// zeros are accurate to ~1e-15 rad; distinct zeros of bands <= 128 are far apart).
constexpr double kSameAngle = 1e-12;

std::vector<double> dedupe_sorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (double x : v)
    if (out.empty() || x - out.back() > kSameAngle) out.push_back(x);
  return out;
}

}  // namespace

std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t restart, std::uint64_t generation,
                          std::uint64_t index) {
  std::uint64_t h = splitmix64(seed);
  h = splitmix64(h ^ restart);
  h = splitmix64(h ^ generation);
  return splitmix64(h ^ index);
}

std::vector<double> theta_candidates(int l, ThetaCandidates kind) {
  if (l < 1 || l >= kMaxOrder) throw InputError("theta_candidates: band out of range");
  std::vector<double> v = {0.0, kPi};
  const int first = kind == ThetaCandidates::band ? l : 1;
  for (int k = first; k <= l; ++k)
    for (int m = 0; m < k; ++m)  // P_k^k = sin^k t has no interior zero
      for (double t : legendre_zeros(k, m)) v.push_back(t);
  return dedupe_sorted(std::move(v));
}

std::vector<double> phi_candidates(int l) {
  if (l < 1 || l >= kMaxOrder) throw InputError("phi_candidates: band out of range");
  // cos(m p) = 0 at p = (2j+1) pi / (2m), sin(m p) = 0 at p = j pi / m = 2j pi / (2m):
  // together all p = j pi / (2m), j = 0..4m-1. Reduced fractions j/(2m) dedupe exactly.
  std::vector<std::pair<int, int>> fr;
  for (int m = 1; m <= l; ++m)
    for (int j = 0; j < 4 * m; ++j) {
      const int g = std::gcd(j, 2 * m);
      fr.emplace_back(j / g, 2 * m / g);
    }
  std::sort(fr.begin(), fr.end(), [](auto a, auto b) {
    return static_cast<long long>(a.first) * b.second < static_cast<long long>(b.first) * a.second;
  });
  fr.erase(std::unique(fr.begin(), fr.end()), fr.end());
  std::vector<double> v;
  for (auto [a, b] : fr) v.push_back(kPi * a / b);
  return v;
}

Vec3<double> lobe_direction(double theta, double phi) {
  if (theta == 0.0) return {0.0, 0.0, 1.0};
  if (theta == kPi) return {0.0, 0.0, -1.0};
  return direction_from_angles(theta, phi);
}

Eigen::MatrixXd zhf_y_matrix(int l, std::span<const Vec3<double>> dirs) {
  const int n = 2 * l + 1;
  if (static_cast<int>(dirs.size()) != n) throw InputError("zhf_y_matrix: need 2l+1 directions");
  Eigen::MatrixXd y(n, n);
  std::vector<double> buf(sh_count(l + 1));
  for (int d = 0; d < n; ++d) {
    eval_sh<double>(l + 1, dirs[d], buf);
    for (int m = -l; m <= l; ++m) y(d, m + l) = buf[sh_index(l, m)];
  }
  return y;
}

ZeroCount count_zeros(const double* a, std::size_t count, std::vector<double>& scratch) {
  // One pass for the common case (the plain count already has a clear gap), sorting the
  // sub-threshold entries only when it does not.
  ZeroCount z;
  int plain = 0;
  double below = 0, above = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < count; ++i) {
    const double v = std::abs(a[i]);
    if (v < kZeroThreshold) {
      ++plain;
      below = std::max(below, v);
    } else {
      above = std::min(above, v);
    }
  }
  if (plain == 0 || below == 0 || above >= kClearGap * below) {
    z.zeros = plain;
    z.largest_zero = below;
    z.smallest_nonzero = above;
    return z;
  }
  scratch.clear();
  for (std::size_t i = 0; i < count; ++i)
    if (std::abs(a[i]) < kZeroThreshold) scratch.push_back(std::abs(a[i]));
  std::sort(scratch.begin(), scratch.end());
  std::size_t k = scratch.size();
  double next = above;
  while (k > 0 && scratch[k - 1] != 0 && next < kClearGap * scratch[k - 1]) next = scratch[--k];
  z.zeros = static_cast<int>(k);
  z.largest_zero = k ? scratch[k - 1] : 0;
  z.smallest_nonzero = next;
  return z;
}

BandReport analyze_band(int l, std::span<const Vec3<double>> dirs) {
  BandReport r;
  r.l = l;
  const int n = 2 * l + 1;
  r.entries = n * n;
  const Eigen::MatrixXd y = zhf_y_matrix(l, dirs);
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(y).singularValues();
  r.cond = sv(n - 1) > 0 ? sv(0) / sv(n - 1) : std::numeric_limits<double>::infinity();
  r.invertible = sv(n - 1) > kSingularRcond * sv(0);
  if (!r.invertible) return r;
  r.a_hat = y.partialPivLu().inverse();
  std::vector<double> scratch;
  const ZeroCount z = count_zeros(r.a_hat.data(), static_cast<std::size_t>(r.a_hat.size()), scratch);
  r.zeros = z.zeros;
  r.largest_zero = z.largest_zero;
  r.smallest_nonzero = z.smallest_nonzero;
  r.lobes_per_function.assign(n, 0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = std::abs(r.a_hat(i, j));
      // The counted entries are exactly those <= largest_zero (the gap is strict).
      if (z.zeros > 0 && a <= z.largest_zero) {
        r.a_hat(i, j) = 0.0;  // structural zero: stored as exactly 0 so consumers can skip it
      } else {
        ++r.lobes_per_function[i];
      }
    }
  r.sparsity = static_cast<double>(r.zeros) / r.entries;
  return r;
}

// ---------------------------------------------------------------------------
// The search.

namespace {

// A search problem: nd directions, each gene pair (theta index, phi index). Band mode has
// one band (l, counted); shared mode has bands 1..N-1, of which 2..N-1 are counted.
struct Problem {
  int nd = 0;
  std::vector<int> bands;
  std::vector<char> counted;
  std::vector<double> theta, phi;
  int nt = 0, np = 0;
  // rows[b][(ti * np + pi) * n_b + (m + k)] = y_k^m(w(theta[ti], phi[pi])), k = bands[b].
  std::vector<std::vector<double>> rows;
  std::int64_t weight = 1;  // 1 + entries of counted Y_k: one A^ zero outweighs all Y zeros
  double max_cond = kDefaultMaxCond;
  bool secondary = true;
  int north = -1;  // theta index of the pole t = 0 / t = pi (phi irrelevant there)
  int south = -1;
  int genes() const { return 2 * nd; }
};

// Half the physical memory: the candidate table plus the workspaces must fit beside the
// rest of the machine's work.
double search_memory_budget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 4.0 * (1ull << 30);
  return 0.5 * static_cast<double>(pages) * static_cast<double>(page);
}

std::string gib(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / (1ull << 30));
  return buf;
}

Problem make_problem(std::vector<int> bands, std::vector<char> counted, int cand_band,
                     const SearchOptions& opt) {
  Problem p;
  p.bands = std::move(bands);
  p.counted = std::move(counted);
  p.nd = 2 * p.bands.back() + 1;
  p.theta = theta_candidates(cand_band, opt.theta);
  p.phi = phi_candidates(cand_band);
  p.nt = static_cast<int>(p.theta.size());
  p.np = static_cast<int>(p.phi.size());
  p.north = 0;
  p.south = p.nt - 1;
  p.max_cond = opt.max_cond;
  p.secondary = opt.secondary;
  // The candidate rows grow as about l^5 (band l: ~l^2/2 polar x ~2.4 l^2 azimuthal
  // candidates x 2l+1 values): refuse up front, with the figure, what this machine
  // cannot hold, instead of failing an allocation minutes later.
  std::size_t per_direction = 0;
  for (int k : p.bands) per_direction += static_cast<std::size_t>(2 * k + 1);
  const double bytes = static_cast<double>(p.nt) * p.np * per_direction * sizeof(double);
  const double budget = search_memory_budget();
  if (bytes > budget)
    throw InputError("band " + std::to_string(p.bands.back()) + " needs " + gib(bytes) +
                     " for its candidate directions (" + std::to_string(p.nt) + " x " + std::to_string(p.np) +
                     " candidates), more than the " + gib(budget) + " this search may use (half the machine's memory)");
  const int order = p.bands.back() + 1;
  std::vector<double> buf(sh_count(order));
  p.rows.resize(p.bands.size());
  for (std::size_t b = 0; b < p.bands.size(); ++b)
    p.rows[b].resize(static_cast<std::size_t>(p.nt) * p.np * (2 * p.bands[b] + 1));
  for (int ti = 0; ti < p.nt; ++ti)
    for (int pi = 0; pi < p.np; ++pi) {
      eval_sh<double>(order, lobe_direction(p.theta[ti], p.phi[pi]), buf);
      for (std::size_t b = 0; b < p.bands.size(); ++b) {
        const int k = p.bands[b], n = 2 * k + 1;
        double* row = &p.rows[b][(static_cast<std::size_t>(ti) * p.np + pi) * n];
        for (int m = -k; m <= k; ++m) row[m + k] = buf[sh_index(k, m)];
      }
    }
  std::int64_t w = 1;
  for (std::size_t b = 0; b < p.bands.size(); ++b)
    if (p.counted[b]) w += static_cast<std::int64_t>(2 * p.bands[b] + 1) * (2 * p.bands[b] + 1);
  p.weight = w;
  return p;
}

const double* cached_row(const Problem& p, std::size_t b, int ti, int pi) {
  const int n = 2 * p.bands[b] + 1;
  return &p.rows[b][(static_cast<std::size_t>(ti) * p.np + pi) * n];
}

constexpr std::int64_t kInvalid = -1;

// Per-thread scratch; evaluate() also leaves Y_k and A^_k of the last call here (the
// local search starts its rank-1 updates from them).
struct Workspace {
  std::vector<Eigen::MatrixXd> y, a;
  Eigen::MatrixXd lu;           // small_inverse
  std::vector<int> perm;        // small_inverse
  std::vector<double> scratch;  // count_zeros
  explicit Workspace(const Problem& p) {
    for (int k : p.bands) {
      const int n = 2 * k + 1;
      y.emplace_back(n, n);
      a.emplace_back(n, n);
    }
  }
};

// inv = y^-1 by LU with partial pivoting, written out for the small sizes of the search
// (n = 2l+1 <= 37): Eigen's dynamic-size LU and inverse go through its blocked GEMM / TRSM
// kernels, whose packing and dispatch cost more than the arithmetic at these sizes (the
// fitness profile was 60 % Eigen LU + inverse). Plain loops over contiguous columns are
// about 3x faster. Returns false on an exactly zero pivot (singular, e.g. two equal lobes).
bool small_inverse(const Eigen::MatrixXd& y, Eigen::MatrixXd& inv, Eigen::MatrixXd& lu,
                   std::vector<int>& perm) {
  const int n = static_cast<int>(y.rows());
  lu = y;
  perm.resize(n);
  std::iota(perm.begin(), perm.end(), 0);
  double* m = lu.data();  // column-major: m[i + j * n] = lu(i, j)
  for (int k = 0; k < n; ++k) {
    int piv = k;
    double best = std::abs(m[k + k * n]);
    for (int i = k + 1; i < n; ++i)
      if (std::abs(m[i + k * n]) > best) best = std::abs(m[(piv = i) + k * n]);
    if (best == 0) return false;
    if (piv != k) {
      for (int j = 0; j < n; ++j) std::swap(m[k + j * n], m[piv + j * n]);
      std::swap(perm[k], perm[piv]);
    }
    const double inv_p = 1.0 / m[k + k * n];
    double* ck = m + k * n;
    for (int i = k + 1; i < n; ++i) ck[i] *= inv_p;
    for (int j = k + 1; j < n; ++j) {
      double* cj = m + j * n;
      const double f = cj[k];
      if (f == 0) continue;
      for (int i = k + 1; i < n; ++i) cj[i] -= ck[i] * f;
    }
  }
  // Column c of the inverse solves L U x = P e_c: x starts as e_r with perm[r] = c.
  inv.setZero(n, n);
  for (int r = 0; r < n; ++r) inv(r, perm[r]) = 1.0;
  for (int c = 0; c < n; ++c) {
    double* x = inv.data() + static_cast<std::size_t>(c) * n;
    for (int k = 0; k < n; ++k) {  // forward, unit lower L
      const double xk = x[k];
      if (xk == 0) continue;
      const double* ck = m + k * n;
      for (int i = k + 1; i < n; ++i) x[i] -= ck[i] * xk;
    }
    for (int k = n - 1; k >= 0; --k) {  // backward, U
      const double* ck = m + k * n;
      const double xk = x[k] / ck[k];
      x[k] = xk;
      if (xk == 0) continue;
      for (int i = 0; i < k; ++i) x[i] -= ck[i] * xk;
    }
  }
  return true;
}

bool conditioned(const Eigen::MatrixXd& y, const Eigen::MatrixXd& a, double max_cond) {
  const int n = static_cast<int>(y.rows());
  if (!a.allFinite()) return false;
  // Cheap bounds on cond_2 = |Y|_2 |A|_2 decide most cases; the SVD decides the rest.
  // Lower: |M|_1 / sqrt(n) <= |M|_2, |M|_F / sqrt(n) <= |M|_2. Upper: |M|_2 <= |M|_F and
  // |M|_2 <= sqrt(|M|_1 |M|_inf).
  const double y1 = y.cwiseAbs().colwise().sum().maxCoeff(), a1 = a.cwiseAbs().colwise().sum().maxCoeff();
  if (!(y1 * a1 <= n * max_cond)) return false;
  const double yf = y.norm(), af = a.norm();
  if (!(yf * af <= n * max_cond)) return false;
  if (yf * af <= max_cond) return true;
  const double yi = y.cwiseAbs().rowwise().sum().maxCoeff(), ai = a.cwiseAbs().rowwise().sum().maxCoeff();
  if (std::min(yf, std::sqrt(y1 * yi)) * std::min(af, std::sqrt(a1 * ai)) <= max_cond) return true;
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(y).singularValues();
  return sv(n - 1) > kSingularRcond * sv(0) && sv(0) <= max_cond * sv(n - 1);
}

// Fitness as an exact integer: zeros(A^) * weight + zeros(Y) (secondary), or kInvalid.
std::int64_t evaluate(const Problem& p, const int* genes, Workspace& ws) {
  std::int64_t za = 0, zy = 0;
  for (std::size_t b = 0; b < p.bands.size(); ++b) {
    const int n = 2 * p.bands[b] + 1;
    Eigen::MatrixXd& y = ws.y[b];
    for (int d = 0; d < n; ++d) {
      const double* row = cached_row(p, b, genes[d], genes[p.nd + d]);
      for (int j = 0; j < n; ++j) y(d, j) = row[j];
    }
    if (!small_inverse(y, ws.a[b], ws.lu, ws.perm)) return kInvalid;
    if (!conditioned(y, ws.a[b], p.max_cond)) return kInvalid;
    if (!p.counted[b]) continue;
    if (p.bands[b] >= kGapFitnessFromBand)
      za += count_zeros(ws.a[b].data(), static_cast<std::size_t>(ws.a[b].size()), ws.scratch).zeros;
    else
      za += (ws.a[b].array().abs() < kZeroThreshold).count();
    if (p.secondary) zy += (y.array().abs() < kZeroThreshold).count();
  }
  return za * p.weight + zy;
}

int zeros_of(const Problem& p, std::int64_t score) {
  return score < 0 ? 0 : static_cast<int>(score / p.weight);
}

// Cache key of an individual: its genes as bytes, with the azimuth of a pole lobe set to 0
// (lobe_direction ignores it there, so the rows of Y are bitwise the same).
std::string canonical_key(const Problem& p, const int* genes) {
  std::string key(static_cast<std::size_t>(p.genes()) * sizeof(int), '\0');
  char* out = key.data();
  for (int g = 0; g < p.genes(); ++g) {
    int x = genes[g];
    if (g >= p.nd && (genes[g - p.nd] == p.north || genes[g - p.nd] == p.south)) x = 0;
    std::memcpy(out + static_cast<std::size_t>(g) * sizeof(int), &x, sizeof(int));
  }
  return key;
}

struct RunResult {
  std::vector<int> genes;
  std::int64_t score = kInvalid;
  long long generations = 0;
  long long evaluations = 0;
};

std::string percent(double x) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << 100 * x << '%';
  return s.str();
}

// One GA run ([1] Sec. 5): uniform crossover for a `crossover` fraction of the
// non-elite children, per-gene uniform mutation for the rest, `elitism` best carried over,
// stop after `stall` generations without improvement. Parents by binary tournament.
RunResult run_ga(const Problem& p, const SearchOptions& opt, int restart,
                 std::vector<Workspace>& ws, ThreadPool& pool, const std::string& label) {
  const int v = p.genes();
  const int pop = opt.population;
  const double rate = opt.mutation > 0 ? opt.mutation : 1.0 / v;
  const int elite = std::min(opt.elitism, pop);
  const int n_cross = static_cast<int>(std::lround(opt.crossover * (pop - elite)));
  auto random_gene = [&](std::mt19937_64& rng, int g) {
    const int size = g < p.nd ? p.nt : p.np;
    return static_cast<int>(uniform_below(rng, static_cast<std::uint64_t>(size)));
  };

  std::vector<int> cur(static_cast<std::size_t>(pop) * v), next(cur.size());
  for (int i = 0; i < pop; ++i) {
    std::mt19937_64 rng(stream_seed(opt.seed, restart, 0, i));
    for (int g = 0; g < v; ++g) cur[static_cast<std::size_t>(i) * v + g] = random_gene(rng, g);
  }
  std::vector<std::int64_t> score(pop), next_score(pop);
  std::vector<char> known(pop, 0);
  std::vector<int> order(pop);
  RunResult res;
  int stall = 0;
  // Fitness is a pure function of the genes, and a converging population is full of repeats
  // (a mutation child is an unchanged parent with probability (1 - 1/v)^v ~ 0.37; crossover
  // of two equal parents is a copy): scores are cached per run by their canonical genes.
  // `evaluations` still counts fitness requests, so table metadata is unchanged.
  std::unordered_map<std::string, std::int64_t> cache;
  std::unordered_map<std::string, int> first_in_gen;
  std::vector<std::string> keys(pop);
  std::vector<int> todo, copy_of(pop);
  constexpr std::size_t kMaxCached = 1 << 21;  // bounds memory; clearing changes no result
  for (long long gen = 0;; ++gen) {
    todo.clear();
    first_in_gen.clear();
    pool.run(pop, [&](int, int lo, int hi) {
      for (int i = lo; i < hi; ++i)
        if (!known[i]) keys[i] = canonical_key(p, &cur[static_cast<std::size_t>(i) * v]);
    });
    for (int i = 0; i < pop; ++i) {
      copy_of[i] = -1;
      if (known[i]) continue;
      if (const auto it = cache.find(keys[i]); it != cache.end()) {
        score[i] = it->second;
        continue;
      }
      const auto [it, fresh] = first_in_gen.emplace(keys[i], i);
      if (fresh) todo.push_back(i);
      else copy_of[i] = it->second;
    }
    pool.run(static_cast<int>(todo.size()), [&](int t, int lo, int hi) {
      for (int k = lo; k < hi; ++k) {
        const int i = todo[k];
        score[i] = evaluate(p, &cur[static_cast<std::size_t>(i) * v], ws[t]);
      }
    });
    if (cache.size() > kMaxCached) cache.clear();
    for (int i : todo) cache.emplace(std::move(keys[i]), score[i]);
    for (int i = 0; i < pop; ++i)
      if (copy_of[i] >= 0) score[i] = score[copy_of[i]];
    for (int i = 0; i < pop; ++i) res.evaluations += !known[i];
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      return score[a] != score[b] ? score[a] > score[b] : a < b;
    });
    ++res.generations;
    if (score[order[0]] > res.score) {
      res.score = score[order[0]];
      res.genes.assign(cur.begin() + static_cast<std::ptrdiff_t>(order[0]) * v,
                       cur.begin() + static_cast<std::ptrdiff_t>(order[0] + 1) * v);
      stall = 0;
    } else {
      ++stall;
    }
    if (opt.progress)
      opt.progress(label + " restart " + std::to_string(restart + 1) + "/" +
                       std::to_string(opt.restarts) + " gen " + std::to_string(gen) + " best " +
                       percent(static_cast<double>(zeros_of(p, res.score)) /
                               std::max<std::int64_t>(1, p.weight - 1)) +
                       " stall " + std::to_string(stall),
                   false);
    if (stall >= opt.stall || res.generations >= opt.max_generations) break;

    auto tournament = [&](std::mt19937_64& rng) {
      const int a = static_cast<int>(uniform_below(rng, static_cast<std::uint64_t>(pop)));
      const int b = static_cast<int>(uniform_below(rng, static_cast<std::uint64_t>(pop)));
      return score[a] != score[b] ? (score[a] > score[b] ? a : b) : std::min(a, b);
    };
    // Each child draws from its own stream, so making them in parallel changes nothing.
    pool.run(pop, [&](int, int lo, int hi) {
    for (int i = lo; i < hi; ++i) {
      int* child = &next[static_cast<std::size_t>(i) * v];
      known[i] = 0;
      if (i < elite) {
        const int* src = &cur[static_cast<std::size_t>(order[i]) * v];
        std::copy(src, src + v, child);
        next_score[i] = score[order[i]];
        known[i] = 1;
        continue;
      }
      std::mt19937_64 rng(stream_seed(opt.seed, restart, gen + 1, i));
      if (i < elite + n_cross) {
        const int* a = &cur[static_cast<std::size_t>(tournament(rng)) * v];
        const int* b = &cur[static_cast<std::size_t>(tournament(rng)) * v];
        for (int g = 0; g < v; ++g) child[g] = uniform_01(rng) < 0.5 ? a[g] : b[g];
      } else {
        const int* a = &cur[static_cast<std::size_t>(tournament(rng)) * v];
        for (int g = 0; g < v; ++g) child[g] = uniform_01(rng) < rate ? random_gene(rng, g) : a[g];
      }
    }
    });
    std::swap(cur, next);
    std::swap(score, next_score);
  }
  return res;
}

// Greedy local search: for each direction in turn, screen every (theta, phi) candidate pair
// by a Sherman-Morrison rank-1 update of each affected A^_k (O(n^2) instead of O(n^3)),
// then verify the best screened moves with a full evaluation (conditioning included) and
// take the first that really improves. Sweeps until no direction improves.
void local_search(const Problem& p, const SearchOptions& opt, RunResult& run,
                  std::vector<Workspace>& ws, ThreadPool& pool, const std::string& label) {
  if (run.score < 0) return;
  // Moves: all (ti, pi) pairs, with one phi only at the poles (the direction ignores it).
  std::vector<std::pair<int, int>> moves;
  for (int ti = 0; ti < p.nt; ++ti)
    for (int pi = 0; pi < p.np; ++pi)
      if ((ti != p.north && ti != p.south) || pi == 0) moves.emplace_back(ti, pi);
  const int nm = static_cast<int>(moves.size());
  std::vector<std::int64_t> screen(nm);
  std::vector<int> rank(nm);
  Workspace base(p);
  std::vector<std::int64_t> fixed_za(p.bands.size()), fixed_zy(p.bands.size());
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> a_rowmajor(p.bands.size());
  for (int sweep = 0;; ++sweep) {
    bool improved = false;
    for (int d = 0; d < p.nd; ++d) {
      std::int64_t cur = evaluate(p, run.genes.data(), base);
      ++run.evaluations;
      run.score = cur;
      const int cti = run.genes[d], cpi = run.genes[p.nd + d];
      // Per band, what does not depend on the move: the zeros of Y_k, and those of A^_k
      // for a band that does not use direction d.
      for (std::size_t b = 0; b < p.bands.size(); ++b) {
        const int n = 2 * p.bands[b] + 1;
        fixed_zy[b] = (base.y[b].array().abs() < kZeroThreshold).count();
        fixed_za[b] = d >= n ? (base.a[b].array().abs() < kZeroThreshold).count() : 0;
        a_rowmajor[b] = base.a[b];
      }
      pool.run(nm, [&](int, int lo, int hi) {
        std::vector<double> r, s;
        for (int mi = lo; mi < hi; ++mi) {
          const auto [ti, pi] = moves[mi];
          const bool same = ti == cti && (pi == cpi || ti == p.north || ti == p.south);
          if (same) {
            screen[mi] = kInvalid;
            continue;
          }
          std::int64_t za = 0, zy = 0;
          bool ok = true;
          for (std::size_t b = 0; b < p.bands.size() && ok; ++b) {
            const int n = 2 * p.bands[b] + 1;
            const Eigen::MatrixXd& y = base.y[b];
            const Eigen::MatrixXd& a = base.a[b];
            if (d >= n) {  // this band does not use direction d
              if (p.counted[b]) {
                za += fixed_za[b];
                if (p.secondary) zy += fixed_zy[b];
              }
              continue;
            }
            const double* nrow = cached_row(p, b, ti, pi);
            r.assign(n, 0.0);
            for (int j = 0; j < n; ++j) r[j] = nrow[j] - y(d, j);
            // s = r^T A^, accumulated over i in order for every j at once (the same sums as
            // one dot product per j, bit for bit, but n independent chains that vectorise).
            s.assign(n, 0.0);
            const double* arm = a_rowmajor[b].data();
            for (int i = 0; i < n; ++i) {
              const double ri = r[i];
              const double* ai = arm + static_cast<std::size_t>(i) * n;
              for (int j = 0; j < n; ++j) s[j] += ri * ai[j];
            }
            const double denom = 1.0 + s[d];
            if (!(std::abs(denom) > 1e-12)) {
              ok = false;
              break;
            }
            if (!p.counted[b]) continue;
            const double* ad = a.data() + static_cast<std::size_t>(d) * n;
            for (int j = 0; j < n; ++j) {
              const double f = s[j] / denom;
              const double* aj = a.data() + static_cast<std::size_t>(j) * n;
              int cz = 0;
              for (int i = 0; i < n; ++i) cz += std::abs(aj[i] - ad[i] * f) < kZeroThreshold;
              za += cz;
            }
            if (p.secondary) {
              zy += fixed_zy[b];
              for (int j = 0; j < n; ++j)
                zy += (std::abs(nrow[j]) < kZeroThreshold) - (std::abs(y(d, j)) < kZeroThreshold);
            }
          }
          screen[mi] = ok ? za * p.weight + zy : kInvalid;
        }
      });
      run.evaluations += nm;
      std::iota(rank.begin(), rank.end(), 0);
      const int top = std::min(nm, 16);
      std::partial_sort(rank.begin(), rank.begin() + top, rank.end(), [&](int a, int b) {
        return screen[a] != screen[b] ? screen[a] > screen[b] : a < b;
      });
      std::vector<int> trial = run.genes;
      for (int k = 0; k < top && screen[rank[k]] > cur; ++k) {
        trial[d] = moves[rank[k]].first;
        trial[p.nd + d] = moves[rank[k]].second;
        const std::int64_t sc = evaluate(p, trial.data(), ws[0]);
        ++run.evaluations;
        if (sc > cur) {
          run.genes = trial;
          run.score = sc;
          improved = true;
          break;
        }
      }
    }
    if (opt.progress)
      opt.progress(label + " local search sweep " + std::to_string(sweep + 1) + " " +
                       percent(static_cast<double>(zeros_of(p, run.score)) /
                               std::max<std::int64_t>(1, p.weight - 1)),
                   false);
    if (!improved) break;
  }
}

void validate(const SearchOptions& o) {
  if (o.population < 2) throw InputError("population must be at least 2");
  if (!(o.crossover >= 0 && o.crossover <= 1)) throw InputError("crossover fraction must be in [0, 1]");
  if (!(o.mutation <= 1)) throw InputError("mutation rate must be <= 1");
  if (o.elitism < 0 || o.elitism >= o.population)
    throw InputError("elitism must be in [0, population)");
  if (o.stall < 1) throw InputError("stall generations must be at least 1");
  if (o.restarts < 1) throw InputError("restarts must be at least 1");
  resolve_threads(o.threads);  // 0 is every core; refuses a negative count and more than the machine can use
  if (!(o.max_cond >= 1) || !std::isfinite(o.max_cond))
    throw InputError("max condition number must be finite and >= 1");
  if (o.max_generations < 1) throw InputError("max generations must be at least 1");
}

SearchResult run_search(const Problem& p, const SearchOptions& opt, const std::string& label) {
  std::vector<Workspace> ws;
  const int threads = resolve_threads(opt.threads);
  ThreadPool pool(threads);
  for (int t = 0; t < threads; ++t) ws.emplace_back(p);
  SearchResult out;
  RunResult best;
  for (int r = 0; r < opt.restarts; ++r) {
    RunResult run = run_ga(p, opt, r, ws, pool, label);
    const double ga_sparsity = static_cast<double>(zeros_of(p, run.score)) / (p.weight - 1);
    if (opt.local_search) local_search(p, opt, run, ws, pool, label);
    out.generations += run.generations;
    out.evaluations += run.evaluations;
    const double sp = static_cast<double>(zeros_of(p, run.score)) / (p.weight - 1);
    out.restart_sparsity.push_back(sp);
    if (opt.progress)
      opt.progress(label + " restart " + std::to_string(r + 1) + "/" + std::to_string(opt.restarts) +
                       ": " + std::to_string(run.generations) + " generations, GA " +
                       percent(ga_sparsity) + (opt.local_search ? ", local search " + percent(sp) : ""),
                   true);
    if (run.score > best.score) {
      best = std::move(run);
      out.best_restart = r;
    }
  }
  if (best.score < 0) throw InputError(label + ": no valid (invertible, conditioned) lobe set found");
  for (int d = 0; d < p.nd; ++d) {
    out.theta.push_back(p.theta[best.genes[d]]);
    out.phi.push_back(p.phi[best.genes[p.nd + d]]);
  }
  return out;
}

}  // namespace

SearchResult search_band(int l, const SearchOptions& options) {
  if (l < 1 || l >= kMaxOrder) throw InputError("band must be in 1.." + std::to_string(kMaxOrder - 1));
  validate(options);
  const Problem p = make_problem({l}, {1}, l, options);
  SearchResult out = run_search(p, options, "band " + std::to_string(l));
  out.shared = false;
  out.order = l + 1;
  std::vector<Vec3<double>> dirs;
  for (int d = 0; d < p.nd; ++d) dirs.push_back(lobe_direction(out.theta[d], out.phi[d]));
  out.bands.push_back(analyze_band(l, dirs));
  out.zeros = out.bands[0].zeros;
  out.entries = out.bands[0].entries;
  out.sparsity = out.bands[0].sparsity;
  return out;
}

SearchResult search_shared(int order, const SearchOptions& options) {
  if (order < 3 || order > kMaxOrder) throw InputError("shared order must be in 3.." + std::to_string(kMaxOrder));
  validate(options);
  std::vector<int> bands;
  std::vector<char> counted;
  for (int k = 1; k < order; ++k) {
    bands.push_back(k);
    counted.push_back(k >= 2);
  }
  const Problem p = make_problem(bands, counted, order - 1, options);
  SearchResult out = run_search(p, options, "shared N=" + std::to_string(order));
  out.shared = true;
  out.order = order;
  std::vector<Vec3<double>> dirs;
  for (int d = 0; d < p.nd; ++d) dirs.push_back(lobe_direction(out.theta[d], out.phi[d]));
  for (int k = 0; k < order; ++k) {
    out.bands.push_back(analyze_band(k, std::span<const Vec3<double>>(dirs).first(2 * k + 1)));
    if (k >= 2) {
      out.zeros += out.bands.back().zeros;
      out.entries += out.bands.back().entries;
    }
  }
  out.sparsity = static_cast<double>(out.zeros) / out.entries;
  return out;
}

}  // namespace shtool::lobes
