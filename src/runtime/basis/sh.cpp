#include "shtool/sh.h"

#include "basis/legendre_recurrence.h"

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace shtool {
namespace {

// We never form K_l^m or P_l^m separately: their product overflows/underflows for
// large l. Instead we run the recurrence on the normalised, pole-free quantity
//   Q_l^m(z) = K_l^m P_l^m(z) / sin^m(t)          (Condon-Shortley phase included)
// and multiply by sin^m(t) cos(m p) = Re (x + i y)^m, sin^m(t) sin(m p) = Im (x + i y)^m,
// which are polynomials in x, y and need no trigonometry. Then
//   y_l^0 = Q_l^0,  y_l^{+m} = sqrt2 Q_l^m Re(x+iy)^m,  y_l^{-m} = sqrt2 Q_l^m Im(x+iy)^m.
// The recurrence and its coefficients: basis/legendre_recurrence.h.
template <class T>
using RecurrenceTable = detail::LegendreRecurrence<T>;

// Walks the basis band by band (l outer, m inner) and calls
// visit(l, m_abs, q, dq, cm, sm, dcm[2], dsm[2]) with Q_l^m, its z-derivative and the
// azimuthal factors, so that eval, gradient and reconstruction share one recurrence.
// kGradient = false skips the derivative work.
template <class T, bool kGradient, class Visitor>
inline void walk_basis(int order, const Vec3<T>& w, Visitor&& visit) {
  const RecurrenceTable<T>& tab = detail::legendre_recurrence<T>();
  const T x = w.x(), y = w.y(), z = w.z();

  // Q_{l-2}^m, Q_{l-1}^m, Q_l^m for every m (and their z derivatives), in three buffers
  // whose roles rotate after each band (copying them instead became `rep movs` or a
  // memmove call per band, which dominated at low orders).
  // Left uninitialised on purpose: entry m is written before it is read, and zeroing
  // 8 x kMaxOrder values would dominate the cost at low orders.
  std::array<T, kMaxOrder> qa, qb, qc, dqa, dqb, dqc;
  T *q2 = qa.data(), *q1 = qb.data(), *q0 = qc.data();
  T *dq2 = dqa.data(), *dq1 = dqb.data(), *dq0 = dqc.data();
  // (x + i y)^m
  std::array<T, kMaxOrder> cm, sm;
  cm[0] = 1;
  sm[0] = 0;
  for (int m = 1; m < order; ++m) {
    cm[m] = x * cm[m - 1] - y * sm[m - 1];
    sm[m] = x * sm[m - 1] + y * cm[m - 1];
  }

  for (int l = 0; l < order; ++l) {
    // New diagonal and sub-diagonal terms, then the three-term recurrence below them.
    if (l == 0) {
      q0[0] = tab.q00;
      dq0[0] = 0;
    } else {
      q0[l] = tab.diag[l] * q1[l - 1];
      q0[l - 1] = tab.subdiag[l - 1] * z * q1[l - 1];
      if constexpr (kGradient) {
        dq0[l] = 0;
        dq0[l - 1] = tab.subdiag[l - 1] * q1[l - 1];
      }
      for (int m = 0; m <= l - 2; ++m) {
        const T a = tab.a[RecurrenceTable<T>::tri(l, m)];
        const T b = tab.b[RecurrenceTable<T>::tri(l, m)];
        q0[m] = a * (z * q1[m] - b * q2[m]);
        if constexpr (kGradient) dq0[m] = a * (q1[m] + z * dq1[m] - b * dq2[m]);
      }
    }
    for (int m = -l; m <= l; ++m) {
      const int ma = m < 0 ? -m : m;
      visit(l, m, q0[ma], dq0[ma], cm, sm);
    }
    T* const q_free = q2;  // next band overwrites every entry it reads
    q2 = q1;
    q1 = q0;
    q0 = q_free;
    if constexpr (kGradient) {
      T* const dq_free = dq2;
      dq2 = dq1;
      dq1 = dq0;
      dq0 = dq_free;
    }
  }
}

template <class T>
constexpr T kSqrt2 = static_cast<T>(std::numbers::sqrt2);

template <class T>
inline T basis_value(int m, T q, const std::array<T, kMaxOrder>& cm,
                     const std::array<T, kMaxOrder>& sm) {
  if (m == 0) return q;
  if (m > 0) return kSqrt2<T> * q * cm[m];
  return kSqrt2<T> * q * sm[-m];
}

}  // namespace

int sh_band(int index) {
  int l = static_cast<int>(std::sqrt(static_cast<double>(index)));
  while (l * l > index) --l;
  while ((l + 1) * (l + 1) <= index) ++l;
  return l;
}

bool is_supported_order(int order) { return order >= 1 && order <= kMaxOrder; }

template <class T>
void eval_sh(int order, const Vec3<T>& w, std::span<T> out) {
  T* dst = out.data();
  walk_basis<T, false>(order, w, [dst](int l, int m, T q, T, const auto& cm, const auto& sm) {
    dst[sh_index(l, m)] = basis_value<T>(m, q, cm, sm);
  });
}

template <class T>
void eval_sh_batch(int order, std::span<const T> dirs, std::span<T> out) {
  const std::size_t count = dirs.size() / 3;
  const std::size_t n = static_cast<std::size_t>(sh_count(order));
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3<T> w(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
    eval_sh<T>(order, w, out.subspan(k * n, n));
  }
}

template <class T>
void eval_sh_with_gradient(int order, const Vec3<T>& w, std::span<T> values, std::span<T> grad) {
  T* val = values.data();
  T* g = grad.data();
  // The basis is written as F(x, y, z) = Q(z) * (azimuthal polynomial in x, y); its
  // ambient gradient projected onto the tangent plane is the surface gradient.
  walk_basis<T, true>(order, w, [&](int l, int m, T q, T dq, const auto& cm, const auto& sm) {
    const int i = sh_index(l, m);
    val[i] = basis_value<T>(m, q, cm, sm);
    T gx, gy, gz;
    if (m == 0) {
      gx = 0;
      gy = 0;
      gz = dq;
    } else {
      const int ma = m < 0 ? -m : m;
      const T s = kSqrt2<T>;
      // d/dx (x+iy)^m = m (x+iy)^{m-1},  d/dy (x+iy)^m = i m (x+iy)^{m-1}
      const T mc = static_cast<T>(ma) * cm[ma - 1], ms = static_cast<T>(ma) * sm[ma - 1];
      if (m > 0) {
        gx = s * q * mc;
        gy = -s * q * ms;
        gz = s * dq * cm[ma];
      } else {
        gx = s * q * ms;
        gy = s * q * mc;
        gz = s * dq * sm[ma];
      }
    }
    const T radial = gx * w.x() + gy * w.y() + gz * w.z();
    g[3 * i + 0] = gx - radial * w.x();
    g[3 * i + 1] = gy - radial * w.y();
    g[3 * i + 2] = gz - radial * w.z();
  });
}

template <class T>
T reconstruct(std::span<const T> coeffs, const Vec3<T>& w) {
  const int order = static_cast<int>(std::lround(std::sqrt(static_cast<double>(coeffs.size()))));
  T sum = 0;
  const T* c = coeffs.data();
  walk_basis<T, false>(order, w, [&](int l, int m, T q, T, const auto& cm, const auto& sm) {
    sum += c[sh_index(l, m)] * basis_value<T>(m, q, cm, sm);
  });
  return sum;
}

template <class T>
Vec3<T> direction_from_angles(T theta, T phi) {
  const T st = std::sin(theta);
  return Vec3<T>(st * std::cos(phi), st * std::sin(phi), std::cos(theta));
}

#define SHTOOL_INSTANTIATE(T)                                                            \
  template void eval_sh<T>(int, const Vec3<T>&, std::span<T>);                           \
  template void eval_sh_batch<T>(int, std::span<const T>, std::span<T>);                 \
  template void eval_sh_with_gradient<T>(int, const Vec3<T>&, std::span<T>, std::span<T>); \
  template T reconstruct<T>(std::span<const T>, const Vec3<T>&);                         \
  template Vec3<T> direction_from_angles<T>(T, T);
SHTOOL_INSTANTIATE(float)
SHTOOL_INSTANTIATE(double)
#undef SHTOOL_INSTANTIATE

}  // namespace shtool
