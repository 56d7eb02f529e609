#include "shtool/rotation.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "shtool/sh.h"
#include "kernels/rotation_kernels.h"
#include "precondition.h"
#include "rotation/x90_structure.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace shtool {
namespace {

// Offset of band l's dense block: sum_{k<l} (2k+1)^2.
constexpr int block_offset(int l) { return l * (4 * l * l - 1) / 3; }

// Method codes of the generated kernels (rotation_kernels.h), by index zxzxz, taylor1,
// taylor1.5, taylor2.
constexpr int kKernelMethod[4] = {0, 1, 15, 2};

// First band of the paired zxzxz path in double at orders above the generated
// whole-order kernels (below it the generated kernel of that order runs).
constexpr int kPairFrom = 10;
// Values per row of band l in the paired path: the longest class, rounded up to even.
constexpr int pair_count(int l) { return (l / 2 + 2) & ~1; }

}  // namespace

namespace detail {

bool fma_kernels_supported() {
#if SHTOOL_FMA_KERNELS
  static const bool supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return supported;
#else
  return false;
#endif
}

namespace {
bool fma_kernels_allowed = true;
}  // namespace

bool fma_kernels_enabled() { return fma_kernels_allowed && fma_kernels_supported(); }
void use_fma_kernels(bool on) { fma_kernels_allowed = on; }

}  // namespace detail

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

double taylor_error_bound(RotationMethod method, int order, double beta, std::optional<double> ddy_offdiag_norm) {
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
    // Without its norm: D2 - diag(D2) has its eigenvalues in [-(N-1)^2, (N-1)^2] (Weyl:
    // D2's in [-(N-1)^2, 0], the diagonal's, Rayleigh quotients of D2, too).
    case RotationMethod::taylor15:
      return std::abs(second) + 0.5 * beta * beta * ddy_offdiag_norm.value_or(double(order - 1) * double(order - 1));
    default: return 0.0;
  }
}

template <class T>
ShRotation<T>::ShRotation(int order, std::shared_ptr<const RotationHelpers> helpers)
    : order_(order), helpers_(std::move(helpers)), fused_(detail::fma_kernels_enabled()) {
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
          // RotationHelpers::from_table checked the structure of every row.
          const std::optional<detail::X90Run> run = detail::x90_row_run(l, r, at);
          if (!run) detail::precondition_failed("rotation helpers: X90 band " + std::to_string(l) +
                                                " breaks the class structure (see RotationHelpers::from_table)");
          start[first + r] = split_pos(l, run->lo);
          for (int c = run->lo; c <= run->hi; c += 2) val[out++] = static_cast<T>(at(c));
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
  // Three entries of padding: the generated kernels, and zyz_tables_sse2, read and write
  // the tables four entries at a time. cos(0) = 1 and sin(0) = 0 for good.
  for (auto* v : {&cos_a_, &sin_a_, &cos_b_, &sin_b_, &cos_g_, &sin_g_}) v->assign(order + 3, T(0));
  for (auto* v : {&cos_a_, &cos_b_, &cos_g_}) (*v)[0] = T(1);
  dense_.assign(block_offset(order), T(0));
  if (helpers_) {
    for (int k = 0; k < 4; ++k) {
      kernel1_[k] = detail::rotation_kernel<T, 1>(kKernelMethod[k], order, fused_);
      kernel3_[k] = detail::rotation_kernel<T, 3>(kKernelMethod[k], order, fused_);
      if (!kernel1_[k] || !kernel3_[k]) detail::invariant_failed("no rotation kernel for this order");
    }
    kernel_order_ = std::min(order, detail::kKernelMaxOrder);
    closed_ = order <= detail::kClosedMaxOrder;
    // The general path's dispatch (method, order, kernels, a stack frame for every order's
    // tables) costs about 3 ns of a 78 ns rotation at N = 5 in float.
    auto use = [this]<int N>(std::integral_constant<int, N>) {
      if constexpr (kMatrixInLanes) {
        zxzxz_set_[0] = &set_zxzxz_lanes<N, false>;
        zxzxz_set_[1] = &set_zxzxz_lanes<N, true>;
      } else {
        zxzxz_set_[0] = &set_zxzxz<N, false>;
        zxzxz_set_[1] = &set_zxzxz<N, true>;
      }
    };
    switch (order) {
      case 5: use(std::integral_constant<int, 5>{}); break;
      case 6: use(std::integral_constant<int, 6>{}); break;
      case 7: use(std::integral_constant<int, 7>{}); break;
      case 8: use(std::integral_constant<int, 8>{}); break;
      case 9: use(std::integral_constant<int, 9>{}); break;
      case 10: use(std::integral_constant<int, 10>{}); break;
      default: break;
    }
    static_assert(detail::kClosedMaxOrder == 4 && detail::kKernelMaxOrder == 10, "the orders of zxzxz_set_");
    if (order <= detail::kBandKernelMaxBand + 1) {
      for (int k = 0; k < 4; ++k) {
        std::vector<BatchKernel>& v = batch_kernels_[k];
        v.push_back(detail::batch_kernel<T>(kKernelMethod[k], kernel_order_, fused_));
        for (int l = detail::kKernelMaxOrder; l < order; ++l)
          v.push_back(detail::batch_band_kernel<T>(kKernelMethod[k], l, fused_));
        if (std::find(v.begin(), v.end(), nullptr) != v.end()) v.clear();
      }
    }
    pair_from_ = order;
    if constexpr (std::is_same_v<T, double>) {
      if (order > detail::kKernelMaxOrder) {
        pair_from_ = kPairFrom;
        kernel1_[0] = detail::rotation_kernel<T, 1>(0, pair_from_, fused_);
        kernel3_[0] = detail::rotation_kernel<T, 3>(0, pair_from_, fused_);
        build_pairs();
      }
    }
  }
}

