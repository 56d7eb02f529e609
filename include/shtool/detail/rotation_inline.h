// Private to ShRotation (shtool/rotation.h): what its inline set() and apply() reach
// into, here so that rotation.h opens with the API. Not an interface: it changes with
// the kernels (src/runtime/kernels/rotation_kernels.h).
#pragma once

#include <type_traits>

#include "shtool/euler.h"

namespace shtool {

namespace detail {
// What one rotation needs at apply time (set() fills it): R column-major, cos(m x) and
// sin(m x) of the zyz angles for m < order, and the Taylor tilt b and b^2 / 2. Read
// by the generated kernels (src/runtime/kernels/rotation_kernels.h); here because
// apply() calls the kernel of a whole rotation inline.
template <class T>
struct BatchState;  // src/runtime/kernels/rotation_kernels.h
// Whether new ShRotation objects take the FMA copies of the kernels: true on CPUs with
// AVX2 and FMA (x86-64 GCC builds), unless use_fma_kernels(false) was called (tests of
// the baseline copies). Not thread-safe against concurrent construction.
bool fma_kernels_enabled();
void use_fma_kernels(bool on);

// Orders up to this one rotate by closed forms in R alone (bands 1..3, no Euler angles):
// zxzxz and the automatic choice there cost a copy of R in set().
inline constexpr int kClosedMaxOrder = 4;

template <class T>
struct KernelState {
  const T* r;
  const T *ca, *sa, *cb, *sb, *cg, *sg;
  T beta, half_beta2;
};

// Band 1 of M(R) for R stored column-major (r[i + 3 j] = R(i, j), Eigen's layout). With
// y_1^-1 = -c y, y_1^0 = c z, y_1^1 = -c x, band 1 is R in (y, z, x) order with the
// entries that mix z with x or y negated (docs/rotation.md). P is T or a vector of T
// (lanes, src/runtime/kernels/rotation_kernels.h); R is T, or P when every lane has its own
// rotation (rotate_batch). Here because ShRotation::apply runs it inline at order 2.
template <class T, class P, class R = T>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void band1_closed(const R* __restrict r, const P* __restrict x, P* __restrict y) {
  // With the band as a plain vector v = (vx, vy, vz) = (-x2, -x0, x1) (times c), the
  // rows are y0 = -(R1 . v), y1 = R2 . v, y2 = -(R0 . v) (R_i: row i). The signs are
  // folded into the order of operations: rounding is symmetric, so -(-(a + b) + c) is
  // (a + b) - c to the bit (up to the sign of a zero), with no negation instructions.
  y[0] = (r[1] * x[2] + r[4] * x[0]) - r[7] * x[1];
  y[1] = r[8] * x[1] - (r[2] * x[2] + r[5] * x[0]);
  y[2] = (r[0] * x[2] + r[3] * x[0]) - r[6] * x[1];
}

// A whole order-2 rotation, out = M(R) in (4 coefficients), R column-major: what apply,
// the three-channel apply and rotate_batch all run there, so they agree bit for bit. The scalar form
// is the reference of the SSE2 one, which gives its bits (tested).
template <class T>
inline void order2_scalar(const T* __restrict r, const T* __restrict in, T* __restrict out) {
  out[0] = in[0];
  band1_closed<T, T>(r, in + 1, out + 1);
}

#if defined(__SSE2__)
// Band 1 in lanes 1..3 (lane 0 carries in[0]) by band1_closed's products and sums in
// the same order; one 4-float load of the input and one store of the output, where the
// scalar code moves 12 floats and stores 4 (docs/rotation.md, "Operation counts").
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void order2_sse2(const float* __restrict r, const float* __restrict in, float* __restrict out) {
  const __m128 v = _mm_loadu_ps(in);
  // R read as set() writes it (two 4-float stores and one float): a load straddling two
  // stores waits for them to reach the cache instead of taking their values.
  const __m128 a = _mm_loadu_ps(r);      // r0 r1 r2 r3
  const __m128 b = _mm_loadu_ps(r + 4);  // r4 r5 r6 r7
  const __m128 c = _mm_load_ss(r + 8);   // r8
  // Lanes 1..3: the rows y0, y1, y2 read (r1 r2 r0) x2 + (r4 r5 r3) x0 - (r7 r8 r6) x1.
  const __m128 r_x2 = lanes<_MM_SHUFFLE(0, 2, 1, 0)>(_mm_castps_si128(a));
  const __m128 r_x0 = lanes<_MM_SHUFFLE(0, 3, 2, 0)>(_mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 3, 3))));
  const __m128 r_x1 = lanes<_MM_SHUFFLE(0, 2, 1, 0)>(_mm_castps_si128(_mm_shuffle_ps(b, c, _MM_SHUFFLE(0, 0, 3, 2))));
  const __m128i vi = _mm_castps_si128(v);
  const __m128 x0 = lanes<_MM_SHUFFLE(1, 1, 1, 1)>(vi);
  const __m128 x1 = lanes<_MM_SHUFFLE(2, 2, 2, 2)>(vi);
  const __m128 x2 = lanes<_MM_SHUFFLE(3, 3, 3, 3)>(vi);
  // Lane 2 wants r8 x1 - (r2 x2 + r5 x0) and gets (-(r2 x2 + r5 x0)) - (-(r8 x1)): the
  // same sum, zeros included (a - b is a + (-b)).
  const __m128 negate_lane2 = sign_mask(false, false, true, false);
  const __m128 sum = _mm_xor_ps(_mm_add_ps(_mm_mul_ps(r_x2, x2), _mm_mul_ps(r_x0, x0)), negate_lane2);
  const __m128 y = _mm_sub_ps(sum, _mm_xor_ps(_mm_mul_ps(r_x1, x1), negate_lane2));
  _mm_storeu_ps(out, _mm_move_ss(y, v));
}
#endif

