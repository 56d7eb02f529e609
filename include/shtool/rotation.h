// SH rotation: one API for every method. Build a rotation once for an order and a
// 3x3 rotation, then apply it to as many coefficient vectors as needed (one channel, or
// several interleaved: an RGB light). g(w) = f(R^-1 w); see docs/conventions.md and docs/rotation.md.
//
// Methods
//   reference  dense per-band matrices by the Ivanic-Ruedenberg recurrences (exact);
//   zxzxz      Rz(a) Rx(-90) Rz(b) Rx(+90) Rz(g) with the sparse X90 table (exact,
//              Kautz et al. 2002; [2] Sec. 2.2, App. C);
//   taylor1, taylor1.5, taylor2
//              Rz(a) T(b) Rz(g) where T is the 1st / "1.5th" / 2nd order Taylor expansion
//              of the y-rotation at b = 0 ([2] Sec. 3): approximate, for small tilt b;
//   automatic  the cheapest method whose error bound for this rotation is within the
//              tolerance (Taylor when the tilt is small enough, zxzxz otherwise; at
//              orders up to 4 always zxzxz, whose bands 1..3 are closed forms in R
//              there, with no Euler angles, which every Taylor step needs).
// The Taylor error bounds are exact operator norms for taylor1/taylor2 (the y-rotation
// generator is normal with eigenvalues i m, |m| < N) and a rigorous bound for taylor1.5.
//
// apply() allocates nothing and only reads the object, so several threads may apply one
// rotation concurrently; set() must not run concurrently with anything else on it.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

#include "shtool/detail/rotation_inline.h"
#include "shtool/euler.h"
#include "shtool/rotation_helpers.h"

namespace shtool {

enum class RotationMethod { automatic, reference, zxzxz, taylor1, taylor15, taylor2 };

std::string_view rotation_method_name(RotationMethod method);  // "taylor1.5", ...
std::optional<RotationMethod> rotation_method_from_name(std::string_view name);

// Default tolerance of the automatic choice: largest coefficient-vector error allowed
// for a unit-length input (spectral norm of the error matrix). Below the rounding error
// of the type it would only forbid approximations that cost nothing in accuracy, so
// float gets a float-sized default.
inline constexpr double kDefaultRotationTolerance = 1e-10;
inline constexpr double kDefaultRotationToleranceFloat = 1e-6;
template <class T>
constexpr double default_rotation_tolerance() {
  return sizeof(T) < sizeof(double) ? kDefaultRotationToleranceFloat : kDefaultRotationTolerance;
}

// Error bound (spectral norm of M(Ry(b)) - approximation) of a Taylor method for
// tilt b at the given order; 0 for exact methods. taylor1.5 also leaves out the
// off-diagonal part of D2 = D1^2: give its norm when it is known (ShRotation uses the
// helpers' infinity norm); without it, (order - 1)^2, which bounds it (D2 is negative
// semidefinite with norm (order - 1)^2).
double taylor_error_bound(RotationMethod method, int order, double beta,
                          std::optional<double> ddy_offdiag_norm = std::nullopt);

template <class T>
class ShRotation;

// Many (rotation, vector) pairs: out[k] = M(rotations[k]) in[k], vectors of N^2
// coefficients stored contiguously (in and out at least rotations.size() N^2 long, else
// std::invalid_argument; they must not overlap). Same method choice as ShRotation::set,
// and the same results bit for bit as set() + apply() of each pair; afterwards
// `rotation` holds the last rotation. Where every rotation of a group resolves to one
// method other than the reference (N <= 20; double zxzxz N <= 10), the group runs one
// rotation per SIMD lane (4 in float, 2 in double): the setup of several rotations
// overlaps and the kernel's instructions are shared (docs/rotation.md, "Many
// rotations"). Returns false (like set()) if the method needs helpers that are missing.
// vectors_per_rotation > 1 turns that many consecutive vectors by each rotation (a
// splat's colour channels, one vector per channel): rotation k turns vectors
// k v .. k v + v - 1, and its setup is made once for the v of them.
template <class T>
bool rotate_batch(ShRotation<T>& rotation, std::span<const Mat3<T>> rotations,
                  std::span<const T> in, std::span<T> out,
                  RotationMethod method = RotationMethod::automatic,
                  double tolerance = default_rotation_tolerance<T>(), int vectors_per_rotation = 1);

template <class T>
class ShRotation {
 public:
  // helpers may be null: then only the reference method is available.
  ShRotation(int order, std::shared_ptr<const RotationHelpers> helpers);

