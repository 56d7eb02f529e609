// SH rotation through the sparse zonal-harmonic factorisation ([1] Sec. 7.1).
//
// A "zhf-lobes" table (written by `shtool search-lobes`, layout in docs/lobes.md) gives, for
// every band l = 0..N-1, 2l+1 lobe directions w_d and the sparse matrix A^_l = Y_l^-1 with
// Y_l[d][m] = y_l^m(w_d). With g(w) = f(R^-1 w) (docs/conventions.md):
//   standard (Eq. 10)        g_l = Y_l(R)^T (A^_l^T f_l), Y_l(R)[d][m] = y_l^m(R w_d):
//                            one sparse product, SH evaluated once per rotated direction
//                            (shared lobes: 2N-1 directions for the whole order);
//   signal-tailored (Eq. 11) g_l = A^_l [f~_l(R^-1 w_d)]_d, f~_l the band-l part of f:
//                            the signal is prepared once, a rotation samples it at the
//                            inversely rotated directions and does one sparse product.
// Both are exact up to rounding amplified by cond(Y_l) (recorded in the table).
//
// Both follow ShRotation's verbs: set(R) prepares a rotation (returning whether it took it,
// as ShRotation::set does; these never refuse one), apply() writes the rotated
// coefficients. Objects own their scratch: set() and apply() allocate nothing and are not
// safe to call concurrently on one object. Nothing here throws; loading reports errors as
// Result.
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "shtool/detail/zhf_lobe_plan.h"
#include "shtool/euler.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool {

// The table kind search-lobes writes and these loaders read.
inline constexpr std::string_view kZhfLobesKind = "zhf-lobes";

// Lobe data for bands 0..order-1.
struct ZhfLobes {
  int order = 0;
  std::vector<Vec3<double>> directions;  // all lobe directions (shared: 2N-1 nested)
  std::vector<int> band_offset;          // band l uses directions[band_offset[l] + d], d = 0..2l
  // Sparse rows of A^_l, flat row i = sh_index(l, m): entries row_start[i]..row_start[i+1]-1,
  // column col[k] = d (0..2l, within the band), value val[k]. Zeros are not stored.
  std::vector<int> row_start, col;
  std::vector<double> val;
  std::vector<int> eval_order;  // per direction: 1 + the highest band that uses it
  std::vector<double> cond;     // cond_2(Y_l) per band, as recorded in the table

  std::size_t nonzeros() const { return val.size(); }

  // Table loading. from_table checks that the table holds bands 0..n-1 in order (a
  // per-band search table cannot rotate on its own), the sparse rows' consistency, unit
  // directions and finite values; load is read_table + from_table, the path prefixed to
  // any message.
  static Result<ZhfLobes> from_table(const Table& table);
  static Result<ZhfLobes> load(const std::filesystem::path& path);
  // Bands 0..order-1 alone, with only the directions they use (what a shader of that order
  // embeds). An error if the table holds fewer bands.
  Result<ZhfLobes> bands_below(int order) const;
};

// The shipped shared-lobe table for `order`: tables/zhf-shared-N<order>.shtb, or the
// smallest shipped order above it (find_shipped_table: $SHTOOL_TABLES, then the install prefix).
// Empty if none is found.
std::filesystem::path default_zhf_lobes_path(int order);

// Standard ZHF rotation (Eq. 10).
template <class T>
class ZhfRotation {
 public:
  // Precondition: lobes != null and lobes->order >= order >= 1.
  ZhfRotation(int order, std::shared_ptr<const ZhfLobes> lobes);
  int order() const { return order_; }
  // Prepares R (orthonormal, det +1): rotates the lobe directions and evaluates SH there.
  // Always true.
  bool set(const Mat3<T>& r);
  // out = M(R) in, N^2 coefficients each; in and out must not overlap.
  void apply(std::span<const T> in, std::span<T> out) const;

 private:
  int order_;
  std::shared_ptr<const ZhfLobes> lobes_;
  detail::ZhfLobePlan plan_;
  std::vector<Vec3<T>> dirs_;  // lobe directions converted to T once
  // A^_l^T by band, column-major ("CSC"): for lobe d of band l, the m with A^_l[m][d] != 0
  // (entries csc_start_[l*l + d] .. csc_start_[l*l + d + 1] - 1), so z = A^T f is a gather.
  std::vector<int> csc_start_, csc_row_;
  std::vector<T> csc_val_;
  std::vector<T> y_;           // Y_l(R)^T [m][d], band-major: band l at plan_.block_offset[l]
  std::vector<T> walk_;        // recurrence scratch (5 N D + 3 D values)
  mutable std::vector<T> z_;   // A^_l^T f_l, one band (2N-1 values)
};

// Signal-tailored rotation (Eq. 11) of one fixed signal.
template <class T>
class ZhfTailoredSignal {
 public:
  // Prepares f (N^2 coefficients, N = order <= lobes->order): keeps its per-band
  // expansions f~_l(u) = sum_m f_l^m y_l^m(u).
  ZhfTailoredSignal(std::shared_ptr<const ZhfLobes> lobes, std::span<const T> coeffs);
  int order() const { return order_; }
  // Prepares R (orthonormal, det +1): samples f~_l at R^-1 w_d. Always true.
  bool set(const Mat3<T>& r);
  // out = M(R) f (N^2 coefficients): one sparse product with A^_l per band.
  void apply(std::span<T> out) const;
  // The sparse product alone, for callers that sample f~_l themselves (e.g. from cubemaps):
  // samples[sh_index(l, d - l)] = f~_l(R^-1 w_d) for d = 0..2l; out = A^ samples per band.
  static void apply_samples(const ZhfLobes& lobes, int order, std::span<const T> samples,
                            std::span<T> out);

 private:
  int order_;
  std::shared_ptr<const ZhfLobes> lobes_;
  detail::ZhfLobePlan plan_;
  std::vector<Vec3<T>> dirs_;
  std::vector<T> f_;
  std::vector<T> val_;  // A^ values converted to T once
  std::vector<T> samples_, walk_;
};

}  // namespace shtool
