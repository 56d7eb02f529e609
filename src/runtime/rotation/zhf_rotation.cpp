// ZHF rotation ([1] Sec. 7.1, Eq. 10-11). See include/shtool/zhf_rotation.h.
#include "shtool/zhf_rotation.h"

#include "basis/legendre_recurrence.h"
#include "io/load_kind.h"
#include "precondition.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace shtool {

namespace {

Error bad(const std::string& what) { return Error{"zhf-lobes table: " + what}; }

// Directions 0..used-1 are those some band below z.order uses; eval_order follows.
int directions_used(ZhfLobes& z) {
  int used = 0;
  for (int l = 0; l < z.order; ++l) used = std::max(used, z.band_offset[l] + 2 * l + 1);
  z.eval_order.assign(used, 0);
  for (int l = 0; l < z.order; ++l)
    for (int d = 0; d < 2 * l + 1; ++d) z.eval_order[z.band_offset[l] + d] = l + 1;
  return used;
}

}  // namespace

Result<ZhfLobes> ZhfLobes::load(const std::filesystem::path& path) {
  return detail::load_kind<ZhfLobes>(path, kZhfLobesKind);
}

Result<ZhfLobes> ZhfLobes::bands_below(int n) const {
  if (n < 1 || n > order)
    return bad("bands 0.." + std::to_string(n - 1) + " asked of a table that holds bands 0.." +
               std::to_string(order - 1));
  ZhfLobes z;
  z.order = n;
  z.band_offset.assign(band_offset.begin(), band_offset.begin() + n);
  z.cond.assign(cond.begin(), cond.begin() + n);
  z.row_start.assign(row_start.begin(), row_start.begin() + sh_count(n) + 1);
  z.col.assign(col.begin(), col.begin() + z.row_start.back());
  z.val.assign(val.begin(), val.begin() + z.row_start.back());
  const int used = directions_used(z);
  z.directions.assign(directions.begin(), directions.begin() + used);
  return z;
}

