// ZHF rotation (paper 000, Sec. 7.1, Eq. 10-11). See include/shtool/zhf_rotation.h.
#include "shtool/zhf_rotation.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

namespace shtool {

namespace {

TableError bad(const std::filesystem::path& path, const std::string& what) {
  return TableError{path.string() + ": zhf-lobes table: " + what};
}

}  // namespace

TableResult<ZhfLobes> load_zhf_lobes(const std::filesystem::path& path, int order) {
  TableResult<Table> read = read_table(path, TableExpectation{"zhf-lobes", 1, 0});
  if (!read) return read.error();
  const Table& t = read.value();
  auto bands = t.get<std::int32_t>("bands");
  auto offset = t.get<std::int32_t>("direction_offset");
  auto dirs = t.get<double>("directions");
  auto rs = t.get<std::int32_t>("sparse_row_start");
  auto col = t.get<std::int32_t>("sparse_col");
  auto val = t.get<double>("sparse_val");
  auto cond = t.get<double>("cond");
  for (const auto* r : {&bands, &offset, &rs, &col})
    if (!*r) return bad(path, r->error().message);
  for (const auto* r : {&dirs, &val, &cond})
    if (!*r) return bad(path, r->error().message);
  const auto& b = bands.value();
  const int nb = static_cast<int>(b.size());
  if (nb == 0) return bad(path, "no bands");
  if (order < 0) return bad(path, "negative order requested");
  const int want = order == 0 ? nb : order;
  if (want > kMaxOrder) return bad(path, "order " + std::to_string(want) + " exceeds kMaxOrder");
  // Rotation needs every band 0..want-1, stored in order (shared and full tables do this).
  for (int l = 0; l < want; ++l)
    if (l >= nb || b[l] != l)
      return bad(path, "does not hold band " + std::to_string(l) + " at position " + std::to_string(l) +
                           " (bands 0.." + std::to_string(want - 1) + " are needed; a per-band search table "
                           "cannot rotate on its own)");
  const std::size_t nd = dirs.value().size() / 3;
  if (offset.value().size() != b.size() || cond.value().size() != b.size() || dirs.value().size() != 3 * nd)
    return bad(path, "arrays 'direction_offset', 'cond' and 'bands' differ in length");
  std::size_t rows = 0;
  for (int l = 0; l < nb; ++l) rows += 2 * b[l] + 1;
  const auto& start = rs.value();
  if (start.size() != rows + 1 || start[0] != 0 || static_cast<std::size_t>(start.back()) != col.value().size() ||
      col.value().size() != val.value().size())
    return bad(path, "sparse rows are inconsistent with 'bands'");

  ZhfLobes z;
  z.order = want;
  z.row_start.push_back(0);
  std::size_t row = 0;
  for (int l = 0; l < want; ++l) {
    const int n = 2 * l + 1, off = offset.value()[l];
    if (off < 0 || static_cast<std::size_t>(off) + n > nd)
      return bad(path, "band " + std::to_string(l) + " uses directions beyond the table");
    z.band_offset.push_back(off);
    z.cond.push_back(cond.value()[l]);
    for (int m = 0; m < n; ++m, ++row) {
      const int lo = start[row], hi = start[row + 1];
      if (hi < lo) return bad(path, "sparse_row_start is not monotone");
      for (int k = lo; k < hi; ++k) {
        const int c = col.value()[k];
        if (c < 0 || c >= n) return bad(path, "sparse_col out of range in band " + std::to_string(l));
        if (!std::isfinite(val.value()[k])) return bad(path, "non-finite A^ value in band " + std::to_string(l));
        z.col.push_back(c);
        z.val.push_back(val.value()[k]);
      }
      z.row_start.push_back(static_cast<int>(z.col.size()));
    }
  }
  // Keep only the directions the kept bands use.
  int used = 0;
  for (int l = 0; l < want; ++l) used = std::max(used, z.band_offset[l] + 2 * l + 1);
  z.eval_order.assign(used, 0);
  for (int d = 0; d < used; ++d) {
    const Vec3<double> w(dirs.value()[3 * d], dirs.value()[3 * d + 1], dirs.value()[3 * d + 2]);
    if (!w.allFinite() || std::abs(w.norm() - 1.0) > 1e-12)
      return bad(path, "direction " + std::to_string(d) + " is not a unit vector");
    z.directions.push_back(w);
  }
  for (int l = 0; l < want; ++l)
    for (int d = 0; d < 2 * l + 1; ++d) z.eval_order[z.band_offset[l] + d] = l + 1;
  return z;
}

std::filesystem::path default_zhf_lobes_path(int order) {
  std::vector<std::filesystem::path> dirs;
  if (const char* env = std::getenv("SHTOOL_TABLES")) dirs.emplace_back(env);
  dirs.emplace_back(SHTOOL_SOURCE_TABLES_DIR);
  dirs.emplace_back(SHTOOL_INSTALL_TABLES_DIR);
  std::error_code ec;
  for (const auto& dir : dirs)
    for (int n = std::max(order, 1); n <= kMaxOrder; ++n) {
      const auto p = dir / ("zhf-shared-N" + std::to_string(n) + ".shtb");
      if (std::filesystem::exists(p, ec)) return p;
    }
  return {};
}

// ---------------------------------------------------------------------------

template <class T>
ZhfRotation<T>::ZhfRotation(int order, std::shared_ptr<const ZhfLobes> lobes)
    : order_(order), lobes_(std::move(lobes)) {
  val_.assign(lobes_->val.begin(), lobes_->val.begin() + lobes_->row_start[sh_count(order_)]);
  std::size_t total = 0;
  int nd = 0;
  for (int l = 0; l < order_; ++l) nd = std::max(nd, lobes_->band_offset[l] + 2 * l + 1);
  for (int d = 0; d < nd; ++d) {
    y_offset_.push_back(total);
    total += sh_count(std::min(order_, lobes_->eval_order[d]));
  }
  y_offset_.push_back(total);
  y_.assign(total, T(0));
  z_.assign(2 * order_ - 1, T(0));
  set(Mat3<T>::Identity());
}

template <class T>
void ZhfRotation<T>::set(const Mat3<T>& r) {
  // Eq. 10: Y(R) holds the SH of the rotated lobe directions R w_d, evaluated once each
  // (with shared lobes, 2N-1 evaluations serve every band).
  const int nd = static_cast<int>(y_offset_.size()) - 1;
  for (int d = 0; d < nd; ++d) {
    const Vec3<T> w = r * lobes_->directions[d].template cast<T>();
    const int n = std::min(order_, lobes_->eval_order[d]);
    eval_sh<T>(n, w, std::span<T>(y_.data() + y_offset_[d], sh_count(n)));
  }
}

template <class T>
void ZhfRotation<T>::apply(std::span<const T> in, std::span<T> out) const {
  const int* rs = lobes_->row_start.data();
  const int* col = lobes_->col.data();
  const T* val = val_.data();
  T* z = z_.data();
  for (int l = 0; l < order_; ++l) {
    const int n = 2 * l + 1, base = l * l, off = lobes_->band_offset[l];
    // z = A^_l^T f_l, touching only the stored non-zeros of A^_l.
    std::fill(z, z + n, T(0));
    for (int m = 0; m < n; ++m) {
      const T f = in[base + m];
      for (int k = rs[base + m]; k < rs[base + m + 1]; ++k) z[col[k]] += val[k] * f;
    }
    // g_l = Y_l(R)^T z.
    for (int m = 0; m < n; ++m) out[base + m] = T(0);
    for (int d = 0; d < n; ++d) {
      const T* y = y_.data() + y_offset_[off + d] + base;
      const T zd = z[d];
      for (int m = 0; m < n; ++m) out[base + m] += y[m] * zd;
    }
  }
}

template <class T>
ZhfTailoredSignal<T>::ZhfTailoredSignal(std::shared_ptr<const ZhfLobes> lobes, std::span<const T> coeffs)
    : lobes_(std::move(lobes)), f_(coeffs.begin(), coeffs.end()) {
  order_ = static_cast<int>(std::lround(std::sqrt(static_cast<double>(coeffs.size()))));
  samples_.assign(sh_count(order_), T(0));
  ybuf_.assign(sh_count(order_), T(0));
}

template <class T>
void ZhfTailoredSignal<T>::rotate(const Mat3<T>& r, std::span<T> out) const {
  // Eq. 11: sample each band's expansion at the inversely rotated lobe directions. A
  // direction shared by several bands is evaluated once, for all of them.
  const Mat3<T> rinv = r.transpose();
  const int nd = static_cast<int>(lobes_->directions.size());
  for (int d = 0; d < nd; ++d) {
    int top = 0;  // highest band (below order_) that uses direction d, plus one
    for (int l = 0; l < order_; ++l)
      if (d >= lobes_->band_offset[l] && d < lobes_->band_offset[l] + 2 * l + 1) top = l + 1;
    if (!top) continue;
    const Vec3<T> u = rinv * lobes_->directions[d].template cast<T>();
    eval_sh<T>(top, u, std::span<T>(ybuf_.data(), sh_count(top)));
    for (int l = 0; l < top; ++l) {
      const int j = d - lobes_->band_offset[l];
      if (j < 0 || j > 2 * l) continue;
      T s = 0;
      for (int m = 0; m < 2 * l + 1; ++m) s += f_[l * l + m] * ybuf_[l * l + m];
      samples_[l * l + j] = s;
    }
  }
  apply_samples(*lobes_, order_, samples_, out);
}

template <class T>
void ZhfTailoredSignal<T>::apply_samples(const ZhfLobes& lobes, int order, std::span<const T> samples,
                                         std::span<T> out) {
  for (int i = 0; i < sh_count(order); ++i) {
    const int l = sh_band(i);
    T s = 0;
    for (int k = lobes.row_start[i]; k < lobes.row_start[i + 1]; ++k)
      s += static_cast<T>(lobes.val[k]) * samples[l * l + lobes.col[k]];
    out[i] = s;
  }
}

template class ZhfRotation<float>;
template class ZhfRotation<double>;
template class ZhfTailoredSignal<float>;
template class ZhfTailoredSignal<double>;

}  // namespace shtool