  // Prepares the rotation R (must be orthonormal, det +1). Throws nothing; returns false
  // (and keeps the previous rotation) if the method needs helpers that are missing or
  // cover fewer bands than the order.
  bool set(const Mat3<T>& r, RotationMethod method = RotationMethod::automatic,
           double tolerance = default_rotation_tolerance<T>()) {
    // Up to order 4 zxzxz (and the automatic choice, which is zxzxz there) needs R alone,
    // so set() is a copy, inline: at order 2 a call costs as much as the rotation.
    if (closed_ && (method == RotationMethod::zxzxz || method == RotationMethod::automatic)) {
      store_matrix(r);
      use_zxzxz_kernels();
      return true;
    }
    if (short_zxzxz_set(r, method, tolerance)) {
      call_zxzxz_set(r, nullptr);
      return true;
    }
    return set_general(r, method, tolerance);
  }

  // The same from a unit quaternion (w, x, y, z) (precondition: |q| = 1 to rounding):
  // the zyz cosines and sines come from q directly (zyz_cos_sin_from_quaternion), with one
  // square root and one division against the matrix route's two and four (results agree
  // to rounding). Measured in float against set(matrix_from_quaternion(q)): level at
  // N = 2..4, 3-5 % slower at N = 5 and 6 (there the matrix is built as well, for band 1).
  bool set_quaternion(T w, T x, T y, T z, RotationMethod method = RotationMethod::automatic,
                      double tolerance = default_rotation_tolerance<T>()) {
    const Mat3<T> r = matrix_from_quaternion<T>(w, x, y, z);
    if (order_ <= detail::kClosedMaxOrder) return set(r, method, tolerance);  // no Euler angles there
    const ZyzCosSin<T> e = zyz_cos_sin_from_quaternion<T>(w, x, y, z);
    if (short_zxzxz_set(r, method, tolerance)) {
      call_zxzxz_set(r, &e);
      return true;
    }
    return set_general(r, method, tolerance, &e);
  }

  int order() const { return order_; }
  RotationMethod method() const { return resolved_; }  // never automatic after set()

  // out = M(R) in on the first N^2 coefficients of each; in and out must not overlap. A
  // span shorter than N^2 is a precondition violation (std::invalid_argument, or an
  // abort without exceptions), checked.
  void apply(std::span<const T> in, std::span<T> out) const {
    const std::size_t n = static_cast<std::size_t>(order_) * static_cast<std::size_t>(order_);
    if (in.size() < n || out.size() < n) sizes_failed(in.size(), out.size());
    // Order 2 under zxzxz is band 1 = R itself, inline (see set()).
    if (order_ == 2 && resolved_ == RotationMethod::zxzxz) {
      detail::order2_rotate<T>(r_, in.data(), out.data());
      return;
    }
    if (whole_kernel_) {  // one generated kernel covers the rotation: call it from here
      const T* src = in.data();
      T* dst = out.data();
      whole_kernel_(kernel_state(), &src, &dst);
      return;
    }
    apply_general(in.data(), out.data());
  }