Result<ZhfLobes> ZhfLobes::from_table(const Table& t) {
  if (t.kind != kZhfLobesKind) return bad("wrong kind '" + t.kind + "'");
  if (const auto problem = detail::array_sizes_problem(t)) return bad(*problem);
  auto bands = t.get<std::int32_t>("bands");
  auto offset = t.get<std::int32_t>("direction_offset");
  auto dirs = t.get<double>("directions");
  auto rs = t.get<std::int32_t>("sparse_row_start");
  auto col = t.get<std::int32_t>("sparse_col");
  auto val = t.get<double>("sparse_val");
  auto cond = t.get<double>("cond");
  for (const auto* r : {&bands, &offset, &rs, &col})
    if (!*r) return bad(r->error().message);
  for (const auto* r : {&dirs, &val, &cond})
    if (!*r) return bad(r->error().message);
  const auto& b = bands.value();
  const int nb = static_cast<int>(b.size());
  if (nb == 0) return bad("no bands");
  const int want = nb;
  if (want > kMaxOrder) return bad("order " + std::to_string(want) + " exceeds kMaxOrder");
  // Rotation needs every band 0..want-1, stored in order (shared and full tables do this).
  for (int l = 0; l < want; ++l)
    if (l >= nb || b[l] != l)
      return bad("does not hold band " + std::to_string(l) + " at position " + std::to_string(l) +
                 " (a rotation table holds every band from 0 up, in order; this one's first is band " +
                 std::to_string(b[0]) + ": a per-band search table cannot rotate on its own)");
  if (t.order != want)
    return bad("the header says order " + std::to_string(t.order) + " but the table holds " + std::to_string(want) +
               " bands");
  const std::size_t nd = dirs.value().size() / 3;
  if (offset.value().size() != b.size() || cond.value().size() != b.size() || dirs.value().size() != 3 * nd)
    return bad("arrays 'direction_offset', 'cond' and 'bands' differ in length");
  // Every count and index is checked against the array sizes before it is used: the
  // bytes may come from anywhere.
  std::size_t rows = 0;
  for (int l = 0; l < nb; ++l) {
    if (b[l] < 0 || b[l] >= kMaxOrder)
      return bad("band entry " + std::to_string(l) + " is " + std::to_string(b[l]) + ", outside 0.." +
                           std::to_string(kMaxOrder - 1));
    rows += 2 * static_cast<std::size_t>(b[l]) + 1;
  }
  const auto& start = rs.value();
  const std::size_t nnz = col.value().size();
  if (start.size() != rows + 1 || start[0] != 0 || nnz != val.value().size() ||
      start.back() < 0 || static_cast<std::size_t>(start.back()) != nnz)
    return bad("sparse rows are inconsistent with 'bands'");
  for (std::size_t i = 0; i + 1 < start.size(); ++i)
    if (start[i + 1] < start[i] || static_cast<std::size_t>(start[i + 1]) > nnz)
      return bad("sparse_row_start is not monotone within 0.." + std::to_string(nnz));

  ZhfLobes z;
  z.order = want;
  z.row_start.push_back(0);
  std::size_t row = 0;
  for (int l = 0; l < want; ++l) {
    const int n = 2 * l + 1, off = offset.value()[l];
    if (off < 0 || static_cast<std::size_t>(off) + n > nd)
      return bad("band " + std::to_string(l) + " uses directions beyond the table");
    z.band_offset.push_back(off);
    if (!(cond.value()[l] >= 1.0) || !std::isfinite(cond.value()[l]))
      return bad("cond of band " + std::to_string(l) + " is not a finite number >= 1");
    z.cond.push_back(cond.value()[l]);
    for (int m = 0; m < n; ++m, ++row) {
      const int lo = start[row], hi = start[row + 1];
      if (hi < lo) return bad("sparse_row_start is not monotone");
      for (int k = lo; k < hi; ++k) {
        const int c = col.value()[k];
        if (c < 0 || c >= n) return bad("sparse_col out of range in band " + std::to_string(l));
        if (!std::isfinite(val.value()[k])) return bad("non-finite A^ value in band " + std::to_string(l));
        // Float's room: one table serves ZhfRotation<float> and <double>.
        if (!detail::within_headroom<float>(val.value()[k]))
          return bad("A^ value too large in band " + std::to_string(l));
        z.col.push_back(c);
        z.val.push_back(val.value()[k]);
      }
      z.row_start.push_back(static_cast<int>(z.col.size()));
    }
  }
  // Keep only the directions the bands use.
  const int used = directions_used(z);
  for (int d = 0; d < used; ++d) {
    const Vec3<double> w(dirs.value()[3 * d], dirs.value()[3 * d + 1], dirs.value()[3 * d + 2]);
    if (!w.allFinite() || std::abs(w.norm() - 1.0) > 1e-12)
      return bad("direction " + std::to_string(d) + " is not a unit vector");
    z.directions.push_back(w);
  }
  return z;
}

std::filesystem::path default_zhf_lobes_path(int order) {
  for (int n = std::max(order, 1); n <= kMaxOrder; ++n) {
    std::filesystem::path p = find_shipped_table("zhf-shared-N" + std::to_string(n) + ".shtb");
    if (!p.empty()) return p;
  }
  return {};
}

// ---------------------------------------------------------------------------
// Evaluation of the rotated lobe directions. The rotation cost is dominated by the SH
// evaluations ([1] Table II), and the generic eval_sh, one direction at a time with
// a per-value visitor, took 70 % of a rotation, and a rotation took about 3x this
// version's time at N = 8 (bench/bench_zhf).
// Here the same recurrence as src/runtime/basis/sh.cpp (Q_l^m = K_l^m P_l^m / sin^m t, times
// Re/Im (x + i y)^m) runs for all lobe directions at once, the direction index innermost
// (it vectorises), band l only for the directions some band >= l uses, and each band's
// values go to the caller as whole arrays (rows of Y_l^T, or sums against f_l).