template <class T>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void order2_rotate(const T* __restrict r, const T* __restrict in, T* __restrict out) {
#if defined(__SSE2__)
  if constexpr (std::is_same_v<T, float>) {
    order2_sse2(r, in, out);
    return;
  }
#endif
  order2_scalar<T>(r, in, out);
}
// order2_rotate of three channels interleaved (in[3 i + k], 12 values): band1_closed
// on lane vectors, lane k doing channel k's operations in order2_scalar's order, so with
// its bits. In float three loads, three stores and six shuffles move the 12 values,
// where three order2_rotate calls would need 12 gathers and scatters; in double (four
// lanes are two SSE2 registers without AVX) channels 0 and 1 run as pairs.
template <class T>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void order2_rotate3(const T* __restrict r, const T* __restrict in, T* __restrict out) {
#if defined(__GNUC__) && defined(__SSE2__)
  if constexpr (std::is_same_v<T, double>) {  // channels 0, 1 as a pair (one SSE2 register), 2 alone
    typedef double Pair __attribute__((vector_size(16)));
    Pair x[3], y[3];
    __builtin_memcpy(&x[0], in + 3, sizeof(Pair));
    __builtin_memcpy(&x[1], in + 6, sizeof(Pair));
    __builtin_memcpy(&x[2], in + 9, sizeof(Pair));
    band1_closed<T, Pair>(r, x, y);
    const double x2[3] = {in[5], in[8], in[11]};
    double y2[3];
    band1_closed<T, T>(r, x2, y2);
    __builtin_memcpy(out, in, 3 * sizeof(double));
    for (int i = 0; i < 3; ++i) {
      __builtin_memcpy(out + 3 + 3 * i, &y[i], sizeof(Pair));
      out[5 + 3 * i] = y2[i];
    }
    return;
  }
#endif
#if defined(__GNUC__)
  typedef T Lanes __attribute__((vector_size(4 * sizeof(T))));
  Lanes a, b, c;  // in[0..3], in[4..7], in[8..11]
  __builtin_memcpy(&a, in, sizeof a);
  __builtin_memcpy(&b, in + 4, sizeof b);
  __builtin_memcpy(&c, in + 8, sizeof c);
  const Lanes x[3] = {__builtin_shufflevector(a, b, 3, 4, 5, 5), __builtin_shufflevector(b, c, 2, 3, 4, 4),
                      __builtin_shufflevector(c, c, 1, 2, 3, 3)};
  Lanes y[3];
  band1_closed<T, Lanes>(r, x, y);
  a = __builtin_shufflevector(a, y[0], 0, 1, 2, 4);
  b = __builtin_shufflevector(y[0], y[1], 1, 2, 4, 5);
  c = __builtin_shufflevector(y[1], y[2], 2, 4, 5, 6);
  __builtin_memcpy(out, &a, sizeof a);
  __builtin_memcpy(out + 4, &b, sizeof b);
  __builtin_memcpy(out + 8, &c, sizeof c);
#else
  for (int k = 0; k < 3; ++k) {
    const T x[4] = {in[k], in[3 + k], in[6 + k], in[9 + k]};
    T y[4];
    order2_scalar<T>(r, x, y);
    for (int i = 0; i < 4; ++i) out[3 * i + k] = y[i];
  }
#endif
}
}  // namespace detail

}  // namespace shtool