  // Several colour channels, interleaved as every colour table of the engine stores them
  // (docs/engine.md, "Colour"): in and out hold N^2 * channels values, coefficient i of
  // channel c at i * channels + c; out = M(R) in channel by channel, bit-identical to
  // apply() of each channel alone. Three channels (an RGB light) run in the lanes of one
  // SIMD vector, read and written in place, so they cost about one apply(), not three;
  // other counts go three at a time through the same code, by way of stack buffers.
  // Returns false and writes nothing if channels < 1 or in or out does not hold
  // N^2 * channels values; in and out must not overlap. Allocates nothing and only reads
  // the object, like apply().
  bool apply(std::span<const T> in, std::span<T> out, int channels) const {
    const std::size_t n = static_cast<std::size_t>(order_) * static_cast<std::size_t>(order_);
    if (channels != 3 || in.size() != 3 * n || out.size() != 3 * n) return apply_channels(in, out, channels);
    if (order_ == 2 && resolved_ == RotationMethod::zxzxz) {  // inline, as in apply()
      detail::order2_rotate3<T>(r_, in.data(), out.data());
      return true;
    }
    if (whole_kernel3_) {  // as in apply()
      const T* src = in.data();
      T* dst = out.data();
      whole_kernel3_(kernel_state(), &src, &dst);
      return true;
    }
    apply_general3(in.data(), out.data());
    return true;
  }

  // The dense per-band matrices of the reference method for the current rotation
  // (band l block of (2l+1)^2 values, row-major, starting at l(4l^2-1)/3).
  std::span<const T> reference_blocks() const { return dense_; }

