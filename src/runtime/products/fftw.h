// Internal to the runtime: the one FFTW binding of the Fourier and grid products (float
// and double through one traits type), the planner lock and FFTW-aligned buffers. FFTW
// stays inside the library: no public header names it.
#pragma once

#include <cstddef>
#include <cstring>
#include <mutex>
#include <new>
#include <utility>

#include <fftw3.h>

#include "precondition.h"

namespace shtool::detail {

// FFTW_ESTIMATE: the plan does not depend on timing (FFTW_MEASURE would pick algorithms
// by timing), so the same inputs give byte-identical results from run to run.
inline constexpr unsigned kFftwPlanFlags = FFTW_ESTIMATE;

// FFTW's planner is not thread-safe (execution of distinct plans is): every plan the
// runtime makes or destroys is made under this one lock.
std::mutex& fftw_planner_mutex();

template <class T>
struct Fftw;

// One specialisation per FFTW precision, its functions named by FFTW's own prefix (fftw_,
// fftwf_), the way fftw3.h declares them (FFTW_DEFINE_API): the two stay the same binding.
//   c2r_2d, r2c_2d: 2D real transforms (Fourier products).
//   c2r_many, r2c_many: `howmany` 1D transforms of length n; complex side strided (stride
//   `cstride`, distance 1), real side contiguous (distance n) (grid products).
#define SHTOOL_FFTW_TRAITS(X, R)                                                                        \
  template <>                                                                                           \
  struct Fftw<R> {                                                                                      \
    using Plan = X##plan;                                                                               \
    using Complex = X##complex;                                                                         \
    static void* alloc(std::size_t bytes) { return X##malloc(bytes); }                                  \
    static void release(void* p) { X##free(p); }                                                        \
    static Plan c2r_2d(int n0, int n1, Complex* in, R* out) {                                           \
      return X##plan_dft_c2r_2d(n0, n1, in, out, kFftwPlanFlags);                                       \
    }                                                                                                   \
    static Plan r2c_2d(int n0, int n1, R* in, Complex* out) {                                           \
      return X##plan_dft_r2c_2d(n0, n1, in, out, kFftwPlanFlags);                                       \
    }                                                                                                   \
    static void run_c2r(Plan p, Complex* in, R* out) { X##execute_dft_c2r(p, in, out); }                \
    static void run_r2c(Plan p, R* in, Complex* out) { X##execute_dft_r2c(p, in, out); }                \
    static Plan c2r_many(int n, int howmany, Complex* in, int cstride, R* out) {                        \
      return X##plan_many_dft_c2r(1, &n, howmany, in, nullptr, cstride, 1, out, nullptr, 1, n, kFftwPlanFlags); \
    }                                                                                                   \
    static Plan r2c_many(int n, int howmany, R* in, Complex* out, int cstride) {                        \
      return X##plan_many_dft_r2c(1, &n, howmany, in, nullptr, 1, n, out, nullptr, cstride, 1, kFftwPlanFlags); \
    }                                                                                                   \
    static void execute(Plan p) { X##execute(p); }                                                      \
    static void destroy(Plan p) { X##destroy_plan(p); }                                                 \
  };

SHTOOL_FFTW_TRAITS(fftw_, double)
SHTOOL_FFTW_TRAITS(fftwf_, float)
#undef SHTOOL_FFTW_TRAITS

// Zero-initialised buffer from fftw_malloc: SIMD-aligned, and equally aligned for every
// buffer, which the new-array execute interface requires.
template <class T, class E>
class FftwBuffer {
 public:
  FftwBuffer() = default;
  explicit FftwBuffer(std::size_t count) : size_(count) {
    data_ = static_cast<E*>(Fftw<T>::alloc(count * sizeof(E)));
    if (!data_) detail::allocation_failed();
    zero();
  }
  ~FftwBuffer() {
    if (data_) Fftw<T>::release(data_);
  }
  FftwBuffer(FftwBuffer&& o) noexcept : data_(o.data_), size_(o.size_) {
    o.data_ = nullptr;
    o.size_ = 0;
  }
  FftwBuffer& operator=(FftwBuffer&& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    return *this;
  }
  FftwBuffer(const FftwBuffer&) = delete;
  FftwBuffer& operator=(const FftwBuffer&) = delete;
  E* data() const { return data_; }
  std::size_t size() const { return size_; }
  void zero() {
    if (size_) std::memset(static_cast<void*>(data_), 0, size_ * sizeof(E));
  }

 private:
  E* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace shtool::detail
