// Internal to the runtime: fixed-order SH rotation kernels. The per-band arithmetic of
// the zxzxz and Taylor rotations for small bands is generated, with X90, D1 and D2 as
// literal constants and every loop unrolled, into rotation_kernels_generated.cpp by
// `shtool gen-tensors --what rotation-kernels --out src/runtime/kernels` (src/offline/tensors/
// rotation_kernels_gen.cpp); tests/test_rotation_kernels.cpp regenerates it and compares
// the bytes, so the committed source cannot drift from its generator. Bands 1 and 2 have
// closed forms in R: band 1 (every order) in shtool/rotation.h, band 2 here (used at
// order 3 only, where it spares the Euler angles; from order 4 on the angles are needed
// anyway and the zxzxz band is cheaper).
#pragma once

#include <type_traits>

#include "shtool/rotation.h"

namespace shtool::detail {

// The helpers and band bodies are forced inline into the entry points: GCC does not
// inline ordinary functions into the FMA copies (their target differs), and a call per
// band would cost more than the band.
#if defined(__GNUC__)
#define SHTOOL_KERNEL_INLINE __attribute__((always_inline)) inline
#define SHTOOL_KERNEL_LAMBDA_INLINE __attribute__((always_inline))
#else
#define SHTOOL_KERNEL_INLINE inline
#define SHTOOL_KERNEL_LAMBDA_INLINE
#endif

// Largest band with a generated kernel; orders up to kKernelMaxBand + 1 run entirely in
// one generated function.
inline constexpr int kKernelMaxBand = 9;
inline constexpr int kKernelMaxOrder = kKernelMaxBand + 1;
// Bands kKernelMaxOrder..kBandKernelMaxBand have generated kernels of their own (called
// one band at a time); larger bands run the table-driven code in rotation.cpp.
inline constexpr int kBandKernelMaxBand = 19;

// Lanes of one rotation: V = 1 is the plain type; V = 3 (an RGB light) runs the three
// vectors in the lanes of one 4-wide vector (GCC/Clang vector extension; for float one
// SSE register), so the three cost one pass over the code and its constants. Lane
// arithmetic is the same IEEE arithmetic as the scalar code.
template <class T, int V>
struct Lanes;
template <class T>
struct Lanes<T, 1> {
  using type = T;
};
#pragma GCC diagnostic push
// Without AVX a 4-double lane vector is passed differently from an AVX build; these
// functions are internal and inlined, so no ABI is involved.
#pragma GCC diagnostic ignored "-Wpsabi"
template <class T>
struct Lanes<T, 3> {
  typedef T type __attribute__((vector_size(4 * sizeof(T))));
};
template <class T, int V>
using Pack = typename Lanes<T, V>::type;

// A scalar in every lane.
template <class P, class T>
SHTOOL_KERNEL_INLINE P splat(T v) {
  if constexpr (std::is_same_v<P, T>) return v;
  else return P{} + v;
}

// Every generated kernel exists twice: the baseline copy, and (x86-64 with GCC) an FMA
// copy compiled for AVX2 + FMA, which ShRotation takes on CPUs that have them. The FMA
// copy fuses exactly the a * b + c that the source writes as madd<true>: the compiler's
// own contraction (off for the runtime) fuses differently in scalar and lane code, and
// apply_rgb must equal three apply() calls, and rotate_batch set() + apply(), bit for bit.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && \
    !defined(SHTOOL_NO_KERNEL_CLONES)
#define SHTOOL_FMA_KERNELS 1
#define SHTOOL_FMA_TARGET __attribute__((target("avx2,fma")))
#else
#define SHTOOL_FMA_KERNELS 0
#define SHTOOL_FMA_TARGET
#endif

// Whether this CPU runs the FMA copies (false where they are not built).
bool fma_kernels_supported();

// a * b + c, rounded twice (F = false) or once (F = true; only inlined into the FMA
// copies). a may be a scalar where b and c are lane vectors.
template <bool F, class A, class P>
SHTOOL_KERNEL_INLINE P madd(A a, P b, P c) {
  if constexpr (!F) {
    return a * b + c;
  } else {
#if SHTOOL_FMA_KERNELS
    if constexpr (std::is_same_v<P, float>) {
      return __builtin_fmaf(a, b, c);
    } else if constexpr (std::is_same_v<P, double>) {
      return __builtin_fma(a, b, c);
    } else {
      P av;
      if constexpr (std::is_same_v<A, P>) av = a;
      else av = splat<P>(a);
      // Lane by lane; the vectorizer turns it into one vector FMA.
      P r;
      constexpr int lanes = sizeof(P) / sizeof(c[0]);
      for (int i = 0; i < lanes; ++i) {
        if constexpr (sizeof(c[0]) == 4) r[i] = __builtin_fmaf(av[i], b[i], c[i]);
        else r[i] = __builtin_fma(av[i], b[i], c[i]);
      }
      return r;
    }
#else
    static_assert(!F, "no FMA kernels in this build");
    return c;
#endif
  }
}

// KernelState (what one rotation needs at apply time) is in shtool/rotation.h.

// in[v] / out[v]: vector v of N^2 coefficients. Transforms the first
// min(order, kKernelMaxOrder)^2 coefficients.
template <class T, int V>
using RotationKernel = void (*)(const KernelState<T>&, const T* const* in, T* const* out);

// Kernel covering bands 0..min(order, kKernelMaxOrder) - 1. Method: 0 = zxzxz (bands 1
// and 2 by the closed forms below), 1 / 15 / 2 = taylor1 / taylor1.5 / taylor2.
// fused: the FMA copy (fma_kernels_supported() must hold), else the baseline one.
template <class T, int V>
RotationKernel<T, V> rotation_kernel(int method, int order, bool fused);
// Kernel of band l alone (kKernelMaxOrder <= l <= kBandKernelMaxBand, else null): same
// methods, same arguments (it transforms coefficients l^2 .. l^2 + 2l).
template <class T, int V>
RotationKernel<T, V> band_kernel(int method, int l, bool fused);

// Lane vectors wider than 16 bytes (4 doubles) are native only with AVX; without it GCC
// splits them badly, so three double vectors run as a pair (2 doubles, one SSE2 register)
// plus a single one. Same operations per lane either way.
#if defined(__AVX__)
inline constexpr int kNativeLaneBytes = 32;
#else
inline constexpr int kNativeLaneBytes = 16;
#endif
template <class T>
struct Lanes<T, 2> {
  typedef T type __attribute__((vector_size(2 * sizeof(T))));
};

template <class T, class P>
SHTOOL_KERNEL_INLINE P load_lane_vector(const T* const* in, int i) {
  if constexpr (std::is_same_v<P, T>) return in[0][i];
  else if constexpr (sizeof(P) == 2 * sizeof(T)) return P{in[0][i], in[1][i]};
  else return P{in[0][i], in[1][i], in[2][i], T(0)};
}

template <class T, class P>
SHTOOL_KERNEL_INLINE void store_lane_vector(const P& y, int i, T* const* out) {
  if constexpr (std::is_same_v<P, T>) {
    out[0][i] = y;
  } else {
    out[0][i] = y[0];
    out[1][i] = y[1];
    if constexpr (sizeof(P) == 4 * sizeof(T)) out[2][i] = y[2];
  }
}

template <class T, class P>
SHTOOL_KERNEL_INLINE void load_lanes(const T* const* in, int first, int count, P* x) {
  for (int i = 0; i < count; ++i) x[i] = load_lane_vector<T, P>(in, first + i);
}

template <class T, class P>
SHTOOL_KERNEL_INLINE void store_lanes(const P* y, int first, int count, T* const* out) {
  for (int i = 0; i < count; ++i) store_lane_vector<T, P>(y[i], first + i, out);
}

// Runs bands(x, y) on coefficients first .. first + count - 1 of V vectors: one vector in
// place on the caller's arrays, three gathered into lane vectors (see Lanes).
template <class T, int V, int First, int Count, class F>
SHTOOL_KERNEL_INLINE void run_lanes(const T* const* in, T* const* out, F&& bands) {
  if constexpr (V == 1) {
    bands(in[0] + First, out[0] + First);
  } else if constexpr (4 * sizeof(T) <= kNativeLaneBytes) {
    Pack<T, 3> x[Count], y[Count];
    load_lanes<T>(in, First, Count, x);
    bands(static_cast<const Pack<T, 3>*>(x), y);
    store_lanes<T>(y, First, Count, out);
  } else {
    Pack<T, 2> x[Count], y[Count];
    load_lanes<T>(in, First, Count, x);
    bands(static_cast<const Pack<T, 2>*>(x), y);
    store_lanes<T>(y, First, Count, out);
    bands(in[2] + First, out[2] + First);
  }
}

// Batches of rotations (rotate_batch): one rotation per lane of a 16-byte SIMD vector
// (4 floats or 2 doubles), each lane with its own R and angle tables, running the same
// zxzxz band code as one rotation, so each lane's result is bit-identical to
// set() + apply() of its rotation.
template <class T>
inline constexpr int kBatchLanes = 16 / sizeof(T);
template <class T>
struct BatchLanes {
  typedef T type __attribute__((vector_size(16)));
};
template <class T>
using BatchPack = typename BatchLanes<T>::type;

// KernelState with a value per lane.
template <class T>
struct BatchState {
  const BatchPack<T>* r;
  const BatchPack<T>*ca, *sa, *cb, *sb, *cg, *sg;
  BatchPack<T> beta, half_beta2;
};

// in[k] / out[k], k < kBatchLanes<T>: the vectors of the lanes' rotations.
template <class T>
using BatchKernel = void (*)(const BatchState<T>&, const T* const* in, T* const* out);

// Kernel of a whole order (1..kKernelMaxOrder) for a batch, methods as in
// rotation_kernel; null above.
template <class T>
BatchKernel<T> batch_kernel(int method, int order, bool fused);
// Kernel of band l alone (kKernelMaxOrder <= l <= kBandKernelMaxBand) for a batch, where
// apply() runs the same generated band code (all but double zxzxz); null otherwise.
template <class T>
BatchKernel<T> batch_band_kernel(int method, int l, bool fused);

// x[i] = {src[0][i], .., src[B-1][i]} for i < count, B = kBatchLanes<T>: B x B transposes
// of register-sized loads (values never pass through memory one lane at a time, which
// would stall store forwarding). scatter_lanes is the inverse.
template <class T>
SHTOOL_KERNEL_INLINE void transpose_lanes(const BatchPack<T>* a, BatchPack<T>* x) {
  if constexpr (kBatchLanes<T> == 4) {
    const BatchPack<T> t0 = __builtin_shufflevector(a[0], a[1], 0, 4, 1, 5);
    const BatchPack<T> t1 = __builtin_shufflevector(a[2], a[3], 0, 4, 1, 5);
    const BatchPack<T> t2 = __builtin_shufflevector(a[0], a[1], 2, 6, 3, 7);
    const BatchPack<T> t3 = __builtin_shufflevector(a[2], a[3], 2, 6, 3, 7);
    x[0] = __builtin_shufflevector(t0, t1, 0, 1, 4, 5);
    x[1] = __builtin_shufflevector(t0, t1, 2, 3, 6, 7);
    x[2] = __builtin_shufflevector(t2, t3, 0, 1, 4, 5);
    x[3] = __builtin_shufflevector(t2, t3, 2, 3, 6, 7);
  } else {
    x[0] = __builtin_shufflevector(a[0], a[1], 0, 2);
    x[1] = __builtin_shufflevector(a[0], a[1], 1, 3);
  }
}

template <class T>
SHTOOL_KERNEL_INLINE BatchPack<T> lanes_at(const T* const* src, int i) {
  if constexpr (kBatchLanes<T> == 4) return BatchPack<T>{src[0][i], src[1][i], src[2][i], src[3][i]};
  else return BatchPack<T>{src[0][i], src[1][i]};
}

template <class T>
SHTOOL_KERNEL_INLINE void gather_lanes(const T* const* src, int count, BatchPack<T>* x) {
  constexpr int B = kBatchLanes<T>;
  int i = 0;
  for (; i + B <= count; i += B) {
    BatchPack<T> a[B];
    for (int k = 0; k < B; ++k) __builtin_memcpy(&a[k], src[k] + i, sizeof a[k]);
    transpose_lanes<T>(a, x + i);
  }
  for (; i < count; ++i) x[i] = lanes_at<T>(src, i);
}

template <class T>
SHTOOL_KERNEL_INLINE void scatter_lanes(const BatchPack<T>* y, int count, T* const* dst) {
  constexpr int B = kBatchLanes<T>;
  int i = 0;
  for (; i + B <= count; i += B) {
    BatchPack<T> a[B];
    transpose_lanes<T>(y + i, a);
    for (int k = 0; k < B; ++k) __builtin_memcpy(dst[k] + i, &a[k], sizeof a[k]);
  }
  for (; i < count; ++i)
    for (int k = 0; k < B; ++k) dst[k][i] = y[i][k];
}

// Runs bands(x, y) on coefficients First .. First + Count - 1 of kBatchLanes<T> vectors
// gathered into lanes.
template <class T, int First, int Count, class F>
SHTOOL_KERNEL_INLINE void run_batch_lanes(const T* const* in, T* const* out, F&& bands) {
  constexpr int B = kBatchLanes<T>;
  const T* src[B];
  T* dst[B];
  for (int k = 0; k < B; ++k) {
    src[k] = in[k] + First;
    dst[k] = out[k] + First;
  }
  BatchPack<T> x[Count], y[Count];
  gather_lanes<T>(src, Count, x);
  bands(static_cast<const BatchPack<T>*>(x), y);
  scatter_lanes<T>(y, Count, dst);
}

// Band 1 is detail::band1_closed (shtool/rotation.h); like band 2 below it reads R
// column-major, r[i + 3 j] = R(i, j).

// Band 2 as a quadratic form: on the unit sphere y_2^m(w) = w^T Q_m w with Q_m traceless
// symmetric, so f = sum f_m y_2^m is w^T A w with A = sum f_m Q_m, and
// g(w) = f(R^T w) = w^T (R A R^T) w: rotating band 2 is rotating a 3x3 matrix, quadratic
// in R's entries, with no Euler angles. With c = sqrt(15 / pi) / 2 and the functions
// y_2^-2 = c xy, y_2^-1 = -c yz, y_2^0 = (c / sqrt3)(3 z^2 - 1) / 2, y_2^1 = -c xz,
// y_2^2 = (c / 2)(x^2 - y^2), A scaled by 2 / c is
//   [[f2 - k f0', f-2, -f1], [f-2, -f2 - k f0', -f-1], [-f1, -f-1, 2 k f0']], k = 1 / sqrt3,
// and projecting B = R A R^T back (integral of (w^T Q w)(w^T B w) = (8 pi / 15) tr(QB)
// for traceless Q, B) gives g-2 = B01, g-1 = -B12, g0 = (sqrt3 / 2) B22, g1 = -B02,
// g2 = (B00 - B11) / 2.
template <bool F, class T, class P, class R = T>
SHTOOL_KERNEL_INLINE void band2_closed(const R* __restrict r, const P* __restrict x, P* __restrict y) {
  const T k = T(0.57735026918962576451);        // 1 / sqrt3
  const T h3 = T(0.86602540378443864676);       // sqrt3 / 2
  const P kf0 = k * x[2];
  const P a00 = x[4] - kf0, a11 = -x[4] - kf0, a22 = kf0 + kf0;
  const P a01 = x[0], a12 = -x[1], a02 = -x[3];
  // u0 v0 + u1 v1 + u2 v2, left to right.
  auto dot3 = [](auto u0, auto v0, auto u1, auto v1, auto u2, auto v2) {
    return madd<F>(u2, v2, madd<F>(u1, v1, u0 * v0));
  };
  // C = R A (A symmetric), then the needed entries of B = C R^T.
  const P c00 = dot3(r[0], a00, r[3], a01, r[6], a02);
  const P c01 = dot3(r[0], a01, r[3], a11, r[6], a12);
  const P c02 = dot3(r[0], a02, r[3], a12, r[6], a22);
  const P c10 = dot3(r[1], a00, r[4], a01, r[7], a02);
  const P c11 = dot3(r[1], a01, r[4], a11, r[7], a12);
  const P c12 = dot3(r[1], a02, r[4], a12, r[7], a22);
  const P c20 = dot3(r[2], a00, r[5], a01, r[8], a02);
  const P c21 = dot3(r[2], a01, r[5], a11, r[8], a12);
  const P c22 = dot3(r[2], a02, r[5], a12, r[8], a22);
  const P b00 = dot3(r[0], c00, r[3], c01, r[6], c02);
  const P b11 = dot3(r[1], c10, r[4], c11, r[7], c12);
  const P b22 = dot3(r[2], c20, r[5], c21, r[8], c22);
  const P b01 = dot3(r[1], c00, r[4], c01, r[7], c02);
  const P b02 = dot3(r[2], c00, r[5], c01, r[8], c02);
  const P b12 = dot3(r[2], c10, r[5], c11, r[8], c12);
  y[0] = b01;
  y[1] = -b12;
  y[2] = h3 * b22;
  y[3] = -b02;
  y[4] = T(0.5) * (b00 - b11);
}

#pragma GCC diagnostic pop

}  // namespace shtool::detail