template <class T>
void ShRotation<T>::build_pairs() {
  // Rows of one band that read the same column class (the same first split column) are
  // paired in their order; an odd one out is paired with a dummy row whose values are 0
  // and whose result goes to the scratch slot 2l + 1.
  pair_band_.assign(2 * order_ + 1, 0);
  pair_band_val_.assign(2 * order_ + 1, 0);
  pair_rows_.clear();
  pair_val_.clear();
  for (int l = 0; l < order_; ++l) {
    const int first = l * l, size = 2 * l + 1;
    for (int k = 0; k < 2; ++k) {
      pair_band_[2 * l + k] = static_cast<int>(pair_rows_.size() / 3);
      pair_band_val_[2 * l + k] = static_cast<int>(pair_val_.size());
      if (l < pair_from_) continue;
      const std::vector<int>& start = k == 0 ? x90_start_ : x90t_start_;
      const T* val = (k == 0 ? x90_val_.data() + x90_band_val_[l] : x90t_val_.data() + x90t_band_val_[l]);
      std::vector<int> row_val(size);  // offset of each row's values
      for (int r = 0, at = 0; r < size; ++r) {
        row_val[r] = at;
        at += detail::x90_row_length(l, r);
      }
      std::vector<bool> done(size, false);
      for (int r = 0; r < size; ++r) {
        if (done[r]) continue;
        int partner = -1;
        for (int q = r + 1; q < size && partner < 0; ++q)
          if (!done[q] && start[first + q] == start[first + r]) partner = q;
        done[r] = true;
        if (partner >= 0) done[partner] = true;
        // Every row of the band is padded with zeros to the longest class, l / 2 + 1,
        // rounded up to even (paired_rows sums even and odd columns apart): one trip
        // count per band also keeps the inner loop's exit branch predictable. The
        // padding reads at most two values past a class: the next class, or the two
        // zeroed slots after the band (apply_bands).
        const int count = detail::x90_row_length(l, r), padded = pair_count(l);
        pair_rows_.insert(pair_rows_.end(), {start[first + r], r, partner >= 0 ? partner : size});
        for (int c = 0; c < padded; ++c) {
          pair_val_.push_back(c < count ? val[row_val[r] + c] : T(0));
          pair_val_.push_back(partner >= 0 && c < count ? val[row_val[partner] + c] : T(0));
        }
      }
    }
  }
  pair_band_[2 * order_] = static_cast<int>(pair_rows_.size() / 3);
  pair_band_val_[2 * order_] = static_cast<int>(pair_val_.size());
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
    taylor_limit_sin2_[k] = std::sin(lo) * std::sin(lo);
  }
  taylor_widest_sin2_ = std::max(std::max(taylor_limit_sin2_[0], taylor_limit_sin2_[1]), taylor_limit_sin2_[2]);
}