 private:
  friend bool rotate_batch<T>(ShRotation<T>&, std::span<const Mat3<T>>, std::span<const T>, std::span<T>,
                              RotationMethod, double, int);
  // r_ = R. Two register-sized copies and one element (Eigen packets), spelled out: as a
  // memcpy, or as copy_n, GCC 12 has emitted a memmove call or `rep movs` here, either of
  // which costs more than a small-order rotation.
  void store_matrix(const Mat3<T>& r) {
    Eigen::Map<Mat3<T>> dst(r_);
    dst = r;
  }
  // What a generated kernel reads of the current rotation.
  detail::KernelState<T> kernel_state() const {
    return {r_, cos_a_.data(), sin_a_.data(), cos_b_.data(), sin_b_.data(), cos_g_.data(), sin_g_.data(), beta_,
            T(0.5) * beta_ * beta_};
  }
  // The zxzxz kernels. They stay from one zxzxz rotation to the next: one test instead
  // of three stores.
  void use_zxzxz_kernels() {
    if (resolved_ != RotationMethod::zxzxz) {
      resolved_ = RotationMethod::zxzxz;
      whole_kernel_ = kernel1_[0];
      whole_kernel3_ = kernel3_[0];
    }
  }
  // sin^2 b = R02^2 + R12^2 of R = Rz(a) Ry(b) Rz(g): the tilt without a square root.
  static double tilt_sin2(const Mat3<T>& r) { return static_cast<double>(r(0, 2) * r(0, 2) + r(1, 2) * r(1, 2)); }
  // Whether one of the Taylor methods may take r under the automatic choice (the limits
  // of cached_tolerance_). The tilt first: for generic rotations it is too large, so the
  // branch is predicted, where the sign of R22 alone is a coin toss (GCC turns a
  // non-short-circuit `&` of the two into two branches, the sign first, mispredicted half
  // the time: 4 ns a set() at N = 5 in float on AMD Zen 1).
  bool taylor_in_reach(const Mat3<T>& r) const { return tilt_sin2(r) <= taylor_widest_sin2_ && r(2, 2) > 0; }
  // Whether set() of r takes zxzxz_set_: from order 5 the generic rotation (a tilt out of
  // the Taylor methods' reach) in one call unrolled for the order.
  bool short_zxzxz_set(const Mat3<T>& r, RotationMethod method, double tolerance) const {
    return zxzxz_set_[0] && (method == RotationMethod::zxzxz ||
                          (method == RotationMethod::automatic && tolerance == cached_tolerance_ && !taylor_in_reach(r)));
  }
  // set() under zxzxz at the orders of zxzxz_set_: R, the kernels, the zyz split (*e if
  // Given, from R otherwise) and the cos / sin tables, unrolled for order N (rotation.cpp).
  // Given is a template argument: as a run-time test, GCC 12 calls the split out of line.
  template <int N, bool Given>
  static void set_zxzxz(ShRotation& rotation, const Mat3<T>& r, const ZyzCosSin<T>* e);
#if defined(__SSE2__)
  // In float R goes to zxzxz_set_ in registers, column-major in two 4-float lanes and
  // R22: matrix_from_quaternion builds it in lanes, and by reference it would go through
  // memory on its way to the split (about 2 ns of a 75 ns rotation at N = 5).
  static constexpr bool kMatrixInLanes = std::is_same_v<T, float>;
  struct MatrixLanes {  // one register still (x86-64 ABIs); a struct, as __m128's attributes
    __m128 v;           // would be dropped as a template argument (std::conditional_t below)
  };
#else
  static constexpr bool kMatrixInLanes = false;
  using MatrixLanes = T;  // unused
#endif
  template <int N, bool Given>
  static void set_zxzxz_lanes(ShRotation& rotation, MatrixLanes r0, MatrixLanes r4, T r8, const ZyzCosSin<T>* e);
  using ZxzxzSet = std::conditional_t<kMatrixInLanes,
                                      void (*)(ShRotation&, MatrixLanes, MatrixLanes, T, const ZyzCosSin<T>*),
                                      void (*)(ShRotation&, const Mat3<T>&, const ZyzCosSin<T>*)>;
  void call_zxzxz_set(const Mat3<T>& r, const ZyzCosSin<T>* e) {
    const int k = e ? 1 : 0;
#if defined(__SSE2__)
    if constexpr (kMatrixInLanes) {
      zxzxz_set_[k](*this, {_mm_loadu_ps(r.data())}, {_mm_loadu_ps(r.data() + 4)}, r(2, 2), e);
      return;
    }
#endif
    if constexpr (!kMatrixInLanes) zxzxz_set_[k](*this, r, e);
  }
  // What set() resolves `method` to for r (never automatic).
  RotationMethod choose_method(const Mat3<T>& r, RotationMethod method, double tolerance);
  // rotate_batch's lane path over whole groups of lanes; returns how many rotations it
  // did (0 if it does not apply: then every pair goes through set() and apply()).
  std::size_t rotate_lanes(std::span<const Mat3<T>> rotations, const T* in, T* out, RotationMethod method,
                           double tolerance, int vectors_per_rotation);
  // e: the zyz cosines and sines of r if the caller has them (else computed from r).
  bool set_general(const Mat3<T>& r, RotationMethod method, double tolerance,
                   const ZyzCosSin<T>* e = nullptr);
  void apply_general(const T* in, T* out) const;
  [[noreturn]] void sizes_failed(std::size_t in, std::size_t out) const;
  void apply_general3(const T* in, T* out) const;  // three channels interleaved
  // apply(in, out, channels) for channel counts other than 3, and the refusals.
  bool apply_channels(std::span<const T> in, std::span<T> out, int channels) const;
  // V lanes (1, or 3 interleaved): the generated kernel of the bands below
  // first_table_band(), then the bands from it on.
  template <int V>
  void apply_lanes(const T* in, T* out) const;
  template <int V>
  void apply_kernel(const T* in, T* out) const;
  // Bands [from, to) (at or above first_table_band()); in and out point at coefficient from^2.
  template <int V>
  void apply_bands(int from, int to, const T* in, T* out) const;
  int first_table_band() const;
  template <int V>
  using Kernel = void (*)(const detail::KernelState<T>&, const T* const*, T* const*);
  void build_reference(const Mat3<T>& r);
  void build_pairs();
  void update_taylor_limits(double tolerance);

