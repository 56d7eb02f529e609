#include "shtool/rotation.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "shtool/sh.h"

namespace shtool {
namespace {

// Offset of band l's dense block: sum_{k<l} (2k+1)^2.
constexpr int block_offset(int l) { return l * (4 * l * l - 1) / 3; }

// cos(m a), sin(m a) for m = 0..n-1 from cos a, sin a by the multiple-angle recurrence
// (paper 001, App. C), in its complex form (c + i s)^m, whose rounding error grows
// only linearly in m: no trigonometric call at all.
template <class T>
void multiple_angles(T c1, T s1, int n, std::vector<T>& c, std::vector<T>& s) {
  c[0] = 1;
  s[0] = 0;
  for (int m = 1; m < n; ++m) {
    c[m] = c[m - 1] * c1 - s[m - 1] * s1;
    s[m] = s[m - 1] * c1 + c[m - 1] * s1;
  }
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
    // Keep the first N^2 rows of X90 (the table may cover more bands).
    x90_row_.assign(h.x90_row.begin(), h.x90_row.begin() + n + 1);
    const int nnz = x90_row_.back();
    x90_col_.assign(h.x90_col.begin(), h.x90_col.begin() + nnz);
    x90_val_.resize(nnz);
    for (int k = 0; k < nnz; ++k) x90_val_[k] = static_cast<T>(h.x90_val[k]);
    // Transpose (= X(-90)) in compressed rows too, so both products are gathers.
    x90t_row_.assign(n + 1, 0);
    for (int k = 0; k < nnz; ++k) ++x90t_row_[x90_col_[k] + 1];
    for (int i = 0; i < n; ++i) x90t_row_[i + 1] += x90t_row_[i];
    x90t_col_.resize(nnz);
    x90t_val_.resize(nnz);
    std::vector<int> fill(x90t_row_.begin(), x90t_row_.end() - 1);
    for (int i = 0; i < n; ++i)
      for (int k = x90_row_[i]; k < x90_row_[i + 1]; ++k) {
        const int slot = fill[x90_col_[k]]++;
        x90t_col_[slot] = i;
        x90t_val_[slot] = x90_val_[k];
      }
    dy_sub_.resize(n);
    ddy_diag_.resize(n);
    ddy_off2_.resize(n);
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
  tmp1_.assign(n, T(0));
  tmp2_.assign(n, T(0));
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
  multiple_angles<T>(e.ca, e.sa, order_, cos_a_, sin_a_);
  multiple_angles<T>(e.cg, e.sg, order_, cos_g_, sin_g_);
  switch (method) {
    case RotationMethod::zxzxz: multiple_angles<T>(e.cb, e.sb, order_, cos_b_, sin_b_); break;
    case RotationMethod::reference: build_reference(r); break;
    default: beta_ = std::atan2(e.sb, e.cb); break;
  }
  return true;
}

// z-rotation of every band: (f_m, f_-m) turns by m a (App. C).
template <class T>
void ShRotation<T>::apply_z(const std::vector<T>& cs, const std::vector<T>& sn, const T* in,
                            T* out) const {
  for (int l = 0; l < order_; ++l) {
    const int centre = l * (l + 1);
    out[centre] = in[centre];
    for (int m = 1; m <= l; ++m) {
      const T p = in[centre + m], q = in[centre - m];
      out[centre + m] = cs[m] * p - sn[m] * q;
      out[centre - m] = sn[m] * p + cs[m] * q;
    }
  }
}

template <class T>
void ShRotation<T>::apply_x90(const T* in, T* out, bool transpose) const {
  const int n = sh_count(order_);
  const std::vector<int>& row = transpose ? x90t_row_ : x90_row_;
  const std::vector<int>& col = transpose ? x90t_col_ : x90_col_;
  const std::vector<T>& val = transpose ? x90t_val_ : x90_val_;
  for (int i = 0; i < n; ++i) {
    T sum = 0;
    for (int k = row[i]; k < row[i + 1]; ++k) sum += val[k] * in[col[k]];
    out[i] = sum;
  }
}

// y-rotation by the truncated Taylor series I + b D1 (+ b^2/2 D2), band by band
// (paper 001, Sec. 3; D1 antisymmetric tridiagonal, D2 diagonal plus distance 2).
template <class T>
void ShRotation<T>::apply_taylor_y(const T* in, T* out) const {
  const T b = beta_, hb2 = T(0.5) * beta_ * beta_;
  const bool diag2 = resolved_ != RotationMethod::taylor1;
  const bool full2 = resolved_ == RotationMethod::taylor2;
  for (int l = 0; l < order_; ++l) {
    const int first = l * l, last = first + 2 * l;  // inclusive
    for (int i = first; i <= last; ++i) {
      T d = 0;  // (D1 in)_i = D1[i][i-1] in[i-1] + D1[i][i+1] in[i+1], D1[i][i+1] = -D1[i+1][i]
      if (i > first) d += dy_sub_[i] * in[i - 1];
      if (i < last) d -= dy_sub_[i + 1] * in[i + 1];
      T v = in[i] + b * d;
      if (diag2) {
        T dd = ddy_diag_[i] * in[i];
        if (full2) {
          if (i - 2 >= first) dd += ddy_off2_[i] * in[i - 2];
          if (i + 2 <= last) dd += ddy_off2_[i + 2] * in[i + 2];
        }
        v += hb2 * dd;
      }
      out[i] = v;
    }
  }
}

template <class T>
void ShRotation<T>::apply(std::span<const T> in, std::span<T> out) const {
  const T* src = in.data();
  T* dst = out.data();
  T* t1 = tmp1_.data();
  T* t2 = tmp2_.data();
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
    case RotationMethod::zxzxz:
      // M(R) = Z(a) X90^T Z(b) X90 Z(g), since Ry(b) = Rx(-90) Rz(b) Rx(+90).
      apply_z(cos_g_, sin_g_, src, t1);
      apply_x90(t1, t2, false);
      apply_z(cos_b_, sin_b_, t2, t1);
      apply_x90(t1, t2, true);
      apply_z(cos_a_, sin_a_, t2, dst);
      break;
    default:  // Taylor variants
      apply_z(cos_g_, sin_g_, src, t1);
      apply_taylor_y(t1, t2);
      apply_z(cos_a_, sin_a_, t2, dst);
      break;
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