namespace {

// cos(m x), sin(m x) for m < n as the powers (c + i s)^m of the unit complex number
// ([2] App. C uses the same multiple-angle products in sequence), built by the
// product tree z^m = z^(m/2) z^(m - m/2): the rounding error still grows only linearly
// in m, but the chain of dependent multiplications is log2(m) long, not m. No
// trigonometric call. N > 0: a compile-time count (the loop unrolls into registers).
template <int N, class T>
inline void multiple_angles(int n_run, T c1, T s1, T* __restrict c, T* __restrict s) {
  const int n = N > 0 ? N : n_run;
  c[0] = T{} + 1;  // T may be a lane vector (rotate_batch)
  s[0] = T{};
  if (n > 1) {
    c[1] = c1;
    s[1] = s1;
  }
  for (int m = 2; m < n; ++m) {
    const int h = m / 2, k = m - h;
    c[m] = c[h] * c[k] - s[h] * s[k];
    s[m] = s[h] * c[k] + c[h] * s[k];
  }
}

// The cos / sin tables of the three zyz angles (beta too if with_beta). E: ZyzCosSin<T>,
// or ZyzLanes<T> when T is a lane vector.
template <int N, class T, class E>
inline void zyz_tables(int n, const E& e, bool with_beta, T* ca, T* sa, T* cb, T* sb, T* cg,
                       T* sg) {
  multiple_angles<N>(n, e.ca, e.sa, ca, sa);
  if (with_beta) multiple_angles<N>(n, e.cb, e.sb, cb, sb);
  multiple_angles<N>(n, e.cg, e.sg, cg, sg);
}

#if defined(__SSE2__)
// zyz_tables for one float rotation in SSE2 lanes: the three angles side by side (lanes
// a, b, g), multiple_angles' products and sums in its order, so every entry has the
// scalar bits. Each group m = 1..4, 5..8, ... is transposed and stored as one vector per
// table: the generated kernels load the same groups as vectors (their z-rotations run
// four pairs in lanes), and a load that matches one pending store takes its value from
// it, where a vector load over four scalar stores would wait for them to reach the
// cache. The tables have three entries of padding for the last group, and their m = 0
// entries (1, 0) are set once by the constructor.
template <int N>
inline void zyz_tables_sse2(const ZyzCosSin<float>& e, float* const* t) {
  static_assert(N >= 2);
  __m128 c[N + 3], s[N + 3];
  c[1] = _mm_setr_ps(e.ca, e.cb, e.cg, 0.0f);
  s[1] = _mm_setr_ps(e.sa, e.sb, e.sg, 0.0f);
  for (int m = 2; m < N; ++m) {
    const int h = m / 2, k = m - h;
    c[m] = _mm_sub_ps(_mm_mul_ps(c[h], c[k]), _mm_mul_ps(s[h], s[k]));
    s[m] = _mm_add_ps(_mm_mul_ps(s[h], c[k]), _mm_mul_ps(c[h], s[k]));
  }
  for (int m = N; m < N + 3; ++m) c[m] = s[m] = _mm_setzero_ps();
  for (int m = 1; m < N; m += 4) {
    const __m128* rows[2] = {c + m, s + m};
    for (int cs = 0; cs < 2; ++cs) {
      const __m128* x = rows[cs];
      const __m128 t0 = _mm_unpacklo_ps(x[0], x[1]), t1 = _mm_unpacklo_ps(x[2], x[3]);
      const __m128 t2 = _mm_unpackhi_ps(x[0], x[1]), t3 = _mm_unpackhi_ps(x[2], x[3]);
      _mm_storeu_ps(t[cs] + m, _mm_movelh_ps(t0, t1));
      _mm_storeu_ps(t[2 + cs] + m, _mm_movehl_ps(t1, t0));
      _mm_storeu_ps(t[4 + cs] + m, _mm_movelh_ps(t2, t3));
    }
  }
}
#endif

// The three tables of zxzxz at order N: in SSE2 lanes for float.
template <int N, class T>
inline void zxzxz_tables(const ZyzCosSin<T>& e, T* const* t) {
#if defined(__SSE2__)
  if constexpr (std::is_same_v<T, float>) {
    zyz_tables_sse2<N>(e, t);
    return;
  }
#endif
  zyz_tables<N>(N, e, true, t[0], t[1], t[2], t[3], t[4], t[5]);
}

// zyz_tables with the count fixed at compile time where the kernels are generated.
// t: ca, sa, cb, sb, cg, sg.
template <class T, class E>
void fill_zyz_tables(int order, const E& e, bool with_beta, T* const* t) {
#if defined(__SSE2__)
  if constexpr (std::is_same_v<T, float> && std::is_same_v<E, ZyzCosSin<float>>) {
    // Every order with generated kernels (whole orders to 10, band kernels to band 19).
    switch (order) {
#define SHTOOL_ZYZ_SSE2_CASE(N) \
  case N: zyz_tables_sse2<N>(e, t); return;
      SHTOOL_ZYZ_SSE2_CASE(5) SHTOOL_ZYZ_SSE2_CASE(6) SHTOOL_ZYZ_SSE2_CASE(7) SHTOOL_ZYZ_SSE2_CASE(8)
      SHTOOL_ZYZ_SSE2_CASE(9) SHTOOL_ZYZ_SSE2_CASE(10) SHTOOL_ZYZ_SSE2_CASE(11) SHTOOL_ZYZ_SSE2_CASE(12)
      SHTOOL_ZYZ_SSE2_CASE(13) SHTOOL_ZYZ_SSE2_CASE(14) SHTOOL_ZYZ_SSE2_CASE(15) SHTOOL_ZYZ_SSE2_CASE(16)
      SHTOOL_ZYZ_SSE2_CASE(17) SHTOOL_ZYZ_SSE2_CASE(18) SHTOOL_ZYZ_SSE2_CASE(19) SHTOOL_ZYZ_SSE2_CASE(20)
#undef SHTOOL_ZYZ_SSE2_CASE
      default: break;
    }
  }
#endif
  switch (order) {
#define SHTOOL_ZYZ_CASE(N) \
  case N: zyz_tables<N>(N, e, with_beta, t[0], t[1], t[2], t[3], t[4], t[5]); break;
    SHTOOL_ZYZ_CASE(1) SHTOOL_ZYZ_CASE(2) SHTOOL_ZYZ_CASE(3) SHTOOL_ZYZ_CASE(4) SHTOOL_ZYZ_CASE(5)
    SHTOOL_ZYZ_CASE(6) SHTOOL_ZYZ_CASE(7) SHTOOL_ZYZ_CASE(8) SHTOOL_ZYZ_CASE(9) SHTOOL_ZYZ_CASE(10)
#undef SHTOOL_ZYZ_CASE
    default: zyz_tables<0>(order, e, with_beta, t[0], t[1], t[2], t[3], t[4], t[5]); break;
  }
}

// The tilt b itself, for the Taylor methods: they are for small b, where b = asin(sin b) =
// s + s^3/6 + 3 s^5/40 + O(s^7) is exact to rounding without an atan2 call (the first
// omitted term, (5/112) s^7, is below half an ulp of b for s < 1e-3 in double, s < 0.03
// in float); any other tilt by atan2.
template <class T>
T taylor_tilt(T cb, T sb) {
  constexpr T kSeries = sizeof(T) < sizeof(double) ? T(0.03) : T(1e-3);
  if (cb > 0 && sb < kSeries) {
    const T s2 = sb * sb;
    return sb + sb * s2 * (T(1) / 6 + s2 * (T(3) / 40));
  }
  return std::atan2(sb, cb);
}

// Square root lane by lane (correctly rounded, as std::sqrt).
template <class T>
inline detail::BatchPack<T> sqrt_lanes(detail::BatchPack<T> x) {
#if defined(__SSE2__)
  if constexpr (sizeof(T) == 4) return reinterpret_cast<detail::BatchPack<T>>(_mm_sqrt_ps(reinterpret_cast<__m128>(x)));
  else return reinterpret_cast<detail::BatchPack<T>>(_mm_sqrt_pd(reinterpret_cast<__m128d>(x)));
#else
  for (int k = 0; k < detail::kBatchLanes<T>; ++k) x[k] = std::sqrt(x[k]);
  return x;
#endif
}

// zyz_cos_sin_from_matrix (shtool/euler.h) for one rotation per lane, r column-major:
// the same operations in the same order, both sides of each branch computed and the
// lane's side selected, so every lane gets the bits the scalar function returns.
template <class P>
struct ZyzLanes {
  P ca, sa, cb, sb, cg, sg;
};

template <class T>
inline ZyzLanes<detail::BatchPack<T>> zyz_cos_sin_lanes(const detail::BatchPack<T>* r) {
  using P = detail::BatchPack<T>;
  auto at = [r](int i, int j) { return r[i + 3 * j]; };
  const P zero = P{}, one = P{} + 1;
  ZyzLanes<P> e;
  e.cb = at(2, 2);
  const P sb2 = at(0, 2) * at(0, 2) + at(1, 2) * at(1, 2);
  e.sb = sqrt_lanes<T>(sb2);
  // copysign(1, cb) lane by lane, as the scalar split takes it.
  using Bits = std::conditional_t<sizeof(T) == 4, std::int32_t, std::int64_t>;
  typedef Bits BitsPack __attribute__((vector_size(16)));
  const BitsPack sign = reinterpret_cast<BitsPack>(e.cb) & (BitsPack{} + std::numeric_limits<Bits>::min());
  const P s = reinterpret_cast<P>(reinterpret_cast<BitsPack>(one) | sign);
  const P u = at(1, 1) + s * at(0, 0), v = s * at(1, 0) - at(0, 1);
  const P norm = one + s * e.cb;
  const auto tilted = sb2 >= P{} + std::numeric_limits<T>::min();
  const P inv_norm = one / norm, inv_sb = e.sb * (one / sb2), inv_g = inv_sb * inv_norm;
  e.ca = tilted ? at(0, 2) * inv_sb : one;
  e.sa = tilted ? at(1, 2) * inv_sb : zero;
  e.cg = tilted ? (u * at(0, 2) + v * at(1, 2)) * inv_g : u * inv_norm;
  e.sg = s * (tilted ? (v * at(0, 2) - u * at(1, 2)) * inv_g : v * inv_norm);
  return e;
}

}  // namespace

