// Sparse zonal-harmonic factorisation (ZHF): candidate lobe directions, the matrices
// Y_l and A^_l = Y_l^-1, their sparsity, and the genetic search for sparse lobe sets
// ([1] Sec. 4-6). Offline only; the runtime reads the tables this produces
// (include/shtool/zhf_rotation.h). Conventions: docs/conventions.md
// (Y_l[d][m] = y_l^m(w_d), rows d and columns m both in -l..l order).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "shtool/sh.h"
#include <nlohmann/json.hpp>

#include "shtool/table.h"
#include "shtool/zhf_rotation.h"

namespace shtool::lobes {

// An entry of A^_l counts as zero below this magnitude ([1] Sec. 5).
inline constexpr double kZeroThreshold = 1e-9;
// Largest cond_2(Y_l) a search accepts. A rotation through A^_l loses about
// cond * (2l+1) * eps relative accuracy: 1e4 * 37 * 1.1e-16 = 4e-11 keeps double rotations
// within the 1e-10 the tests ask for up to l = 18 (float users want 1e3, see docs/lobes.md).
inline constexpr double kDefaultMaxCond = 1e4;
// Below this relative smallest singular value Y_l is treated as singular outright.
inline constexpr double kSingularRcond = 1e-12;
// Zeros are counted only across a clear gap: the counted entries (all below kZeroThreshold)
// must be at least this factor below every entry not counted. From l ~ 11 on, A^_l can have
// entries between 1e-12 and 1e-6 (near-cancellations, rounding amplified by cond), and a
// count that moves with the threshold says nothing about structural zeros (measured at
// l = 18, 20.8 / 30.8 / 32.2 % at 1e-12 / 1e-9 / 1e-6). True zeros sit at cond * eps ~ 1e-12
// or below, structural non-zeros at 1e-4 or above, so 1e3 separates them with room.
inline constexpr double kClearGap = 1e3;

// The search's fitness counts zeros across the clear gap (count_zeros) from this band on,
// where counts were measured to depend on the threshold; below it, the plain count
// |a| < kZeroThreshold, which keeps the shipped l <= 12 and shared N <= 10 searches as they
// were (the two counts differ only for sets with entries between 1e-12 and 1e-6, and every
// shipped result has a gap > 1e10, so its reported count is the same under both rules).
inline constexpr int kGapFitnessFromBand = 13;

struct ZeroCount {
  int zeros = 0;
  double largest_zero = 0;  // largest |a| counted (0 when none)
  double smallest_nonzero = std::numeric_limits<double>::infinity();  // smallest |a| not counted
};
// The zero count across a clear gap: with |a| sorted ascending, the largest k such that the
// k smallest are all < kZeroThreshold and the (k+1)-th is >= kClearGap times the k-th (any
// count when the k-th is exactly 0). Equal to the plain count |a| < kZeroThreshold whenever
// that count already has a clear gap (every shipped l <= 12 set: gaps > 1e10). `scratch`
// avoids an allocation per call.
ZeroCount count_zeros(const double* a, std::size_t count, std::vector<double>& scratch);

enum class ThetaCandidates {
  band,   // zeros of P_l^m(cos t), m = 0..l-1, of the band itself, plus the poles (default)
  pooled  // zeros of P_k^m(cos t) for all bands k = 1..l (the paper's wording), plus the poles
};

// Polar-angle candidates for band l (l >= 1), ascending, deduplicated; both sets include
// t = 0 and t = pi, where every P_k^m with m >= 1 vanishes.
std::vector<double> theta_candidates(int l, ThetaCandidates kind);
// Azimuth candidates: zeros of cos(m p) and sin(m p) on [0, 2 pi) for m = 1..l, i.e. the
// multiples j pi / (2m); deduplicated exactly (as reduced fractions), ascending.
std::vector<double> phi_candidates(int l);

// Unit vector of (t, p) with exact poles: sin(pi) is 1.2e-16 in double, which would put
// a spurious tilt on a lobe at the south pole.
Vec3<double> lobe_direction(double theta, double phi);

// Y_l[d][m] = y_l^m(w_d) for the 2l+1 directions (shtool::eval_sh).
Eigen::MatrixXd zhf_y_matrix(int l, std::span<const Vec3<double>> dirs);

struct BandReport {
  int l = 0;
  bool invertible = false;
  double cond = 0;         // cond_2(Y_l) = sigma_max / sigma_min (SVD)
  Eigen::MatrixXd a_hat;   // A^_l = Y_l^-1, entries with |a| < kZeroThreshold set to 0.0
  int zeros = 0;           // entries of A^_l counted as zero (count_zeros: < kZeroThreshold, clear gap)
  int entries = 0;         // (2l+1)^2
  double sparsity = 0;     // zeros / entries
  double largest_zero = 0;      // largest |a| counted as zero (gap report)
  double smallest_nonzero = 0;  // smallest |a| not counted as zero (may be < kZeroThreshold)
  std::vector<int> lobes_per_function;  // non-zeros of row m of A^_l (paper Table I)
};

// A^_l from the directions by LU inverse, cond from the SVD, zeros by count_zeros; the
// counted entries are stored as exact 0.0.
BandReport analyze_band(int l, std::span<const Vec3<double>> dirs);

// ---------------------------------------------------------------------------
// Search.

struct SearchOptions {
  int population = 500;
  double crossover = 0.8;   // fraction of non-elite children made by uniform crossover
  double mutation = -1;     // per-gene rate; <= 0 means 1/v (v = genes per individual)
  int elitism = 2;
  int stall = 50;           // stop after this many generations without improvement
  int max_generations = 10000;
  int restarts = 20;        // independent GA runs; the best is kept
  bool local_search = true; // greedy (t, p)-pair moves on each run's best
  bool secondary = true;    // zeros of Y_l as a tie-breaking slope (never outweighs a zero of A^)
  ThetaCandidates theta = ThetaCandidates::band;
  double max_cond = kDefaultMaxCond;
  int threads = 2;  // 0: every core
  std::uint64_t seed = 1;
  // Called from the calling thread: after every generation and sweep (persistent = false,
  // a transient status line) and once per finished restart (persistent = true).
  std::function<void(const std::string& line, bool persistent)> progress;
};

struct SearchResult {
  bool shared = false;
  int order = 0;                      // shared: N; band: l + 1
  std::vector<double> theta, phi;     // the directions (2l+1, or 2N-1 nested in shared mode)
  std::vector<BandReport> bands;      // band: {l}; shared: k = 0..N-1
  int zeros = 0, entries = 0;         // counted bands (band: l; shared: 2..N-1)
  double sparsity = 0;
  long long generations = 0;          // over all restarts
  long long evaluations = 0;
  int best_restart = 0;
  std::vector<double> restart_sparsity;  // best sparsity of each restart (after local search)
};

// Per-band search ([1] Sec. 5): 2l+1 directions for band l >= 1.
SearchResult search_band(int l, const SearchOptions& options);
// Shared lobes (Sec. 6): 2N-1 nested directions, band k uses the first 2k+1; fitness counts
// zeros of A^_k, k = 2..N-1, while bands 1..N-1 must all be invertible and conditioned.
SearchResult search_shared(int order, const SearchOptions& options);

// ---------------------------------------------------------------------------
// Output: the "zhf-lobes" table (schemas/zhf-lobes.schema.json) and the --json summary.
// Layout, for the B bands listed in "bands" (band mode: the searched bands; shared mode:
// 0..N-1, band k using the first 2k+1 of the 2N-1 directions):
//   theta, phi [D], directions [D, 3]     D = sum of 2l+1 (band mode) or 2N-1 (shared)
//   direction_offset [B]                  first direction of each band
//   a_hat [sum (2l+1)^2]                  A^_l blocks, row-major (row m, column d), zeros exact
//   sparse_row_start [sum (2l+1) + 1], sparse_col, sparse_val [nnz]
//                                         the non-zeros of each row of A^_l (col = d)
//   lobes_per_function [sum (2l+1)]       non-zeros per row (paper Table I)
//   zeros, sparsity, cond, largest_zero, smallest_nonzero [B]
// `searches` are the per-band results (band mode) or one shared result.
Table make_lobes_table(const std::vector<SearchResult>& searches, const nlohmann::json& generator,
                       const SearchOptions& options);
nlohmann::json lobes_summary_json(const std::vector<SearchResult>& searches);

// The shared lobes of the zhf rotations for bands 0..order-1: from `table` (empty: the
// shipped table that covers the order), InputError naming the problem otherwise.
std::shared_ptr<const ZhfLobes> zhf_lobes_for(int order, const std::filesystem::path& table = {});

std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t restart, std::uint64_t generation,
                          std::uint64_t index);

}  // namespace shtool::lobes
