// Internal to the runtime: fixed-order SH rotation kernels. The per-band arithmetic of
// the zxzxz and Taylor rotations for small bands is generated, with X90, D1 and D2 as
// literal constants and every loop unrolled, into rotation_kernels_generated.inc by
// `shtool gen-tensors --what rotation-kernels --out src/runtime/kernels` (src/offline/tensors/
// rotation_kernels_gen.cpp); tests/test_rotation_kernels.cpp regenerates it and compares
// the bytes, so the committed source cannot drift from its generator. Bands 1..3 have
// closed forms in R: band 1 (every order) in shtool/rotation.h, bands 2 and 3 here (used
// at orders up to detail::kClosedMaxOrder only, where they spare the Euler angles; from
// the next order on the angles are needed anyway and the zxzxz bands are cheaper).
#pragma once

#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

// Lanes of one rotation: V = 1 is the plain type; V = 3 (an RGB light, its channels
// interleaved) runs the three channels in the lanes of one 4-wide vector (GCC/Clang
// vector extension; for float one SSE register), so the three cost one pass over the
// code and its constants. Lane arithmetic is the same IEEE arithmetic as the scalar code.
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
// three interleaved channels must equal apply() of each, and rotate_batch set() + apply(),
// bit for bit.
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

// Four floats in the lanes of one SSE register: the generated zxzxz bands run the pairs
// of a z-rotation of one float vector in them (rotation_kernels_gen.cpp, z_rotation).
using Lanes4 = Pack<float, 3>;
// Entries p[0..3] of a cos / sin table (ShRotation pads its tables for the last group).
SHTOOL_KERNEL_INLINE Lanes4 table_lanes(const float* p) {
  Lanes4 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

// The pairs (m, -m), m = m0 .. m0 + Count - 1, of a band in lanes, Count = 2..4, lanes
// past Count zero: `plus` loads p[0 .. Count - 1] (the +m side, in order), `minus` loads
// p[-(Count - 1) .. 0] reversed (the -m side, where m runs downwards in memory). One
// load of Count entries (and one shuffle), where lane-by-lane inserts cost a shuffle
// each; and nothing outside the band's entries is read.
template <int Count>
SHTOOL_KERNEL_INLINE Lanes4 pairs_plus(const float* p) {
#if defined(__SSE2__)
  // A memcpy of 8 or 12 bytes into a vector goes through the stack in GCC 12, and the
  // vector load then waits for the narrower stores: spelled out instead.
  if constexpr (Count == 4) return reinterpret_cast<Lanes4>(_mm_loadu_ps(p));
  // p[0], p[1], 0, 0 (through __m128i, which may alias the floats)
  const __m128 low = _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
  if constexpr (Count == 2) return reinterpret_cast<Lanes4>(low);
  else return reinterpret_cast<Lanes4>(_mm_movelh_ps(low, _mm_load_ss(p + 2)));
#else
  Lanes4 v{};
  __builtin_memcpy(&v, p, Count * sizeof(float));
  return v;
#endif
}
// Lanes 0 .. Count - 1 of v in reverse order, the lanes past Count left where they are:
// the -m side of a band runs downwards in memory.
template <int Count>
SHTOOL_KERNEL_INLINE Lanes4 reverse_pairs(Lanes4 v) {
  if constexpr (Count == 4) return __builtin_shufflevector(v, v, 3, 2, 1, 0);
  else if constexpr (Count == 3) return __builtin_shufflevector(v, v, 2, 1, 0, 3);
  else return __builtin_shufflevector(v, v, 1, 0, 2, 3);
}
template <int Count>
SHTOOL_KERNEL_INLINE Lanes4 pairs_minus(const float* p) {
  return reverse_pairs<Count>(pairs_plus<Count>(p - (Count - 1)));
}
// The stores matching pairs_plus / pairs_minus: lanes 0 .. Count - 1 of v to p[0 ..] or
// to p[0], p[-1], ...: one store (and one shuffle) where lane-by-lane extracts cost a
// shuffle and a store each.
template <int Count>
SHTOOL_KERNEL_INLINE void store_pairs_plus(float* p, Lanes4 v) {
#if defined(__SSE2__)
  const __m128 x = reinterpret_cast<__m128>(v);
  if constexpr (Count == 4) {
    _mm_storeu_ps(p, x);
  } else {
    _mm_storel_epi64(reinterpret_cast<__m128i*>(p), _mm_castps_si128(x));
    if constexpr (Count == 3) _mm_store_ss(p + 2, _mm_movehl_ps(x, x));
  }
#else
  __builtin_memcpy(p, &v, Count * sizeof(float));
#endif
}
template <int Count>
SHTOOL_KERNEL_INLINE void store_pairs_minus(float* p, Lanes4 v) {
  store_pairs_plus<Count>(p - (Count - 1), reverse_pairs<Count>(v));
}

// KernelState (what one rotation needs at apply time) is in shtool/rotation.h.

// in[0] / out[0]: V = 1 one vector, V = 3 three channels interleaved (coefficient i of
// channel k at [3 i + k]). Transforms the first min(order, kKernelMaxOrder)^2
// coefficients.
template <class T, int V>
using RotationKernel = void (*)(const KernelState<T>&, const T* const* in, T* const* out);

// Kernel covering bands 0..min(order, kKernelMaxOrder) - 1. Method: 0 = zxzxz (bands 1
// and 2 by the closed forms below), 1 / 15 / 2 = taylor1 / taylor1.5 / taylor2.
// fused: the FMA copy (fma_kernels_supported() must hold), else the baseline one.
template <class T, int V>
RotationKernel<T, V> rotation_kernel(int method, int order, bool fused);
// Kernel of band l alone (kKernelMaxOrder <= l <= kBandKernelMaxBand, else null): same
// methods, same arguments, except that in[0] and out[0] point at coefficient l^2 (it
// transforms coefficients l^2 .. l^2 + 2l).
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

// Three lanes interleaved (an RGB light as the engine stores colour, coefficient i of
// lane k at p[3 i + k]): the three values of one coefficient are contiguous, so a lane
// vector moves in one load or store. A 4-wide vector reads and writes one value past
// them (the next coefficient's lane 0: lanes never mix, and the stores go in order, so
// the next coefficient's store overwrites it); the last coefficient of a range moves
// three values only, so nothing outside the arrays is read or written.
template <class T, class P, bool Last>
SHTOOL_KERNEL_INLINE P load_interleaved(const T* p) {
  if constexpr (sizeof(P) == 2 * sizeof(T) || !Last) {  // lanes 0, 1 (a pair) or 0..3
    P v;
    __builtin_memcpy(&v, p, sizeof v);
    return v;
  } else if constexpr (std::is_same_v<T, float>) {
    return pairs_plus<3>(p);
  } else {
    return P{p[0], p[1], p[2], T(0)};
  }
}
template <class T, class P, bool Last>
SHTOOL_KERNEL_INLINE void store_interleaved(T* p, const P& v) {
  if constexpr (sizeof(P) == 2 * sizeof(T) || !Last) {
    __builtin_memcpy(p, &v, sizeof v);
  } else if constexpr (std::is_same_v<T, float>) {
    store_pairs_plus<3>(p, v);
  } else {
    p[0] = v[0];
    p[1] = v[1];
    p[2] = v[2];
  }
}

// x[j] = coefficient j of V lanes: V = 1 in[j]; V = 3 interleaved, as lane vectors P, or
// lane `lane` alone when P is T (three doubles without AVX, see Lanes).
template <int V, class T, class P>
SHTOOL_KERNEL_INLINE void load_lanes(const T* __restrict in, int count, P* __restrict x, int lane = 0) {
  if constexpr (V == 1) {
    for (int j = 0; j < count; ++j) x[j] = in[j];
  } else if constexpr (std::is_same_v<P, T>) {
    for (int j = 0; j < count; ++j) x[j] = in[3 * j + lane];
  } else {
    for (int j = 0; j + 1 < count; ++j) x[j] = load_interleaved<T, P, false>(in + 3 * j);
    x[count - 1] = load_interleaved<T, P, true>(in + 3 * (count - 1));
  }
}
template <int V, class T, class P>
SHTOOL_KERNEL_INLINE void store_lanes(const P* __restrict y, int count, T* __restrict out, int lane = 0) {
  if constexpr (V == 1) {
    for (int j = 0; j < count; ++j) out[j] = y[j];
  } else if constexpr (std::is_same_v<P, T>) {
    for (int j = 0; j < count; ++j) out[3 * j + lane] = y[j];
  } else {
    for (int j = 0; j + 1 < count; ++j) store_interleaved<T, P, false>(out + 3 * j, y[j]);
    store_interleaved<T, P, true>(out + 3 * (count - 1), y[count - 1]);
  }
}

// Runs bands(x, y) on coefficients First .. First + Count - 1 of V lanes; in[0] and
// out[0] point at coefficient First. One vector works in place on the caller's arrays;
// three (interleaved) are loaded into lane vectors, or, for doubles without AVX, lanes
// 0 and 1 into pairs (one SSE2 register) and lane 2 alone (see Lanes). Avx: the caller
// is compiled for AVX (the FMA copies, SHTOOL_FMA_TARGET), where four doubles are one
// register whatever the build's flags.
template <class T, int V, int First, int Count, bool Avx = false, class F>
SHTOOL_KERNEL_INLINE void run_lanes(const T* const* in, T* const* out, F&& bands) {
  if constexpr (V == 1) {
    bands(in[0], out[0]);
  } else if constexpr (4 * sizeof(T) <= (Avx ? 32 : kNativeLaneBytes)) {
    Pack<T, 3> x[Count], y[Count];
    load_lanes<3>(in[0], Count, x);
    bands(static_cast<const Pack<T, 3>*>(x), y);
    store_lanes<3>(y, Count, out[0]);
  } else {
    Pack<T, 2> x[Count], y[Count];
    load_lanes<3>(in[0], Count, x);
    bands(static_cast<const Pack<T, 2>*>(x), y);
    store_lanes<3>(y, Count, out[0]);
    T x2[Count], y2[Count];
    load_lanes<3>(in[0], Count, x2, 2);
    bands(static_cast<const T*>(x2), y2);
    store_lanes<3>(static_cast<const T*>(y2), Count, out[0], 2);
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

// sum_a u_a v_a for a = 0, 1, 2, left to right: the contraction the closed forms of
// bands 2 and 3 below are made of. u_a and v_a are scalars or lane vectors.
template <bool F, class U, class V>
SHTOOL_KERNEL_INLINE auto dot3(U u0, V v0, U u1, V v1, U u2, V v2) {
  return madd<F>(u2, v2, madd<F>(u1, v1, u0 * v0));
}

// The maps in and out of band2_closed (below): the matrix A of the coefficients x, and
// the coefficients y of the rotated matrix B from its entries.
template <class P>
struct Band2Matrix {
  P a00, a11, a22, a01, a12, a02;
};
template <class T, class P>
SHTOOL_KERNEL_INLINE Band2Matrix<P> band2_matrix(const P* __restrict x) {
  const T k = T(0.57735026918962576451);  // 1 / sqrt3
  const P kf0 = k * x[2];
  return {x[4] - kf0, -x[4] - kf0, kf0 + kf0, x[0], -x[1], -x[3]};
}
template <class T, class P>
SHTOOL_KERNEL_INLINE void band2_coefficients(P b00, P b11, P b22, P b01, P b02, P b12, P* __restrict y) {
  const T h3 = T(0.86602540378443864676);  // sqrt3 / 2 (also in band2_closed_lanes)
  y[0] = b01;
  y[1] = -b12;
  y[2] = h3 * b22;
  y[3] = -b02;
  y[4] = T(0.5) * (b00 - b11);
}

// The maps in and out of band3_closed (below): the 10 entries of the tensor A of the
// coefficients x, and the coefficients y from the 7 entries of the rotated tensor B with
// at most one index z.
template <class P>
struct Band3Tensor {
  P axxx, axxy, axxz, axyy, axyz, axzz, ayyy, ayyz, ayzz, azzz;
};
template <class T, class P>
SHTOOL_KERNEL_INLINE Band3Tensor<P> band3_tensor(const P* __restrict x) {
  const T k3 = T(0.59004358992664351035), k2 = T(2.8906114426405540554);
  const T k1 = T(0.45704579946446573616), k0 = T(0.37317633259011539141);
  // Scaled coefficients; then the entries of A (A_abc = coefficient of the monomial over
  // its multiplicity 3!/(i! j! k!)).
  const P fm3 = k3 * x[0], fm2 = (k2 / 6) * x[1], fm1 = k1 * x[2], f0 = k0 * x[3];
  const P f1 = k1 * x[4], f2 = (k2 / 6) * x[5], f3 = k3 * x[6];
  Band3Tensor<P> a;
  a.axxx = f1 - f3;
  a.axxy = (fm1 - T(3) * fm3) * T(1.0 / 3);
  a.axyy = (f1 + T(3) * f3) * T(1.0 / 3);
  a.ayyy = fm1 + fm3;
  a.axxz = f2 - f0;  // ((k2 / 2) x[5] - 3 k0 x[3]) / 3
  a.ayyz = -f2 - f0;
  a.axyz = fm2;
  a.axzz = T(-4.0 / 3) * f1;
  a.ayzz = T(-4.0 / 3) * fm1;
  a.azzz = f0 + f0;
  return a;
}
template <bool F, class T, class P>
SHTOOL_KERNEL_INLINE void band3_coefficients(P bxxx, P bxxy, P bxyy, P byyy, P bxxz, P bxyz, P byyz,
                                             P* __restrict y) {
  const T i3 = T(1) / (4 * 0.59004358992664351035), i1 = T(3) / (4 * 0.45704579946446573616);
  const T i2 = T(6) / 2.8906114426405540554, i0 = T(-1) / (2 * 0.37317633259011539141);
  y[0] = i3 * madd<F>(T(-3), bxxy, byyy);
  y[1] = i2 * bxyz;
  y[2] = i1 * (bxxy + byyy);
  y[3] = i0 * (bxxz + byyz);
  y[4] = i1 * (bxxx + bxyy);
  y[5] = (i2 / 2) * (bxxz - byyz);
  y[6] = i3 * madd<F>(T(3), bxyy, -bxxx);
}

// Bands 2 and 3 of one float vector run their contractions with R on 4-wide lane vectors
// (lane 3 unused): each lane takes the products and sums of one entry of the scalar code
// (band2_closed, band3_closed below) in the same order, so the results have its bits,
// which the three-channel apply and rotate_batch compute lane by lane. Against the scalar form, 3
// operations where it takes 9 per group of three entries, plus lane broadcasts.
template <int L>
SHTOOL_KERNEL_INLINE Lanes4 lane_splat(Lanes4 v) {
  return __builtin_shufflevector(v, v, L, L, L, L);
}

// The columns of R (r column-major) in lanes 0..2, read as set() stores R (two 4-float
// stores and one float): a load straddling two stores would wait for them to reach the
// cache instead of taking their values.
struct RColumnLanes {
  Lanes4 col[3];
};
SHTOOL_KERNEL_INLINE RColumnLanes r_column_lanes(const float* __restrict r) {
  const Lanes4 a = table_lanes(r), b = table_lanes(r + 4);  // r0..r3, r4..r7
  const Lanes4 c = {r[8], 0.0f, 0.0f, 0.0f};
  return {{a, __builtin_shufflevector(a, b, 3, 4, 5, 6), __builtin_shufflevector(b, c, 2, 3, 4, 5)}};
}

// Rotations whose table, input and output are all float take the lane-parallel forms below.
template <class T, class P, class R>
inline constexpr bool kAllFloat = std::is_same_v<T, float> && std::is_same_v<P, float> && std::is_same_v<R, float>;

// band2_closed for one float vector. Lanes j of C_i = R_i. A are c_ij; lanes j of
// B_0 = sum_b C_0b R_.b are b_0j; and (b11, b12, b22) come from one more vector whose
// lanes pair C_1 and C_2 with rows 1, 2 of R.
template <bool F>
SHTOOL_KERNEL_INLINE void band2_closed_lanes(const float* __restrict r, const float* __restrict x,
                                             float* __restrict y) {
  const Band2Matrix<float> m = band2_matrix<float, float>(x);
  const Lanes4 a0 = {m.a00, m.a01, m.a02, 0.0f}, a1 = {m.a01, m.a11, m.a12, 0.0f};
  const Lanes4 a2 = {m.a02, m.a12, m.a22, 0.0f};
  const Lanes4 c0 = dot3<F>(r[0], a0, r[3], a1, r[6], a2);
  const Lanes4 c1 = dot3<F>(r[1], a0, r[4], a1, r[7], a2);
  const Lanes4 c2 = dot3<F>(r[2], a0, r[5], a1, r[8], a2);
  const RColumnLanes rc = r_column_lanes(r);
  const Lanes4 b0 = dot3<F>(lane_splat<0>(c0), rc.col[0], lane_splat<1>(c0), rc.col[1], lane_splat<2>(c0), rc.col[2]);
  // Lanes (b11, b12, b22): entry b of C_1, C_1, C_2 against entries 1, 2, 2 of column b.
  auto rows12 = [&](int b) { return __builtin_shufflevector(rc.col[b], rc.col[b], 1, 2, 2, 2); };
  const Lanes4 b1 = dot3<F>(__builtin_shufflevector(c1, c2, 0, 0, 4, 4), rows12(0),
                            __builtin_shufflevector(c1, c2, 1, 1, 5, 5), rows12(1),
                            __builtin_shufflevector(c1, c2, 2, 2, 6, 6), rows12(2));
  // band2_coefficients in lanes: (b01, -b12, h3 b22, -b02) in one store (products by 1
  // and -1 are exact), where five scalar extracts and stores cost 1 ns a rotation at N = 3
  // and 4.
  const float h3 = 0.86602540378443864676f;
  const Lanes4 out = __builtin_shufflevector(b0, b1, 1, 5, 6, 2) * Lanes4{1.0f, -1.0f, h3, -1.0f};
  __builtin_memcpy(y, &out, sizeof out);
  y[4] = 0.5f * (b0[0] - b1[0]);
}

// band3_closed for one float vector: C_i,b. = sum_a R_ia A_ab. (lanes c), D_ij. =
// sum_b R_jb C_i,b. (lanes c), B_ij. = sum_c D_ij,c R_.c (lanes k).
template <bool F>
SHTOOL_KERNEL_INLINE void band3_closed_lanes(const float* __restrict r, const float* __restrict x,
                                             float* __restrict y) {
  const Band3Tensor<float> a = band3_tensor<float, float>(x);
  const Lanes4 axx = {a.axxx, a.axxy, a.axxz, 0.0f}, axy = {a.axxy, a.axyy, a.axyz, 0.0f};
  const Lanes4 axz = {a.axxz, a.axyz, a.axzz, 0.0f}, ayy = {a.axyy, a.ayyy, a.ayyz, 0.0f};
  const Lanes4 ayz = {a.axyz, a.ayyz, a.ayzz, 0.0f}, azz = {a.axzz, a.ayzz, a.azzz, 0.0f};
  const Lanes4 cxx = dot3<F>(r[0], axx, r[3], axy, r[6], axz);
  const Lanes4 cxy = dot3<F>(r[0], axy, r[3], ayy, r[6], ayz);
  const Lanes4 cxz = dot3<F>(r[0], axz, r[3], ayz, r[6], azz);
  const Lanes4 cyx = dot3<F>(r[1], axx, r[4], axy, r[7], axz);
  const Lanes4 cyy = dot3<F>(r[1], axy, r[4], ayy, r[7], ayz);
  const Lanes4 cyz = dot3<F>(r[1], axz, r[4], ayz, r[7], azz);
  const Lanes4 dxx = dot3<F>(r[0], cxx, r[3], cxy, r[6], cxz);
  const Lanes4 dxy = dot3<F>(r[1], cxx, r[4], cxy, r[7], cxz);
  const Lanes4 dyy = dot3<F>(r[1], cyx, r[4], cyy, r[7], cyz);
  const RColumnLanes rc = r_column_lanes(r);
  auto contract = [&](Lanes4 d) {
    return dot3<F>(lane_splat<0>(d), rc.col[0], lane_splat<1>(d), rc.col[1], lane_splat<2>(d), rc.col[2]);
  };
  const Lanes4 bxx = contract(dxx), bxy = contract(dxy), byy = contract(dyy);
  band3_coefficients<F, float, float>(bxx[0], bxx[1], bxy[1], byy[1], bxx[2], bxy[2], byy[2], y);
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
  if constexpr (kAllFloat<T, P, R>) return band2_closed_lanes<F>(r, x, y);
  const Band2Matrix<P> m = band2_matrix<T, P>(x);
  const P a00 = m.a00, a11 = m.a11, a22 = m.a22, a01 = m.a01, a12 = m.a12, a02 = m.a02;
  // C = R A (A symmetric), then the needed entries of B = C R^T.
  const P c00 = dot3<F>(r[0], a00, r[3], a01, r[6], a02);
  const P c01 = dot3<F>(r[0], a01, r[3], a11, r[6], a12);
  const P c02 = dot3<F>(r[0], a02, r[3], a12, r[6], a22);
  const P c10 = dot3<F>(r[1], a00, r[4], a01, r[7], a02);
  const P c11 = dot3<F>(r[1], a01, r[4], a11, r[7], a12);
  const P c12 = dot3<F>(r[1], a02, r[4], a12, r[7], a22);
  const P c20 = dot3<F>(r[2], a00, r[5], a01, r[8], a02);
  const P c21 = dot3<F>(r[2], a01, r[5], a11, r[8], a12);
  const P c22 = dot3<F>(r[2], a02, r[5], a12, r[8], a22);
  const P b00 = dot3<F>(r[0], c00, r[3], c01, r[6], c02);
  const P b11 = dot3<F>(r[1], c10, r[4], c11, r[7], c12);
  const P b22 = dot3<F>(r[2], c20, r[5], c21, r[8], c22);
  const P b01 = dot3<F>(r[1], c00, r[4], c01, r[7], c02);
  const P b02 = dot3<F>(r[2], c00, r[5], c01, r[8], c02);
  const P b12 = dot3<F>(r[2], c10, r[5], c11, r[8], c12);
  band2_coefficients<T, P>(b00, b11, b22, b01, b02, b12, y);
}

// Band 3 as a cubic form, as band 2 above is a quadratic one: a band-3 function is the
// harmonic cubic p(w) = A[w, w, w] with A symmetric (10 entries), and g(w) = p(R^T w) has
// the tensor B_ijk = sum_abc A_abc R_ia R_jb R_kc, cubic in R's entries, with no Euler
// angles. A harmonic cubic is fixed by its monomials of degree <= 1 in z (the Laplace
// equation gives the rest), so only the 7 entries of B with at most one index z are
// formed, by three contractions with rows of R: C = R_x. A and R_y. A (12 dot products),
// D_ij = R_j . C_i for ij = xx, xy, yy (9), B_ijk = R_k . D_ij (7): 84 multiplications,
// and 19 more for the maps in and out (docs/rotation.md).
// With the Condon-Shortley phase (y_3^m for odd m negated) and k3 = sqrt(35 / (2 pi)) / 4,
// k2 = sqrt(105 / pi) / 2, k1 = sqrt(21 / (2 pi)) / 4, k0 = sqrt(7 / pi) / 4:
//   y_3^-3 = -k3 y (3x^2 - y^2), y_3^-2 = k2 xyz, y_3^-1 = -k1 y (4z^2 - x^2 - y^2),
//   y_3^0 = k0 z (2z^2 - 3x^2 - 3y^2), y_3^1 = -k1 x (4z^2 - x^2 - y^2),
//   y_3^2 = (k2 / 2) z (x^2 - y^2), y_3^3 = -k3 x (x^2 - 3y^2),
// and solving those 7 monomials of g for its coefficients gives
//   g-3 = (B_yyy - 3 B_xxy) / (4 k3), g-1 = 3 (B_xxy + B_yyy) / (4 k1), g-2 = 6 B_xyz / k2,
//   g0 = -(B_xxz + B_yyz) / (2 k0), g2 = 3 (B_xxz - B_yyz) / k2,
//   g1 = 3 (B_xxx + B_xyy) / (4 k1), g3 = (3 B_xyy - B_xxx) / (4 k3).
template <bool F, class T, class P, class R = T>
SHTOOL_KERNEL_INLINE void band3_closed(const R* __restrict r, const P* __restrict x, P* __restrict y) {
  if constexpr (kAllFloat<T, P, R>) return band3_closed_lanes<F>(r, x, y);
  const Band3Tensor<P> a = band3_tensor<T, P>(x);
  const P axxx = a.axxx, axxy = a.axxy, axxz = a.axxz, axyy = a.axyy, axyz = a.axyz;
  const P axzz = a.axzz, ayyy = a.ayyy, ayyz = a.ayyz, ayzz = a.ayzz, azzz = a.azzz;
  // C_i,bc = sum_a R_ia A_abc for i = x, y.
  const P cxxx = dot3<F>(r[0], axxx, r[3], axxy, r[6], axxz);
  const P cxxy = dot3<F>(r[0], axxy, r[3], axyy, r[6], axyz);
  const P cxxz = dot3<F>(r[0], axxz, r[3], axyz, r[6], axzz);
  const P cxyy = dot3<F>(r[0], axyy, r[3], ayyy, r[6], ayyz);
  const P cxyz = dot3<F>(r[0], axyz, r[3], ayyz, r[6], ayzz);
  const P cxzz = dot3<F>(r[0], axzz, r[3], ayzz, r[6], azzz);
  const P cyxx = dot3<F>(r[1], axxx, r[4], axxy, r[7], axxz);
  const P cyxy = dot3<F>(r[1], axxy, r[4], axyy, r[7], axyz);
  const P cyxz = dot3<F>(r[1], axxz, r[4], axyz, r[7], axzz);
  const P cyyy = dot3<F>(r[1], axyy, r[4], ayyy, r[7], ayyz);
  const P cyyz = dot3<F>(r[1], axyz, r[4], ayyz, r[7], ayzz);
  const P cyzz = dot3<F>(r[1], axzz, r[4], ayzz, r[7], azzz);
  // D_ij,c = sum_b R_jb C_i,bc.
  const P dxxx = dot3<F>(r[0], cxxx, r[3], cxxy, r[6], cxxz);
  const P dxxy = dot3<F>(r[0], cxxy, r[3], cxyy, r[6], cxyz);
  const P dxxz = dot3<F>(r[0], cxxz, r[3], cxyz, r[6], cxzz);
  const P dxyx = dot3<F>(r[1], cxxx, r[4], cxxy, r[7], cxxz);
  const P dxyy = dot3<F>(r[1], cxxy, r[4], cxyy, r[7], cxyz);
  const P dxyz = dot3<F>(r[1], cxxz, r[4], cxyz, r[7], cxzz);
  const P dyyx = dot3<F>(r[1], cyxx, r[4], cyxy, r[7], cyxz);
  const P dyyy = dot3<F>(r[1], cyxy, r[4], cyyy, r[7], cyyz);
  const P dyyz = dot3<F>(r[1], cyxz, r[4], cyyz, r[7], cyzz);
  // B_ijk = sum_c R_kc D_ij,c.
  const P bxxx = dot3<F>(r[0], dxxx, r[3], dxxy, r[6], dxxz);
  const P bxxy = dot3<F>(r[1], dxxx, r[4], dxxy, r[7], dxxz);
  const P bxyy = dot3<F>(r[1], dxyx, r[4], dxyy, r[7], dxyz);
  const P byyy = dot3<F>(r[1], dyyx, r[4], dyyy, r[7], dyyz);
  const P bxxz = dot3<F>(r[2], dxxx, r[5], dxxy, r[8], dxxz);
  const P bxyz = dot3<F>(r[2], dxyx, r[5], dxyy, r[8], dxyz);
  const P byyz = dot3<F>(r[2], dyyx, r[5], dyyy, r[8], dyyz);
  band3_coefficients<F, T, P>(bxxx, bxxy, bxyy, byyy, bxxz, bxyz, byyz, y);
}

#pragma GCC diagnostic pop

}  // namespace shtool::detail