template <class T>
#if defined(__GNUC__)
__attribute__((always_inline))  // on every set() from order 5 on: a call costs more than the test
#endif
inline RotationMethod ShRotation<T>::choose_method(const Mat3<T>& r, RotationMethod method, double tolerance) {
  if (method == RotationMethod::automatic && order_ <= detail::kClosedMaxOrder)
    return RotationMethod::zxzxz;  // see rotation.h
  if (method != RotationMethod::automatic) return method;
  if (tolerance != cached_tolerance_) update_taylor_limits(tolerance);
  if (taylor_in_reach(r)) {
    const RotationMethod taylor[3] = {RotationMethod::taylor1, RotationMethod::taylor15,
                                      RotationMethod::taylor2};
    const double sb2 = tilt_sin2(r);
    for (int k = 0; k < 3; ++k)
      if (sb2 <= taylor_limit_sin2_[k]) return taylor[k];
  }
  return RotationMethod::zxzxz;
}

template <class T>
template <int N, bool Given>
#if defined(__GNUC__)
// Everything inline: with a dozen instances in this file GCC 12 otherwise calls the zyz
// split out of line, its results through memory (5 ns of a 75 ns rotation at N = 5).
__attribute__((flatten))
#endif
void ShRotation<T>::set_zxzxz(ShRotation& rotation, const Mat3<T>& r, const ZyzCosSin<T>* given) {
  rotation.store_matrix(r);
  rotation.use_zxzxz_kernels();
  ZyzCosSin<T> e;
  if constexpr (Given) e = *given;
  else e = zyz_cos_sin_from_matrix<T>(r);
  T* const t[6] = {rotation.cos_a_.data(), rotation.sin_a_.data(), rotation.cos_b_.data(),
                   rotation.sin_b_.data(), rotation.cos_g_.data(), rotation.sin_g_.data()};
  zxzxz_tables<N>(e, t);
}

template <class T>
template <int N, bool Given>
#if defined(__GNUC__)
__attribute__((flatten))
#endif
void ShRotation<T>::set_zxzxz_lanes(ShRotation& rotation, MatrixLanes r0, MatrixLanes r4, T r8,
                                    const ZyzCosSin<T>* given) {
#if defined(__SSE2__)
  if constexpr (kMatrixInLanes) {
    Mat3<T> r;  // GCC keeps it in registers: its entries become shuffles of r0 and r4
    _mm_storeu_ps(r.data(), r0.v);
    _mm_storeu_ps(r.data() + 4, r4.v);
    r(2, 2) = r8;
    set_zxzxz<N, Given>(rotation, r, given);
    return;
  }
#endif
  (void)rotation, (void)r0, (void)r4, (void)r8, (void)given;
}

template <class T>
bool ShRotation<T>::set_general(const Mat3<T>& r, RotationMethod method, double tolerance,
                                 const ZyzCosSin<T>* given) {
  if (method != RotationMethod::reference && !helpers_) return false;
  method = choose_method(r, method, tolerance);
  resolved_ = method;
  const bool whole = method != RotationMethod::reference && order_ <= kernel_order_;
  const int k = method == RotationMethod::zxzxz      ? 0
                : method == RotationMethod::taylor1  ? 1
                : method == RotationMethod::taylor15 ? 2
                                                     : 3;
  whole_kernel_ = whole ? kernel1_[k] : nullptr;
  whole_kernel3_ = whole ? kernel3_[k] : nullptr;
  store_matrix(r);
  switch (method) {
    case RotationMethod::reference: build_reference(r); break;
    case RotationMethod::zxzxz:
      // Bands 1..3 are closed forms in R up to order 4 (rotation_kernels.h): no Euler
      // angles there.
      if (order_ <= detail::kClosedMaxOrder) break;
      [[fallthrough]];
    default: {
      const bool zxzxz = method == RotationMethod::zxzxz;
      const ZyzCosSin<T> e = given ? *given : zyz_cos_sin_from_matrix<T>(r);
      T* const t[6] = {cos_a_.data(), sin_a_.data(), cos_b_.data(), sin_b_.data(), cos_g_.data(), sin_g_.data()};
      fill_zyz_tables(order_, e, zxzxz, t);
      if (!zxzxz) beta_ = taylor_tilt(e.cb, e.sb);
      break;
    }
  }
  return true;
}