namespace {

// The Legendre recurrence (basis/legendre_recurrence.h) with one change: y_l^{+-m} =
// sqrt2 Q_l^m Re/Im (x+iy)^m for m >= 1. The recurrence is linear in Q at fixed m and
// every Q_l^m, m >= 1, descends from Q_1^1, so folding sqrt2 into diag[1] scales them all
// at no cost per value.
template <class T>
struct ZhfRecurrence : detail::LegendreRecurrence<T> {
  ZhfRecurrence() { this->diag[1] = static_cast<T>(-std::sqrt(1.5) * std::numbers::sqrt2); }
};

template <class T>
const ZhfRecurrence<T>& zhf_recurrence() {
  static const ZhfRecurrence<T> table;
  return table;
}

// The loops over directions, with restrict-qualified arguments: the arrays share one
// scratch buffer, and without the qualifier the compiler versions every loop with runtime
// overlap checks (measured: 20 % of a rotation at N = 2, where the loops are 3 long).
template <class T>
inline void zhf_power_step(int lo, int hi, const T* __restrict x, const T* __restrict y, const T* __restrict cp,
                           const T* __restrict sp, T* __restrict cm, T* __restrict sm) {
  for (int d = lo; d < hi; ++d) {
    cm[d] = x[d] * cp[d] - y[d] * sp[d];
    sm[d] = x[d] * sp[d] + y[d] * cp[d];
  }
}

template <class T>
inline void zhf_diag_step(int lo, int hi, T dg, T sd, const T* __restrict z, const T* __restrict p1,
                          T* __restrict ql, T* __restrict qs) {
  for (int d = lo; d < hi; ++d) {
    ql[d] = dg * p1[d];
    qs[d] = sd * z[d] * p1[d];
  }
}

template <class T>
inline void zhf_three_term(int lo, int hi, T am, T bm, const T* __restrict z, const T* __restrict r1,
                           const T* __restrict r2, T* __restrict r0) {
  for (int d = lo; d < hi; ++d) r0[d] = am * (z[d] * r1[d] - bm * r2[d]);
}

// Runs the recurrence for all plan.directions directions at once (x, y, z: their
// components) and calls emit(l, q, c, s) for every band l < plan.order, where row m of the
// direction-indexed arrays (stride plan.directions) holds q: Q_l^m (sqrt2 included for
// m >= 1), c: Re (x+iy)^m, s: Im (x+iy)^m, so that y_l^0 = q[0][d], y_l^{+m} = q[m][d] c[m][d],
// y_l^{-m} = q[m][d] s[m][d]. Only directions [active_lo[l], active_hi[l]) are computed.
// scratch: 5 N D values.
template <class T, class Emit>
inline void zhf_walk(const detail::ZhfLobePlan& plan, const T* x, const T* y, const T* z, T* scratch,
                     Emit&& emit) {
  const ZhfRecurrence<T>& tab = zhf_recurrence<T>();
  const int n = plan.order, D = plan.directions;
  T* q0 = scratch;          // band l
  T* q1 = q0 + n * D;       // band l-1
  T* q2 = q1 + n * D;       // band l-2
  T* c = q2 + n * D;
  T* s = c + n * D;
  for (int d = 0; d < D; ++d) {
    c[d] = 1;
    s[d] = 0;
  }
  for (int m = 1; m < n; ++m) {
    const int lo = plan.active_lo[m], hi = plan.active_hi[m];
    const T* cp = c + (m - 1) * D;
    const T* sp = s + (m - 1) * D;
    T* cm = c + m * D;
    T* sm = s + m * D;
    zhf_power_step<T>(lo, hi, x, y, cp, sp, cm, sm);
  }
  for (int l = 0; l < n; ++l) {
    const int lo = plan.active_lo[l], hi = plan.active_hi[l];
    if (l == 0) {
      for (int d = lo; d < hi; ++d) q0[d] = tab.q00;
    } else {
      const T dg = tab.diag[l], sd = tab.subdiag[l - 1];
      const T* p1 = q1 + (l - 1) * D;
      T* ql = q0 + l * D;
      T* qs = q0 + (l - 1) * D;
      zhf_diag_step<T>(lo, hi, dg, sd, z, p1, ql, qs);
      const T* a = tab.a.data() + l * (l + 1) / 2;
      const T* b = tab.b.data() + l * (l + 1) / 2;
      for (int m = 0; m <= l - 2; ++m) {
        const T am = a[m], bm = b[m];
        const T* r1 = q1 + m * D;
        const T* r2 = q2 + m * D;
        T* r0 = q0 + m * D;
        zhf_three_term<T>(lo, hi, am, bm, z, r1, r2, r0);
      }
    }
    emit(l, static_cast<const T*>(q0), static_cast<const T*>(c), static_cast<const T*>(s));
    T* t = q2;  // rotate the three bands without copying
    q2 = q1;
    q1 = q0;
    q0 = t;
  }
}

// zhf_walk at the lobe directions turned by `turn`. walk: (5 N + 3) D values, the walk's
// scratch followed by the turned directions' x, y and z rows.
template <class T, class Emit>
inline void zhf_walk_turned(const detail::ZhfLobePlan& plan, const Mat3<T>& turn, const std::vector<Vec3<T>>& dirs,
                            T* walk, Emit&& emit) {
  const int D = plan.directions;
  T* x = walk + 5 * plan.order * D;
  T* y = x + D;
  T* z = y + D;
  for (int d = 0; d < D; ++d) {
    const Vec3<T> w = turn * dirs[d];
    x[d] = w.x();
    y[d] = w.y();
    z[d] = w.z();
  }
  zhf_walk<T>(plan, x, y, z, walk, std::forward<Emit>(emit));
}

}  // namespace

