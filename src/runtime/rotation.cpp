#include "shtool/rotation.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "shtool/sh.h"

namespace shtool {
namespace {

// Offset of band l's dense block: sum_{k<l} (2k+1)^2.
constexpr int block_offset(int l) { return l * (4 * l * l - 1) / 3; }

// Number of non-zeros in row j (m = j - l) of band l of X90, and of X90^T: X90 maps
// the four classes of m (sign, parity) onto each other by square dense blocks of sizes
// floor(l/2) and ceil(l/2) (+1 for m >= 0 even). Checked against the table when the
// rotation is constructed.
constexpr int x90_row_length(int l, int j) {
  const int m = j - l;
  if (l & 1) return (m < 0 && !(m & 1)) ? (l - 1) / 2 : (l + 1) / 2;
  return (m >= 0 && !(m & 1)) ? l / 2 + 1 : l / 2;
}

}  // namespace

std::string_view rotation_method_name(RotationMethod method) {
  switch (method) {
    case RotationMethod::automatic: return "auto";
    case RotationMethod::reference: return "reference";
    case RotationMethod::zxzxz: return "zxzxz";
    case RotationMethod::taylor1: return "taylor1";
    case RotationMethod::taylor15: return "taylor1.5";
    case RotationMethod::taylor2: return "taylor2";
  }
  return "?";
}

std::optional<RotationMethod> rotation_method_from_name(std::string_view name) {
  for (RotationMethod m : {RotationMethod::automatic, RotationMethod::reference, RotationMethod::zxzxz,
                           RotationMethod::taylor1, RotationMethod::taylor15, RotationMethod::taylor2})
    if (rotation_method_name(m) == name) return m;
  return std::nullopt;
}

double taylor_error_bound(RotationMethod method, int order, double beta, double ddy_offdiag_norm) {
  // M(Ry(b)) = exp(b D1) with D1 real antisymmetric (normal), eigenvalues i m for
  // |m| <= l in band l. Truncations of the exponential series are polynomials in D1, so
  // the error is normal too and its norm is the largest scalar error over the spectrum:
  //   |e^{i t} - 1 - i t| (1st order), |e^{i t} - 1 - i t + t^2 / 2| (2nd order),
  // both increasing in t = |b| m on the range where they matter, so m = N - 1.
  const double t = std::abs(beta) * (order - 1);
  const std::complex<double> e = std::polar(1.0, t);
  const std::complex<double> first = e - std::complex<double>(1.0, t);
  const std::complex<double> second = first + 0.5 * t * t;
  switch (method) {
    case RotationMethod::taylor1: return std::abs(first);
    case RotationMethod::taylor2: return std::abs(second);
    // 1.5th order drops the off-diagonal part of D2 from the 2nd order expansion.
    case RotationMethod::taylor15: return std::abs(second) + 0.5 * beta * beta * ddy_offdiag_norm;
    default: return 0.0;
  }
}

template <class T>
ShRotation<T>::ShRotation(int order, std::shared_ptr<const RotationHelpers> helpers)
    : order_(order), helpers_(std::move(helpers)) {
  const int n = sh_count(order);
  if (helpers_ && helpers_->order >= order) {
    const RotationHelpers& h = *helpers_;
    // X90 band by band in strided rows (see rotation.h). The non-zeros of a row lie in
    // one class of columns (sign of m, parity of m), so they are c0, c0 + 2, ... ;
    // checked here, since the apply loops rely on it. A class may hold a few exact
    // zeros (kept: the loops are branch-free), so size for the dense blocks.
    x90_val_.assign(block_offset(order), T(0));
    x90t_val_.assign(block_offset(order), T(0));
    x90_start_.assign(n, 0);
    x90t_start_.assign(n, 0);
    x90_band_val_.assign(order + 1, 0);
    x90t_band_val_.assign(order + 1, 0);
    // Position of band-relative column j once the band is split: even j first, then odd.
    auto split_pos = [](int l, int j) { return (j & 1) ? l + 1 + (j >> 1) : (j >> 1); };
    int written = 0, written_t = 0;
    for (int l = 0; l < order; ++l) {
      const int first = l * l, size = 2 * l + 1;
      x90_band_val_[l] = written;
      x90t_band_val_[l] = written_t;
      // Dense copy of the band block, to read rows of X90 and of its transpose alike.
      std::vector<double> block(size * size, 0.0);
      for (int i = first; i < first + size; ++i)
        for (int k = h.x90_row[i]; k < h.x90_row[i + 1]; ++k)
          block[(i - first) * size + (h.x90_col[k] - first)] = h.x90_val[k];
      auto pack = [&](bool transpose, std::vector<int>& start, std::vector<T>& val, int& out) {
        for (int r = 0; r < size; ++r) {
          auto at = [&](int c) { return transpose ? block[c * size + r] : block[r * size + c]; };
          int nz = -1;
          for (int c = 0; c < size && nz < 0; ++c)
            if (at(c) != 0.0) nz = c;
          if (nz < 0) throw std::logic_error("X90 row is empty");
          // The class of the first non-zero column (sign of m, parity of m) is the run
          // of columns this row reads: lo, lo + 2, ..., hi.
          const int m = nz - l, odd = m & 1;
          const int m_lo = m < 0 ? -l + (((-l) & 1) != odd) : odd;
          const int m_hi = m < 0 ? -1 - (odd == 0) : l - ((l & 1) != odd);
          const int lo = m_lo + l, hi = m_hi + l;
          if ((hi - lo) / 2 + 1 != x90_row_length(l, r)) throw std::logic_error("X90 row class size");
          for (int c = 0; c < size; ++c)
            if (at(c) != 0.0 && (c < lo || c > hi || (c - lo) % 2))
              throw std::logic_error("X90 row is not parity-strided");
          start[first + r] = split_pos(l, lo);
          for (int c = lo; c <= hi; c += 2) val[out++] = static_cast<T>(at(c));
        }
      };
      pack(false, x90_start_, x90_val_, written);
      pack(true, x90t_start_, x90t_val_, written_t);
    }
    x90_band_val_[order] = written;
    x90t_band_val_[order] = written_t;
    x90_val_.resize(written);
    x90t_val_.resize(written_t);
    dy_sub_.assign(n + 2, T(0));
    ddy_diag_.assign(n + 2, T(0));
    ddy_off2_.assign(n + 2, T(0));
    for (int i = 0; i < n; ++i) {
      dy_sub_[i] = static_cast<T>(h.dy_sub[i]);
      ddy_diag_[i] = static_cast<T>(h.ddy_diag[i]);
      ddy_off2_[i] = static_cast<T>(h.ddy_off2[i]);
    }
    // Infinity norm of the off-diagonal part of D2 (symmetric, so it bounds the
    // spectral norm): what the 1.5th order expansion leaves out.
    for (int i = 0; i < n; ++i) {
      const double row = std::abs(h.ddy_off2[i]) + (i + 2 < n ? std::abs(h.ddy_off2[i + 2]) : 0.0);
      ddy_offdiag_norm_ = std::max(ddy_offdiag_norm_, row);
    }
  } else {
    helpers_.reset();
  }
  for (auto* v : {&cos_a_, &sin_a_, &cos_b_, &sin_b_, &cos_g_, &sin_g_}) v->assign(order, T(0));
  // One band at a time, with two zeros of padding on each side for the Taylor loop.
  tmp1_.assign(2 * order + 4, T(0));
  tmp2_.assign(2 * order + 4, T(0));
  dense_.assign(block_offset(order), T(0));
}

template <class T>
void ShRotation<T>::update_taylor_limits(double tolerance) {
  // Largest tilt at which each Taylor method's bound is within the tolerance, by
  // bisection (the bounds increase with the tilt on [0, pi/2]); stored as sin(limit) so
  // set() compares it with sin(b) straight from the matrix, without an atan2.
  cached_tolerance_ = tolerance;
  const RotationMethod methods[3] = {RotationMethod::taylor1, RotationMethod::taylor15,
                                     RotationMethod::taylor2};
  for (int k = 0; k < 3; ++k) {
    double lo = 0.0, hi = 1.5707963267948966;
    if (taylor_error_bound(methods[k], order_, hi, ddy_offdiag_norm_) <= tolerance) {
      lo = hi;
    } else {
      for (int iter = 0; iter < 60; ++iter) {
        const double mid = 0.5 * (lo + hi);
        (taylor_error_bound(methods[k], order_, mid, ddy_offdiag_norm_) <= tolerance ? lo : hi) = mid;
      }
    }
    taylor_limit_sin_[k] = std::sin(lo);
  }
}

template <class T>
bool ShRotation<T>::set(const Mat3<T>& r, RotationMethod method, double tolerance) {
  if (method != RotationMethod::reference && !helpers_) return false;
  const ZyzCosSin<T> e = zyz_cos_sin_from_matrix<T>(r);
  if (method == RotationMethod::automatic) {
    if (tolerance != cached_tolerance_) update_taylor_limits(tolerance);
    method = RotationMethod::zxzxz;
    if (e.cb > 0) {
      const RotationMethod taylor[3] = {RotationMethod::taylor1, RotationMethod::taylor15,
                                        RotationMethod::taylor2};
      for (int k = 0; k < 3; ++k)
        if (static_cast<double>(e.sb) <= taylor_limit_sin_[k]) {
          method = taylor[k];
          break;
        }
    }
  }
  resolved_ = method;
  switch (method) {
    case RotationMethod::zxzxz: {
      // cos(m a), sin(m a) by the multiple-angle recurrence (paper 001, App. C) in its
      // complex form (c + i s)^m, whose rounding error grows only linearly in m: no
      // trigonometric call. The three recurrences are independent: one loop lets them
      // overlap (each is a chain of dependent multiplications).
      T* ca = cos_a_.data(); T* sa = sin_a_.data();
      T* cb = cos_b_.data(); T* sb = sin_b_.data();
      T* cg = cos_g_.data(); T* sg = sin_g_.data();
      ca[0] = cb[0] = cg[0] = 1;
      sa[0] = sb[0] = sg[0] = 0;
      for (int m = 1; m < order_; ++m) {
        ca[m] = ca[m - 1] * e.ca - sa[m - 1] * e.sa;
        sa[m] = sa[m - 1] * e.ca + ca[m - 1] * e.sa;
        cb[m] = cb[m - 1] * e.cb - sb[m - 1] * e.sb;
        sb[m] = sb[m - 1] * e.cb + cb[m - 1] * e.sb;
        cg[m] = cg[m - 1] * e.cg - sg[m - 1] * e.sg;
        sg[m] = sg[m - 1] * e.cg + cg[m - 1] * e.sg;
      }
      // Band 1 of M(R) is R in (y, z, x) order, entries (m, n) with m + n odd negated
      // (Condon-Shortley phase; see build_reference): exact and cheaper than zxzxz.
      const int axis[3] = {1, 2, 0};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r1_[i * 3 + j] = ((i == 1) != (j == 1)) ? -r(axis[i], axis[j]) : r(axis[i], axis[j]);
      break;
    }
    case RotationMethod::reference: build_reference(r); break;
    default: {
      T* ca = cos_a_.data(); T* sa = sin_a_.data();
      T* cg = cos_g_.data(); T* sg = sin_g_.data();
      ca[0] = cg[0] = 1;
      sa[0] = sg[0] = 0;
      for (int m = 1; m < order_; ++m) {  // one loop: the two recurrences overlap
        ca[m] = ca[m - 1] * e.ca - sa[m - 1] * e.sa;
        sa[m] = sa[m - 1] * e.ca + ca[m - 1] * e.sa;
        cg[m] = cg[m - 1] * e.cg - sg[m - 1] * e.sg;
        sg[m] = sg[m - 1] * e.cg + cg[m - 1] * e.sg;
      }
      beta_ = std::atan2(e.sb, e.cb);
      break;
    }
  }
  return true;
}

namespace {

// The band kernels below take the band as a template argument L for the small bands
// (L > 0: every loop has a fixed trip count and is unrolled; at small orders loop
// overheads would otherwise cost more than the arithmetic) and at run time otherwise
// (L = 0: then l is used).

// Band l of a z-rotation: (f_m, f_-m) turns by m a (paper 001, App. C). `in` is the band
// in natural order (m = -l..l); the result goes to `out` split by parity of the
// band-relative index j = m + l (even j at j / 2, odd j at l + 1 + j / 2), the order
// in which the strided X90 rows read their input.
template <int L, class T>
inline void z_band_to_split(int l_run, const T* __restrict c, const T* __restrict s,
                            const T* __restrict in, T* __restrict out) {
  const int l = L > 0 ? L : l_run;
  T* even = out;
  T* odd = out + l + 1;
  ((l & 1) ? odd : even)[l >> 1] = in[l];
  for (int m = 1; m <= l; ++m) {
    const T p = in[l + m], q = in[l - m];
    T* half = ((l + m) & 1) ? odd : even;  // l + m and l - m have the same parity
    half[(l + m) >> 1] = c[m] * p - s[m] * q;
    half[(l - m) >> 1] = s[m] * p + c[m] * q;
  }
}

// Band l of a z-rotation, natural order in and out.
template <int L, class T>
inline void z_band(int l_run, const T* __restrict c, const T* __restrict s, const T* __restrict in,
                   T* __restrict out) {
  const int l = L > 0 ? L : l_run;
  out[l] = in[l];
  for (int m = 1; m <= l; ++m) {
    const T p = in[l + m], q = in[l - m];
    out[l + m] = c[m] * p - s[m] * q;
    out[l - m] = s[m] * p + c[m] * q;
  }
}

// Rows of one band of X90 (or its transpose) in strided form, reading the split input.
template <int L, class T>
inline void strided_rows(int l_run, const int* __restrict start, const T* __restrict val,
                         const T* __restrict in, T* __restrict out) {
  const int l = L > 0 ? L : l_run;
  for (int r = 0; r <= 2 * l; ++r) {
    const T* x = in + start[r];
    const int count = x90_row_length(l, r);
    T sum = 0;
    for (int k = 0; k < count; ++k) sum += val[k] * x[k];
    val += count;
    out[r] = sum;
  }
}

}  // namespace

// Band l of M(R) = Z(a) X90^T Z(b) X90 Z(g) (Ry(b) = Rx(-90) Rz(b) Rx(+90)), with the
// intermediate vectors in two small buffers.
template <class T>
template <int L>
void ShRotation<T>::zxzxz_band(int l, const T* in, T* out) const {
  const int first = l * l;
  T* __restrict t1 = tmp1_.data();
  T* __restrict t2 = tmp2_.data();
  z_band_to_split<L>(l, cos_g_.data(), sin_g_.data(), in + first, t1);
  strided_rows<L>(l, x90_start_.data() + first, x90_val_.data() + x90_band_val_[l], t1, t2);
  z_band_to_split<L>(l, cos_b_.data(), sin_b_.data(), t2, t1);
  strided_rows<L>(l, x90t_start_.data() + first, x90t_val_.data() + x90t_band_val_[l], t1, t2);
  z_band<L>(l, cos_a_.data(), sin_a_.data(), t2, out + first);
}

// Band 0 is invariant and band 1 is R itself; the others by zxzxz.
template <class T>
void ShRotation<T>::apply_zxzxz(const T* in, T* out) const {
  out[0] = in[0];
  if (order_ < 2) return;
  for (int i = 0; i < 3; ++i)
    out[1 + i] = r1_[i * 3] * in[1] + r1_[i * 3 + 1] * in[2] + r1_[i * 3 + 2] * in[3];
  for (int l = 2; l < order_; ++l) {
    switch (l) {
      case 2: zxzxz_band<2>(l, in, out); break;
      case 3: zxzxz_band<3>(l, in, out); break;
      case 4: zxzxz_band<4>(l, in, out); break;
      case 5: zxzxz_band<5>(l, in, out); break;
      case 6: zxzxz_band<6>(l, in, out); break;
      case 7: zxzxz_band<7>(l, in, out); break;
      default: zxzxz_band<0>(l, in, out); break;
    }
  }
}

namespace {

// The y part of the Taylor rotation for one band (paper 001, Sec. 3): u = t + b D1 t
// (+ b^2/2 D2 t), D1 antisymmetric tridiagonal (only its sub-diagonal s1 is stored), D2
// diagonal (sd) plus distance 2 (s2). Order 1, 15 (diagonal of D2 only) or 2. t has two
// zeros of padding on each side and the derivative entries that would reach into a
// neighbouring band are zero, so the loop needs no bounds tests.
template <int L, int Order, class T>
inline void taylor_y_band(int l_run, T b, T hb2, const T* __restrict s1, const T* __restrict sd,
                          const T* __restrict s2, const T* __restrict t, T* __restrict u) {
  const int size = 2 * (L > 0 ? L : l_run) + 1;
  for (int i = 0; i < size; ++i) {
    T v = t[i] + b * (s1[i] * t[i - 1] - s1[i + 1] * t[i + 1]);
    if constexpr (Order == 15) v += hb2 * (sd[i] * t[i]);
    if constexpr (Order == 2) v += hb2 * (sd[i] * t[i] + s2[i] * t[i - 2] + s2[i + 2] * t[i + 2]);
    u[i] = v;
  }
}

}  // namespace

// Band l of Z(a) T(b) Z(g), T the truncated Taylor series of the y-rotation.
template <class T>
template <int L, int Order>
void ShRotation<T>::taylor_band(int l, const T* in, T* out) const {
  const int first = l * l, size = 2 * l + 1;
  T* __restrict t = tmp1_.data() + 2;  // t[-2], t[-1] and t[size], t[size + 1] are 0
  T* __restrict u = tmp2_.data();
  z_band<L>(l, cos_g_.data(), sin_g_.data(), in + first, t);
  t[size] = t[size + 1] = 0;
  taylor_y_band<L, Order>(l, beta_, T(0.5) * beta_ * beta_, dy_sub_.data() + first,
                          ddy_diag_.data() + first, ddy_off2_.data() + first, t, u);
  z_band<L>(l, cos_a_.data(), sin_a_.data(), u, out + first);
}

template <class T>
template <int Order>
void ShRotation<T>::apply_taylor_order(const T* in, T* out) const {
  tmp1_[0] = tmp1_[1] = 0;  // left padding (the zxzxz path shares the buffer)
  out[0] = in[0];
  for (int l = 1; l < order_; ++l) {
    switch (l) {  // small bands with fixed trip counts, as in apply_zxzxz
      case 1: taylor_band<1, Order>(l, in, out); break;
      case 2: taylor_band<2, Order>(l, in, out); break;
      case 3: taylor_band<3, Order>(l, in, out); break;
      case 4: taylor_band<4, Order>(l, in, out); break;
      case 5: taylor_band<5, Order>(l, in, out); break;
      default: taylor_band<0, Order>(l, in, out); break;
    }
  }
}

template <class T>
void ShRotation<T>::apply_taylor(const T* in, T* out) const {
  switch (resolved_) {
    case RotationMethod::taylor1: apply_taylor_order<1>(in, out); break;
    case RotationMethod::taylor15: apply_taylor_order<15>(in, out); break;
    default: apply_taylor_order<2>(in, out); break;
  }
}

template <class T>
void ShRotation<T>::apply(std::span<const T> in, std::span<T> out) const {
  const T* src = in.data();
  T* dst = out.data();
  switch (resolved_) {
    case RotationMethod::reference: {
      for (int l = 0; l < order_; ++l) {
        const int size = 2 * l + 1, first = l * l;
        const T* block = dense_.data() + block_offset(l);
        for (int r = 0; r < size; ++r) {
          T sum = 0;
          for (int c = 0; c < size; ++c) sum += block[r * size + c] * src[first + c];
          dst[first + r] = sum;
        }
      }
      break;
    }
    case RotationMethod::zxzxz: apply_zxzxz(src, dst); break;
    default: apply_taylor(src, dst); break;  // Taylor variants
  }
}

// Ivanic-Ruedenberg recurrences (J. Phys. Chem. 1996, with the 1998 errata), written
// for real SH without the Condon-Shortley phase, whose band-1 matrix is R itself in
// the (y, z, x) order. Our basis differs from theirs by (-1)^m on every function, so
// the result is conjugated by diag((-1)^m) at the end.
template <class T>
void ShRotation<T>::build_reference(const Mat3<T>& r) {
  // Band 0.
  dense_[0] = 1;
  if (order_ < 2) return;
  // Band 1 in IR's basis: index m = -1, 0, 1 <-> y, z, x.
  const int axis[3] = {1, 2, 0};
  T* b1 = dense_.data() + block_offset(1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) b1[i * 3 + j] = r(axis[i], axis[j]);
  auto r1 = [b1](int i, int j) { return b1[(i + 1) * 3 + (j + 1)]; };

  for (int l = 2; l < order_; ++l) {
    const T* prev = dense_.data() + block_offset(l - 1);
    T* cur = dense_.data() + block_offset(l);
    const int ps = 2 * l - 1, cs = 2 * l + 1;
    auto mp = [prev, ps, l](int a, int b) { return prev[(a + l - 1) * ps + (b + l - 1)]; };
    // P^l_{i,a,b}
    auto P = [&](int i, int a, int b) -> T {
      if (b == l) return r1(i, 1) * mp(a, l - 1) - r1(i, -1) * mp(a, -l + 1);
      if (b == -l) return r1(i, 1) * mp(a, -l + 1) + r1(i, -1) * mp(a, l - 1);
      return r1(i, 0) * mp(a, b);
    };
    for (int m = -l; m <= l; ++m) {
      const int am = std::abs(m);
      const T d = m == 0 ? T(1) : T(0);
      for (int n = -l; n <= l; ++n) {
        const T denom = std::abs(n) == l ? T(2 * l * (2 * l - 1)) : T((l + n) * (l - n));
        const T u = std::sqrt(T((l + m) * (l - m)) / denom);
        const T v = T(0.5) * std::sqrt((1 + d) * T((l + am - 1) * (l + am)) / denom) * (1 - 2 * d);
        const T w = T(-0.5) * std::sqrt(T((l - am - 1) * (l - am)) / denom) * (1 - d);
        T value = 0;
        if (u != 0) value += u * P(0, m, n);
        if (v != 0) {
          T V;
          if (m == 0) V = P(1, 1, n) + P(-1, -1, n);
          else if (m > 0) V = P(1, m - 1, n) * std::sqrt(T(1) + (m == 1)) - P(-1, -m + 1, n) * T(m != 1);
          else V = P(1, m + 1, n) * T(m != -1) + P(-1, -m - 1, n) * std::sqrt(T(1) + (m == -1));
          value += v * V;
        }
        if (w != 0) {
          T W;
          if (m > 0) W = P(1, m + 1, n) + P(-1, -m - 1, n);
          else W = P(1, m - 1, n) - P(-1, -m + 1, n);
          value += w * W;
        }
        cur[(m + l) * cs + (n + l)] = value;
      }
    }
  }
  // Condon-Shortley phase: entry (m, n) of every band picks up (-1)^(m + n).
  for (int l = 1; l < order_; ++l) {
    T* block = dense_.data() + block_offset(l);
    const int size = 2 * l + 1;
    for (int m = -l; m <= l; ++m)
      for (int n = -l; n <= l; ++n)
        if ((m + n) & 1) block[(m + l) * size + (n + l)] = -block[(m + l) * size + (n + l)];
  }
}

template <class T>
bool rotate_batch(ShRotation<T>& rotation, std::span<const Mat3<T>> rotations, std::span<const T> in,
                  std::span<T> out, RotationMethod method, double tolerance) {
  const std::size_t n = static_cast<std::size_t>(sh_count(rotation.order()));
  for (std::size_t k = 0; k < rotations.size(); ++k) {
    if (!rotation.set(rotations[k], method, tolerance)) return false;
    rotation.apply(in.subspan(k * n, n), out.subspan(k * n, n));
  }
  return true;
}

template class ShRotation<float>;
template class ShRotation<double>;
template bool rotate_batch<float>(ShRotation<float>&, std::span<const Mat3<float>>, std::span<const float>,
                                  std::span<float>, RotationMethod, double);
template bool rotate_batch<double>(ShRotation<double>&, std::span<const Mat3<double>>,
                                   std::span<const double>, std::span<double>, RotationMethod, double);

}  // namespace shtool