namespace {

// Bands above the generated kernels (l >= detail::kKernelMaxOrder), at run time. P is the
// lane type: T for one vector, a 4-wide vector of T for three (rotation_kernels.h).

// Band l of a z-rotation: (f_m, f_-m) turns by m a ([2] App. C). `in` is the band
// in natural order (m = -l..l); the result goes to `out` split by parity of the
// band-relative index j = m + l (even j at j / 2, odd j at l + 1 + j / 2), the order
// in which the strided X90 rows read their input.
template <class T, class P>
inline void z_band_to_split(int l, const T* __restrict c, const T* __restrict s,
                            const P* __restrict in, P* __restrict out) {
  P* even = out;
  P* odd = out + l + 1;
  // The middle (m = 0) entry, by index arithmetic: GCC 12 under -fsanitize=shift
  // miscompiles the equivalent `((l & 1) ? odd : even)[l >> 1] = ...`.
  out[(l & 1) ? l + 1 + (l >> 1) : (l >> 1)] = in[l];
  for (int m = 1; m <= l; ++m) {
    const P p = in[l + m], q = in[l - m];
    P* half = ((l + m) & 1) ? odd : even;  // l + m and l - m have the same parity
    half[(l + m) >> 1] = c[m] * p - s[m] * q;
    half[(l - m) >> 1] = s[m] * p + c[m] * q;
  }
}

// Band l of a z-rotation, natural order in and out (entry j of the output at out[S j]:
// S = 3 writes one lane of three interleaved).
template <class T, class P, int S = 1>
inline void z_band(int l, const T* __restrict c, const T* __restrict s, const P* __restrict in,
                   P* __restrict out) {
  out[S * l] = in[l];
  for (int m = 1; m <= l; ++m) {
    const P p = in[l + m], q = in[l - m];
    out[S * (l + m)] = c[m] * p - s[m] * q;
    out[S * (l - m)] = s[m] * p + c[m] * q;
  }
}

// Rows of one band of X90 (or its transpose) in strided form, reading the split input.
template <class T, class P>
inline void strided_rows(int l, const int* __restrict start, const T* __restrict val,
                         const P* __restrict in, P* __restrict out) {
  for (int r = 0; r <= 2 * l; ++r) {
    const P* x = in + start[r];
    const int count = detail::x90_row_length(l, r);
    P sum = val[0] * x[0];
    for (int k = 1; k < count; ++k) sum += val[k] * x[k];
    val += count;
    out[r] = sum;
  }
}

// The y part of the Taylor rotation for one band ([2] Sec. 3): u = t + b D1 t
// (+ b^2/2 D2 t), D1 antisymmetric tridiagonal (only its sub-diagonal s1 is stored), D2
// diagonal (sd) plus distance 2 (s2). Order 1, 15 (diagonal of D2 only) or 2. t has two
// zeros of padding on each side and the derivative entries that would reach into a
// neighbouring band are zero, so the loop needs no bounds tests.
template <int Order, class T, class P>
inline void taylor_y_band(int l, T b, T hb2, const T* __restrict s1, const T* __restrict sd,
                          const T* __restrict s2, const P* __restrict t, P* __restrict u) {
  const int size = 2 * l + 1;
  for (int i = 0; i < size; ++i) {
    P v = t[i] + b * (s1[i] * t[i - 1] - s1[i + 1] * t[i + 1]);
    if constexpr (Order == 15) v += hb2 * (sd[i] * t[i]);
    if constexpr (Order == 2) v += hb2 * (sd[i] * t[i] + s2[i] * t[i - 2] + s2[i + 2] * t[i + 2]);
    u[i] = v;
  }
}

// Rows of X90 (or its transpose) of one band two at a time (build_pairs): the two rows
// of a pair read the same split columns, so each column value is multiplied into both
// in one SSE2 operation. `in` holds each split column value twice (both halves of a
// register, written so by z_band_to_split_pairs), so no broadcast is needed per use.
// Two partial sums (even and odd columns; the padded count is even) halve the chain of
// dependent additions. This path alone computes zxzxz bands >= pair_from_ in double, for
// one vector and three interleaved alike, so their results stay identical.
using Pair = detail::Pack<double, 2>;
inline void paired_rows(const int* __restrict rows, int pairs, int count, const double* __restrict val,
                        const Pair* __restrict in, double* __restrict out) {
  for (int p = 0; p < pairs; ++p, rows += 3) {
    const Pair* x = in + rows[0];
    Pair v0, v1;
    __builtin_memcpy(&v0, val, sizeof v0);
    __builtin_memcpy(&v1, val + 2, sizeof v1);
    Pair even = v0 * x[0], odd = v1 * x[1];
    for (int k = 2; k < count; k += 2) {
      __builtin_memcpy(&v0, val + 2 * k, sizeof v0);
      __builtin_memcpy(&v1, val + 2 * k + 2, sizeof v1);
      even += v0 * x[k];
      odd += v1 * x[k + 1];
    }
    val += 2 * count;
    const Pair sum = even + odd;
    out[rows[1]] = sum[0];
    out[rows[2]] = sum[1];
  }
}

// z_band_to_split with every value written twice, into a register-sized pair (entry j
// of the input at in[S j], as in z_band).
template <int S>
inline void z_band_to_split_pairs(int l, const double* __restrict c, const double* __restrict s,
                                  const double* __restrict in, Pair* __restrict out) {
  Pair* even = out;
  Pair* odd = out + l + 1;
  out[(l & 1) ? l + 1 + (l >> 1) : (l >> 1)] = Pair{in[S * l], in[S * l]};  // as in z_band_to_split
  for (int m = 1; m <= l; ++m) {
    const double p = in[S * (l + m)], q = in[S * (l - m)];
    Pair* half = ((l + m) & 1) ? odd : even;
    const double a = c[m] * p - s[m] * q, b = s[m] * p + c[m] * q;
    half[(l + m) >> 1] = Pair{a, a};
    half[(l - m) >> 1] = Pair{b, b};
  }
}

// Buffer of one band of lanes (2l + 1 <= 2 kMaxOrder - 1 values, plus padding).
constexpr int kBandBuffer = 2 * kMaxOrder + 8;

}  // namespace

template <class T>
int ShRotation<T>::first_table_band() const {
  if (resolved_ == RotationMethod::reference) return 0;
  if (resolved_ == RotationMethod::zxzxz && pair_from_ < order_) return pair_from_;
  return kernel_order_;
}

// The generated kernel of the bands below first_table_band() (> 0).
template <class T>
template <int V>
void ShRotation<T>::apply_kernel(const T* in, T* out) const {
  const int k = resolved_ == RotationMethod::zxzxz      ? 0
                : resolved_ == RotationMethod::taylor1  ? 1
                : resolved_ == RotationMethod::taylor15 ? 2
                                                        : 3;
  const detail::KernelState<T> state{r_,
                                     cos_a_.data(),
                                     sin_a_.data(),
                                     cos_b_.data(),
                                     sin_b_.data(),
                                     cos_g_.data(),
                                     sin_g_.data(),
                                     beta_,
                                     T(0.5) * beta_ * beta_};
  if constexpr (V == 1) kernel1_[k](state, &in, &out);
  else kernel3_[k](state, &in, &out);
}