  int order_;
  std::shared_ptr<const RotationHelpers> helpers_;
  // Generated fixed-order kernels (src/runtime/kernels/rotation_kernels.h) for the bands below
  // detail::kKernelMaxOrder: zxzxz, taylor1, taylor1.5, taylor2; one and three vectors.
  Kernel<1> kernel1_[4] = {};
  // The kernel of the current rotation when it covers every band (orders <= 10, not the
  // reference method), else null.
  Kernel<1> whole_kernel_ = nullptr;
  Kernel<3> whole_kernel3_ = nullptr;
  // set_zxzxz<order, false> and <order, true> at the orders above kClosedMaxOrder whose
  // kernels cover every band (detail::kKernelMaxOrder), else null.
  ZxzxzSet zxzxz_set_[2] = {};
  // rotate_batch's lane kernels per method (zxzxz, taylor1, taylor1.5, taylor2): the
  // whole-order kernel, then one per band from detail::kKernelMaxOrder on; empty for a
  // method without lanes at this order. Looked up once, here.
  using BatchKernel = void (*)(const detail::BatchState<T>&, const T* const*, T* const*);
  std::vector<BatchKernel> batch_kernels_[4];
  Kernel<3> kernel3_[4] = {};
  int kernel_order_ = 0;  // bands [0, kernel_order_) are covered by the kernels
  // Order <= kClosedMaxOrder with the kernels: zxzxz (and the automatic choice) is
  // closed forms in R, and set() a copy of R.
  bool closed_ = false;
  // The FMA copies of the kernels (src/runtime/kernels/rotation_kernels.h), chosen once
  // for the object so that both apply()s and rotate_batch always run the same copy.
  bool fused_ = false;
  // Helpers converted to T once (float rotations must not convert in the hot loop), for
  // the bands above the kernels.
  // X90 and X90^T band by band in "strided rows": the non-zeros of a row of band l sit
  // on every other column (parity), so a row is (first column, count, values) and its
  // columns are contiguous once the input band is split into even and odd positions.
  std::vector<T> x90_val_, x90t_val_;
  std::vector<int> x90_start_, x90t_start_;  // per flat row: first column, split order
  std::vector<int> x90_band_val_, x90t_band_val_;  // offset of band l's values
  // zxzxz in double from band pair_from_ up (rotation.cpp, paired_rows): the rows of
  // X90 and X90^T that read the same column class, two at a time in one SSE2 register.
  // Per pair {first split column, row, second row} and pair_count(l) values per row,
  // interleaved row by row; per band l and matrix k (0 = X90, 1 = X90^T) the pairs
  // [pair_band_[2l + k], pair_band_[2l + k + 1]), values from pair_band_val_[2l + k].
  // pair_from_ = order_ when unused (float, or orders within the generated kernels).
  std::vector<T> pair_val_;
  std::vector<int> pair_rows_, pair_band_, pair_band_val_;
  int pair_from_ = 0;
  // Taylor derivative entries with two zeros of padding at the end, so the band loop
  // needs no bounds tests (entries that would couple two bands are zero).
  std::vector<T> dy_sub_, ddy_diag_, ddy_off2_;
  T r_[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // R column-major (bands 1 and 2 are closed forms in R)
  double ddy_offdiag_norm_ = 0.0;

  RotationMethod resolved_ = RotationMethod::reference;
  T beta_ = 0;  // tilt, for the Taylor methods
  double cached_tolerance_ = -1.0;
  // Squared sine of the largest tilt for taylor1, 1.5, 2: set() compares it with
  // R02^2 + R12^2 = sin^2 b, without a square root or an atan2.
  double taylor_limit_sin2_[3] = {0, 0, 0};
  double taylor_widest_sin2_ = 0;  // the largest of the three: one test for generic rotations
  std::vector<T> cos_a_, sin_a_, cos_b_, sin_b_, cos_g_, sin_g_;  // cos(m angle), m < N
  std::vector<T> dense_;
  // The reference recurrence's last two bands in long double (sized on its first use).
  std::vector<long double> reference_bands_;
};

}  // namespace shtool