namespace {

// One row pair of Y_l(R)^T: yp[j] = q[j] c[j], yn[j] = q[j] s[j] (see set()).
template <class T>
inline void zhf_emit_rows(int n, const T* __restrict q, const T* __restrict c, const T* __restrict s,
                          T* __restrict yp, T* __restrict yn) {
  for (int j = 0; j < n; ++j) {
    yp[j] = q[j] * c[j];
    yn[j] = q[j] * s[j];
  }
}

// acc[j] += q[j] (fc c[j] + fs s[j]): one m of f~_l at n directions (see ZhfTailoredSignal::set).
template <class T>
inline void zhf_emit_samples(int n, T fc, T fs, const T* __restrict q, const T* __restrict c,
                             const T* __restrict s, T* __restrict acc) {
  for (int j = 0; j < n; ++j) acc[j] += q[j] * (fc * c[j] + fs * s[j]);
}

}  // namespace

namespace detail {

ZhfLobePlan::ZhfLobePlan(const ZhfLobes& lobes, int order_in) : order(order_in) {
  for (int l = 0; l < order; ++l) {
    band_offset.push_back(lobes.band_offset[l]);
    directions = std::max(directions, lobes.band_offset[l] + 2 * l + 1);
  }
  // Band l's recurrence serves every direction used by a band >= l: the hull of those
  // ranges, built from the top band down (it only grows as l decreases).
  active_lo.assign(order, directions);
  active_hi.assign(order, 0);
  int lo = directions, hi = 0;
  for (int l = order - 1; l >= 0; --l) {
    lo = std::min(lo, band_offset[l]);
    hi = std::max(hi, band_offset[l] + 2 * l + 1);
    active_lo[l] = lo;
    active_hi[l] = hi;
  }
  int total = 0;
  for (int l = 0; l < order; ++l) {
    block_offset.push_back(total);
    total += (2 * l + 1) * (2 * l + 1);
  }
  block_offset.push_back(total);
}

}  // namespace detail