// Bands from..to-1 at run time: the reference blocks, the paired zxzxz rows (double), the
// generated kernels of single bands, or the table-driven bands.
template <class T>
template <int V>
void ShRotation<T>::apply_bands(int from, int to, const T* in, T* out) const {
  // Lanes of the table-driven bands: as in rotation_kernels.h, but three doubles without
  // AVX run one lane at a time.
  constexpr bool kSplit = V == 3 && 4 * sizeof(T) > detail::kNativeLaneBytes;
  constexpr int kPasses = kSplit ? 3 : 1;
  using P = detail::Pack<T, kSplit ? 1 : V>;
  P x[kBandBuffer], y[kBandBuffer];
  const int base = from * from;
  if (resolved_ == RotationMethod::reference) {
    for (int l = from; l < to; ++l) {
      const int size = 2 * l + 1;
      const T* block = dense_.data() + block_offset(l);
      const T* src = in + V * (l * l - base);
      T* dst = out + V * (l * l - base);
      for (int lane = 0; lane < kPasses; ++lane) {
        detail::load_lanes<V>(src, size, x, lane);
        for (int r = 0; r < size; ++r) {
          P sum = block[r * size] * x[0];
          for (int c = 1; c < size; ++c) sum += block[r * size + c] * x[c];
          y[r] = sum;
        }
        detail::store_lanes<V>(static_cast<const P*>(y), size, dst, lane);
      }
    }
    return;
  }
  P t1[kBandBuffer], t2[kBandBuffer];
  const T hb2 = T(0.5) * beta_ * beta_;
  const int k = resolved_ == RotationMethod::zxzxz      ? 0
                : resolved_ == RotationMethod::taylor1  ? 1
                : resolved_ == RotationMethod::taylor15 ? 2
                                                        : 3;
  const detail::KernelState<T> state{r_,          cos_a_.data(), sin_a_.data(), cos_b_.data(), sin_b_.data(),
                                     cos_g_.data(), sin_g_.data(), beta_,         hb2};
  if constexpr (std::is_same_v<T, double>) {
    if (k == 0 && pair_from_ < order_) {
      // zxzxz in double: X90 two rows at a time, one lane at a time (see Lanes).
      Pair split[kBandBuffer];
      double t[kBandBuffer];
      for (int l = from; l < to; ++l) {
        const int count = pair_count(l);
        const int* rows = pair_rows_.data() + 3 * pair_band_[2 * l];
        const int* rows_t = pair_rows_.data() + 3 * pair_band_[2 * l + 1];
        const int pairs = pair_band_[2 * l + 1] - pair_band_[2 * l];
        const int pairs_t = pair_band_[2 * l + 2] - pair_band_[2 * l + 1];
        const double* val = pair_val_.data() + pair_band_val_[2 * l];
        const double* val_t = pair_val_.data() + pair_band_val_[2 * l + 1];
        split[2 * l + 1] = split[2 * l + 2] = Pair{};  // read (times 0) by the padding
        for (int lane = 0; lane < V; ++lane) {
          z_band_to_split_pairs<V>(l, cos_g_.data(), sin_g_.data(), in + V * (l * l - base) + lane, split);
          paired_rows(rows, pairs, count, val, split, t);
          z_band_to_split_pairs<1>(l, cos_b_.data(), sin_b_.data(), t, split);
          paired_rows(rows_t, pairs_t, count, val_t, split, t);
          z_band<double, double, V>(l, cos_a_.data(), sin_a_.data(), t, out + V * (l * l - base) + lane);
        }
      }
      return;
    }
  }
  for (int l = from; l < to; ++l) {
    const int first = l * l, size = 2 * l + 1;
    const T* src = in + V * (first - base);
    T* dst = out + V * (first - base);
    // Generated kernel of this band, when there is one.
    if (const auto kernel = detail::band_kernel<T, V>(kKernelMethod[k], l, fused_)) {
      kernel(state, &src, &dst);
      continue;
    }
    for (int lane = 0; lane < kPasses; ++lane) {
      detail::load_lanes<V>(src, size, x, lane);
      if (resolved_ == RotationMethod::zxzxz) {
        // Band l of M(R) = Z(a) X90^T Z(b) X90 Z(g) (Ry(b) = Rx(-90) Rz(b) Rx(+90)).
        z_band_to_split(l, cos_g_.data(), sin_g_.data(), x, t1);
        strided_rows(l, x90_start_.data() + first, x90_val_.data() + x90_band_val_[l], t1, t2);
        z_band_to_split(l, cos_b_.data(), sin_b_.data(), t2, t1);
        strided_rows(l, x90t_start_.data() + first, x90t_val_.data() + x90t_band_val_[l], t1, t2);
        z_band(l, cos_a_.data(), sin_a_.data(), t2, y);
      } else {
        // Band l of Z(a) T(b) Z(g), T the truncated Taylor series of the y-rotation.
        P* t = t1 + 2;  // t[-2], t[-1] and t[size], t[size + 1] are 0
        t1[0] = t1[1] = t[size] = t[size + 1] = P{};
        z_band(l, cos_g_.data(), sin_g_.data(), x, t);
        const T* s1 = dy_sub_.data() + first;
        const T* sd = ddy_diag_.data() + first;
        const T* s2 = ddy_off2_.data() + first;
        if (resolved_ == RotationMethod::taylor1) taylor_y_band<1>(l, beta_, hb2, s1, sd, s2, t, t2);
        else if (resolved_ == RotationMethod::taylor15) taylor_y_band<15>(l, beta_, hb2, s1, sd, s2, t, t2);
        else taylor_y_band<2>(l, beta_, hb2, s1, sd, s2, t, t2);
        z_band(l, cos_a_.data(), sin_a_.data(), t2, y);
      }
      detail::store_lanes<V>(static_cast<const P*>(y), size, dst, lane);
    }
  }
}

template <class T>
template <int V>
void ShRotation<T>::apply_lanes(const T* in, T* out) const {
  const int from = first_table_band();
  if (from > 0) apply_kernel<V>(in, out);
  if (from < order_) apply_bands<V>(from, order_, in + V * from * from, out + V * from * from);
}

template <class T>
void ShRotation<T>::sizes_failed(std::size_t in, std::size_t out) const {
  const std::size_t n = static_cast<std::size_t>(order_) * static_cast<std::size_t>(order_);
  detail::check_span_size("ShRotation::apply", "in", in, n);
  detail::check_span_size("ShRotation::apply", "out", out, n);
  detail::invariant_failed("ShRotation::apply: sizes_failed with sizes that fit");
}

template <class T>
void ShRotation<T>::apply_general(const T* in, T* out) const {
  apply_lanes<1>(in, out);
}

template <class T>
void ShRotation<T>::apply_general3(const T* in, T* out) const {
  apply_lanes<3>(in, out);
}

// Channel counts other than 3: groups of three channels (a last group of one or two
// repeats its last channel in the spare lanes, whose results are dropped) copied into
// interleaved stack buffers, the kernel's bands at once and the others band by band, so
// that no buffer grows with the order beyond one band.
template <class T>
bool ShRotation<T>::apply_channels(std::span<const T> in, std::span<T> out, int channels) const {
  if (channels < 1) return false;
  const std::size_t n = static_cast<std::size_t>(order_) * static_cast<std::size_t>(order_);
  if (in.size() / static_cast<std::size_t>(channels) != n || in.size() % static_cast<std::size_t>(channels) != 0 ||
      out.size() != in.size())
    return false;
  if (channels == 1) {
    apply(in, out);
    return true;
  }
  if (channels == 3) {  // the sizes were right after all (only reached through a direct call)
    apply_general3(in.data(), out.data());
    return true;
  }
  const int from = first_table_band();
  constexpr int kKernelValues = 3 * detail::kKernelMaxOrder * detail::kKernelMaxOrder;
  constexpr int kBandValues = 3 * (2 * kMaxOrder - 1);
  T x[kBandValues > kKernelValues ? kBandValues : kKernelValues];
  T y[sizeof x / sizeof x[0]];
  const std::size_t stride = static_cast<std::size_t>(channels);
  for (int c0 = 0; c0 < channels; c0 += 3) {
    const int lanes = std::min(3, channels - c0);
    // Coefficients first .. first + count - 1 of the group, to and from x and y.
    auto gather = [&](int first, int count) {
      const T* src = in.data() + static_cast<std::size_t>(first) * stride + c0;
      for (int j = 0; j < count; ++j, src += stride)
        for (int k = 0; k < 3; ++k) x[3 * j + k] = src[std::min(k, lanes - 1)];
    };
    auto scatter = [&](int first, int count) {
      T* dst = out.data() + static_cast<std::size_t>(first) * stride + c0;
      for (int j = 0; j < count; ++j, dst += stride)
        for (int k = 0; k < lanes; ++k) dst[k] = y[3 * j + k];
    };
    if (from > 0) {
      gather(0, from * from);
      if (order_ == 2 && resolved_ == RotationMethod::zxzxz) detail::order2_rotate3<T>(r_, x, y);
      else apply_kernel<3>(x, y);
      scatter(0, from * from);
    }
    for (int l = from; l < order_; ++l) {
      gather(l * l, 2 * l + 1);
      apply_bands<3>(l, l + 1, x, y);
      scatter(l * l, 2 * l + 1);
    }
  }
  return true;
}