template <class T>
ZhfRotation<T>::ZhfRotation(int order, std::shared_ptr<const ZhfLobes> lobes)
    : order_(order), lobes_(std::move(lobes)), plan_(*lobes_, order) {
  for (int d = 0; d < plan_.directions; ++d) dirs_.push_back(lobes_->directions[d].template cast<T>());
  // Transpose each band's CSR rows into columns once.
  csc_start_.assign(sh_count(order_) + 1, 0);
  for (int l = 0; l < order_; ++l)
    for (int m = 0; m <= 2 * l; ++m)
      for (int k = lobes_->row_start[l * l + m]; k < lobes_->row_start[l * l + m + 1]; ++k)
        ++csc_start_[l * l + lobes_->col[k] + 1];
  for (int i = 0; i < sh_count(order_); ++i) csc_start_[i + 1] += csc_start_[i];
  csc_row_.resize(csc_start_.back());
  csc_val_.resize(csc_start_.back());
  std::vector<int> fill(csc_start_.begin(), csc_start_.end() - 1);
  for (int l = 0; l < order_; ++l)
    for (int m = 0; m <= 2 * l; ++m)
      for (int k = lobes_->row_start[l * l + m]; k < lobes_->row_start[l * l + m + 1]; ++k) {
        const int at = fill[l * l + lobes_->col[k]]++;
        csc_row_[at] = m;
        csc_val_[at] = static_cast<T>(lobes_->val[k]);
      }
  y_.assign(plan_.block_offset.back(), T(0));
  walk_.assign(static_cast<std::size_t>(5 * order_ + 3) * plan_.directions, T(0));
  z_.assign(2 * order_ - 1, T(0));
  set(Mat3<T>::Identity());
}

template <class T>
bool ZhfRotation<T>::set(const Mat3<T>& r) {
  // Eq. 10: Y_l(R)[d][m] = y_l^m(R w_d). Each rotated direction is evaluated once, for
  // every band that uses it (shared lobes: 2N-1 evaluations serve the whole order).
  const int D = plan_.directions;
  T* yb = y_.data();
  zhf_walk_turned<T>(plan_, r, dirs_, walk_.data(), [&](int l, const T* q, const T* c, const T* s) {
    // Stored transposed, yt[(l + m) n + j] = y_l^m(R w_{off+j}): the direction index j is
    // contiguous both here and in the recurrence, so these loops vectorise.
    const int n = 2 * l + 1, off = plan_.band_offset[l];
    T* yt = yb + plan_.block_offset[l] + l * n;  // row m = 0
    const T* q0 = q + off;
    for (int j = 0; j < n; ++j) yt[j] = q0[j];
    for (int m = 1; m <= l; ++m) {
      const T* qm = q + m * D + off;
      const T* cm = c + m * D + off;
      const T* sm = s + m * D + off;
      zhf_emit_rows<T>(n, qm, cm, sm, yt + m * n, yt - m * n);
    }
  });
  return true;
}

template <class T>
void ZhfRotation<T>::apply(std::span<const T> in, std::span<T> out) const {
  const std::size_t n = static_cast<std::size_t>(sh_count(order_));
  detail::check_span_size("ZhfRotation::apply", "in", in.size(), n);
  detail::check_span_size("ZhfRotation::apply", "out", out.size(), n);
  const int* cs = csc_start_.data();
  const int* cr = csc_row_.data();
  const T* cv = csc_val_.data();
  T* z = z_.data();
  for (int l = 0; l < order_; ++l) {
    const int n = 2 * l + 1, base = l * l;
    const T* f = in.data() + base;
    // z = A^_l^T f_l over the stored non-zeros of A^_l only.
    for (int d = 0; d < n; ++d) {
      T acc = 0;
      for (int k = cs[base + d]; k < cs[base + d + 1]; ++k) acc += cv[k] * f[cr[k]];
      z[d] = acc;
    }
    // g_l = Y_l(R)^T z: row m of the stored transpose dotted with z.
    T* g = out.data() + base;
    const T* yt = y_.data() + plan_.block_offset[l];
    for (int m = 0; m < n; ++m) {
      const T* row = yt + m * n;
      T acc = 0;
      for (int d = 0; d < n; ++d) acc += row[d] * z[d];
      g[m] = acc;
    }
  }
}