// Ivanic-Ruedenberg recurrences (J. Phys. Chem. 1996, with the 1998 errata), written
// for real SH without the Condon-Shortley phase, whose band-1 matrix is R itself in
// the (y, z, x) order. Our basis differs from theirs by (-1)^m on every function, so
// the result is conjugated by diag((-1)^m) at the end. Each band is built from the one
// before and inherits its rounding, which grows band by band (in double a band's norm
// moved by 5e-13 at order 64 and 6e-7 at 128): the bands are carried in long double
// and stored as T.
template <class T>
void ShRotation<T>::build_reference(const Mat3<T>& r) {
  using W = long double;
  // Band 0.
  dense_[0] = 1;
  if (order_ < 2) return;
  const std::size_t largest = static_cast<std::size_t>(2 * order_ - 1) * (2 * order_ - 1);
  if (reference_bands_.size() < 2 * largest) reference_bands_.assign(2 * largest, W(0));
  W* prev = reference_bands_.data();
  W* cur = prev + largest;
  // Band 1 in IR's basis: index m = -1, 0, 1 <-> y, z, x.
  const int axis[3] = {1, 2, 0};
  W b1[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) b1[i * 3 + j] = r(axis[i], axis[j]);
  std::copy(b1, b1 + 9, prev);
  for (int k = 0; k < 9; ++k) dense_[block_offset(1) + k] = static_cast<T>(b1[k]);
  auto r1 = [&b1](int i, int j) { return b1[(i + 1) * 3 + (j + 1)]; };

  for (int l = 2; l < order_; ++l) {
    const int ps = 2 * l - 1, cs = 2 * l + 1;
    auto mp = [prev, ps, l](int a, int b) { return prev[(a + l - 1) * ps + (b + l - 1)]; };
    // P^l_{i,a,b}
    auto P = [&](int i, int a, int b) -> W {
      if (b == l) return r1(i, 1) * mp(a, l - 1) - r1(i, -1) * mp(a, -l + 1);
      if (b == -l) return r1(i, 1) * mp(a, -l + 1) + r1(i, -1) * mp(a, l - 1);
      return r1(i, 0) * mp(a, b);
    };
    for (int m = -l; m <= l; ++m) {
      const int am = std::abs(m);
      const W d = m == 0 ? W(1) : W(0);
      for (int n = -l; n <= l; ++n) {
        const W denom = std::abs(n) == l ? W(2 * l * (2 * l - 1)) : W((l + n) * (l - n));
        const W u = std::sqrt(W((l + m) * (l - m)) / denom);
        const W v = W(0.5) * std::sqrt((1 + d) * W((l + am - 1) * (l + am)) / denom) * (1 - 2 * d);
        const W w = W(-0.5) * std::sqrt(W((l - am - 1) * (l - am)) / denom) * (1 - d);
        W value = 0;
        if (u != 0) value += u * P(0, m, n);
        if (v != 0) {
          W V;
          if (m == 0) V = P(1, 1, n) + P(-1, -1, n);
          else if (m > 0)
            V = P(1, m - 1, n) * std::sqrt(W(1) + (m == 1)) - P(-1, -m + 1, n) * W(m != 1);
          else
            V = P(1, m + 1, n) * W(m != -1) + P(-1, -m - 1, n) * std::sqrt(W(1) + (m == -1));
          value += v * V;
        }
        if (w != 0) {
          W Wt;
          if (m > 0)
            Wt = P(1, m + 1, n) + P(-1, -m - 1, n);
          else
            Wt = P(1, m - 1, n) - P(-1, -m + 1, n);
          value += w * Wt;
        }
        cur[(m + l) * cs + (n + l)] = value;
      }
    }
    T* out = dense_.data() + block_offset(l);
    for (int k = 0; k < cs * cs; ++k) out[k] = static_cast<T>(cur[k]);
    std::swap(prev, cur);
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
std::size_t ShRotation<T>::rotate_lanes(std::span<const Mat3<T>> rotations, const T* in, T* out,
                                        RotationMethod method, double tolerance, int vectors_per_rotation) {
  using P = detail::BatchPack<T>;
  constexpr int B = detail::kBatchLanes<T>;
  constexpr int kMaxBatchOrder = detail::kBandKernelMaxBand + 1;
  if (!helpers_ || order_ > kMaxBatchOrder || method == RotationMethod::reference) return 0;
  const std::size_t n = static_cast<std::size_t>(sh_count(order_)), groups = rotations.size() / B;
  const std::size_t v = static_cast<std::size_t>(vectors_per_rotation), stride = v * n;
  // Per lane: R column-major, and the tables (and tilt) set() would compute, by the same
  // operations, so each lane's kernel input is bit-identical to set()'s.
  P r[9], tables[6][kMaxBatchOrder];
  detail::BatchState<T> state{r, tables[0], tables[1], tables[2], tables[3], tables[4], tables[5], P{}, P{}};
  for (std::size_t g = 0; g < groups; ++g) {
    const Mat3<T>* group = rotations.data() + g * B;
    const T* src[B];
    T* dst[B];
    const RotationMethod chosen = choose_method(group[0], method, tolerance);
    bool same = true;  // one method for the whole group
    for (int j = 0; j < B; ++j) {
      src[j] = in + (g * B + j) * stride;
      dst[j] = out + (g * B + j) * stride;
      same = same && (j == 0 || choose_method(group[j], method, tolerance) == chosen);
    }
    const int k = chosen == RotationMethod::zxzxz      ? 0
                  : chosen == RotationMethod::taylor1  ? 1
                  : chosen == RotationMethod::taylor15 ? 2
                                                       : 3;
    const std::vector<BatchKernel>& kernels = batch_kernels_[k];
    if (!same || kernels.empty()) {  // one at a time
      for (int j = 0; j < B; ++j) {
        set(group[j], method, tolerance);
        for (std::size_t c = 0; c < v; ++c) apply(std::span<const T>(src[j] + c * n, n), std::span<T>(dst[j] + c * n, n));
      }
      continue;
    }
    const T* lane_src[B];
    for (int j = 0; j < B; ++j) lane_src[j] = group[j].data();
    detail::gather_lanes<T>(lane_src, 9, r);
    const bool zxzxz = k == 0;
    if (!zxzxz || order_ > detail::kClosedMaxOrder) {  // else zxzxz is closed forms in R alone
      const ZyzLanes<P> e = zyz_cos_sin_lanes<T>(r);
      P* const t[6] = {tables[0], tables[1], tables[2], tables[3], tables[4], tables[5]};
      fill_zyz_tables(order_, e, zxzxz, t);
      if (!zxzxz) {
        for (int j = 0; j < B; ++j) state.beta[j] = taylor_tilt(e.cb[j], e.sb[j]);
        state.half_beta2 = T(0.5) * state.beta * state.beta;
      }
    }
    for (std::size_t c = 0; c < v; ++c) {  // the lanes' setup above serves all v vectors
      for (const BatchKernel kernel : kernels) kernel(state, src, dst);  // whole order, then bands
      for (int j = 0; j < B; ++j) src[j] += n, dst[j] += n;
    }
  }
  return groups * B;
}

template <class T>
bool rotate_batch(ShRotation<T>& rotation, std::span<const Mat3<T>> rotations, std::span<const T> in,
                  std::span<T> out, RotationMethod method, double tolerance, int vectors_per_rotation) {
  if (vectors_per_rotation < 1)
    detail::precondition_failed("rotate_batch: " + std::to_string(vectors_per_rotation) +
                                " vectors per rotation (at least 1)");
  const std::size_t v = static_cast<std::size_t>(vectors_per_rotation);
  const std::size_t n = static_cast<std::size_t>(sh_count(rotation.order())), count = rotations.size();
  if (in.size() < count * v * n || out.size() < count * v * n)
    detail::precondition_failed("rotate_batch: " + std::to_string(count) + " rotations of order " +
                                std::to_string(rotation.order()) +
                                (v == 1 ? std::string() : " and " + std::to_string(v) + " vectors each") + " need " + std::to_string(count * v * n) +
                                " coefficients in and out, got " + std::to_string(in.size()) + " and " +
                                std::to_string(out.size()));
  if (count == 0) return true;
  if (method != RotationMethod::reference && !rotation.helpers_) return false;
  if (rotation.order_ == 2 && rotation.kernel_order_ > 0 &&
      (method == RotationMethod::zxzxz || method == RotationMethod::automatic)) {
    // Band 1 is nine products of R: gathering four rotations into lanes and scattering
    // them back costs more than it saves, so each rotation reads its matrix in place
    // (order2_rotate, which apply() runs too: the same bits).
    const T* src = in.data();
    T* dst = out.data();
    for (std::size_t k = 0; k < count; ++k)
      for (std::size_t c = 0; c < v; ++c, src += 4, dst += 4) detail::order2_rotate<T>(rotations[k].data(), src, dst);
    rotation.set(rotations[count - 1], method, tolerance);
    return true;
  }
  const std::size_t done =
      rotation.rotate_lanes(rotations, in.data(), out.data(), method, tolerance, vectors_per_rotation);
  for (std::size_t k = done; k < count; ++k) {
    if (!rotation.set(rotations[k], method, tolerance)) return false;
    for (std::size_t c = k * v; c < (k + 1) * v; ++c) rotation.apply(in.subspan(c * n, n), out.subspan(c * n, n));
  }
  if (done == count) rotation.set(rotations[count - 1], method, tolerance);
  return true;
}

template class ShRotation<float>;
template class ShRotation<double>;
template bool rotate_batch<float>(ShRotation<float>&, std::span<const Mat3<float>>, std::span<const float>,
                                  std::span<float>, RotationMethod, double, int);
template bool rotate_batch<double>(ShRotation<double>&, std::span<const Mat3<double>>,
                                   std::span<const double>, std::span<double>, RotationMethod, double, int);

}  // namespace shtool