template <class T>
ZhfTailoredSignal<T>::ZhfTailoredSignal(std::shared_ptr<const ZhfLobes> lobes, std::span<const T> coeffs)
    : lobes_(std::move(lobes)), f_(coeffs.begin(), coeffs.end()) {
  order_ = static_cast<int>(std::lround(std::sqrt(static_cast<double>(coeffs.size()))));
  plan_ = detail::ZhfLobePlan(*lobes_, order_);
  for (int d = 0; d < plan_.directions; ++d) dirs_.push_back(lobes_->directions[d].template cast<T>());
  val_.assign(lobes_->val.begin(), lobes_->val.begin() + lobes_->row_start[sh_count(order_)]);
  samples_.assign(sh_count(order_), T(0));
  walk_.assign(static_cast<std::size_t>(5 * order_ + 3) * plan_.directions, T(0));
  set(Mat3<T>::Identity());
}

template <class T>
bool ZhfTailoredSignal<T>::set(const Mat3<T>& r) {
  // Eq. 11: sample each band's expansion f~_l at the inversely rotated lobe directions; a
  // direction shared by several bands runs the recurrence once for all of them.
  const Mat3<T> rinv = r.transpose();
  const int D = plan_.directions;
  T* samples = samples_.data();
  const T* f = f_.data();
  zhf_walk_turned<T>(plan_, rinv, dirs_, walk_.data(), [&](int l, const T* q, const T* c, const T* s) {
    const int n = 2 * l + 1, off = plan_.band_offset[l];
    const T* fl = f + l * l + l;  // fl[m] = f_l^m, m = -l..l
    T* acc = samples + l * l;     // acc[j] = f~_l(R^-1 w_{off+j})
    const T f0 = fl[0];
    const T* q0 = q + off;
    for (int j = 0; j < n; ++j) acc[j] = f0 * q0[j];
    for (int m = 1; m <= l; ++m) {
      const T fc = fl[m], fs = fl[-m];
      const T* qm = q + m * D + off;
      const T* cm = c + m * D + off;
      const T* sm = s + m * D + off;
      zhf_emit_samples<T>(n, fc, fs, qm, cm, sm, acc);
    }
  });
  return true;
}

template <class T>
void ZhfTailoredSignal<T>::apply(std::span<T> out) const {
  detail::check_span_size("ZhfTailoredSignal::apply", "out", out.size(), static_cast<std::size_t>(sh_count(order_)));
  const T* samples = samples_.data();
  const int* rs = lobes_->row_start.data();
  const int* col = lobes_->col.data();
  const T* val = val_.data();
  for (int l = 0; l < order_; ++l) {
    const T* sl = samples + l * l;
    for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
      T acc = 0;
      for (int k = rs[i]; k < rs[i + 1]; ++k) acc += val[k] * sl[col[k]];
      out[i] = acc;
    }
  }
}

template <class T>
void ZhfTailoredSignal<T>::apply_samples(const ZhfLobes& lobes, int order, std::span<const T> samples,
                                         std::span<T> out) {
  const std::size_t n = static_cast<std::size_t>(sh_count(order));
  detail::check_span_size("ZhfTailoredSignal::apply_samples", "samples", samples.size(), n);
  detail::check_span_size("ZhfTailoredSignal::apply_samples", "out", out.size(), n);
  for (int l = 0; l < order; ++l) {
    const T* sl = samples.data() + l * l;
    for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
      T s = 0;
      for (int k = lobes.row_start[i]; k < lobes.row_start[i + 1]; ++k)
        s += static_cast<T>(lobes.val[k]) * sl[lobes.col[k]];
      out[i] = s;
    }
  }
}

template class ZhfRotation<float>;
template class ZhfRotation<double>;
template class ZhfTailoredSignal<float>;
template class ZhfTailoredSignal<double>;

}  // namespace shtool
