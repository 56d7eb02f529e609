#include "shtool/grid_product.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fftw3.h>

#include "shtool/legendre.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

// FFTW_ESTIMATE: the plan does not depend on timing, so results are byte-identical
// from run to run.
constexpr unsigned kPlanFlags = FFTW_ESTIMATE;

template <class T>
struct Fftw;
template <>
struct Fftw<double> {
  using Plan = fftw_plan;
  using Complex = fftw_complex;
  static void* alloc(std::size_t bytes) { return fftw_malloc(bytes); }
  static void release(void* p) { fftw_free(p); }
  // `howmany` transforms of length n; complex side strided (stride `cstride`, distance 1),
  // real side contiguous (distance n).
  static Plan c2r(int n, int howmany, Complex* in, int cstride, double* out) {
    return fftw_plan_many_dft_c2r(1, &n, howmany, in, nullptr, cstride, 1, out, nullptr, 1, n,
                                  kPlanFlags);
  }
  static Plan r2c(int n, int howmany, double* in, Complex* out, int cstride) {
    return fftw_plan_many_dft_r2c(1, &n, howmany, in, nullptr, 1, n, out, nullptr, cstride, 1,
                                  kPlanFlags);
  }
  static void execute(Plan p) { fftw_execute(p); }
  static void destroy(Plan p) { fftw_destroy_plan(p); }
};
template <>
struct Fftw<float> {
  using Plan = fftwf_plan;
  using Complex = fftwf_complex;
  static void* alloc(std::size_t bytes) { return fftwf_malloc(bytes); }
  static void release(void* p) { fftwf_free(p); }
  static Plan c2r(int n, int howmany, Complex* in, int cstride, float* out) {
    return fftwf_plan_many_dft_c2r(1, &n, howmany, in, nullptr, cstride, 1, out, nullptr, 1, n,
                                   kPlanFlags);
  }
  static Plan r2c(int n, int howmany, float* in, Complex* out, int cstride) {
    return fftwf_plan_many_dft_r2c(1, &n, howmany, in, nullptr, 1, n, out, nullptr, cstride, 1,
                                   kPlanFlags);
  }
  static void execute(Plan p) { fftwf_execute(p); }
  static void destroy(Plan p) { fftwf_destroy_plan(p); }
};

// Azimuthal grid size: the smallest size >= n from a list of even lengths whose FFTW_ESTIMATE
// real transforms (one c2r plus one r2c, batched over rings, float and double) were
// measured here to be cheaper than every other even 2^a 3^b 5^c length up to the next
// entry; e.g. 60 points cost 1.5-1.9x as much as 72, and 64 or 96 more than 72 or 100
// (ESTIMATE's algorithm choice, not the size, dominates). A fixed list keeps the grid,
// hence every rounding, independent of timing. Beyond the list: the smallest even
// 2^a 3^b 5^c.
int fft_friendly_even(int n) {
  static constexpr int kMeasured[] = {4,  6,  8,  10, 12,  16,  20,  32,  36,  40,
                                      48, 50, 72, 100, 120, 144, 240, 288, 320, 400};
  for (int c : kMeasured)
    if (c >= n) return c;
  for (int c = std::max(n, 2);; ++c) {
    if (c % 2) continue;
    int r = c;
    for (int p : {2, 3, 5})
      while (r % p == 0) r /= p;
    if (r == 1) return c;
  }
}

}  // namespace

template <class T>
struct GridProduct<T>::Impl {
  using F = Fftw<T>;
  using Complex = typename F::Complex;

  int order = 0;
  int inputs = 0;
  int rings = 0;   // Gauss-Legendre nodes n_t
  int pairs = 0;   // rings with x > 0; ring t and ring pairs + t are x_t and -x_t
  bool equator = false;  // n_t odd: ring 2 pairs is x = 0
  int nphi = 0;
  int ncplx = 0;   // nphi / 2 + 1

  // Synthesis: for each m, for l = m..N-1, a row of `pairs` values c_m K P_l^m(x_t),
  // c_0 = 1, c_m = 1/sqrt2 (the real basis' sqrt2 times the 1/2 of the Hermitian half
  // spectrum). syn_eq[m * N + l]: the same at x = 0.
  std::vector<T> syn;
  std::vector<std::size_t> syn_off;  // per m: start of its rows
  std::vector<T> syn_eq;
  // Projection: for each m and each ring pair t (and the equator), the rows over the
  // l of even l - m, then of odd l - m, of w_t (2 pi / nphi) sqrt2^[m>0] K P_l^m(x_t).
  std::vector<T> ana;
  std::vector<std::size_t> ana_off;  // per m: start of its block

  Complex* spec = nullptr;  // [ncplx][inputs * rings]: half spectra of the inputs per ring
  T* grid = nullptr;        // [inputs * rings][nphi]: input values on the grid
  T* prod = nullptr;        // [rings][nphi]: pointwise product
  Complex* out = nullptr;   // [ncplx][rings]: half spectra of the product per ring
  typename F::Plan c2r = nullptr, r2c = nullptr;
  std::vector<T> acc;       // 4 * max(pairs, N) accumulators

  Impl(int n, int q) : order(n), inputs(q) {
    const int degree = (q + 1) * (n - 1);
    rings = degree / 2 + 1;
    pairs = rings / 2;
    equator = rings % 2 == 1;
    nphi = fft_friendly_even(degree + 1);
    ncplx = nphi / 2 + 1;

    const GaussLegendre gl = gauss_legendre(rings);
    const long double pi = std::numbers::pi_v<long double>;
    const long double rs2 = 1.0L / std::sqrt(2.0L);
    std::vector<std::vector<long double>> leg(pairs + (equator ? 1 : 0));
    std::vector<long double> weight(leg.size());
    const long double p00 = 0.5L / std::sqrt(pi);  // K_0^0: the SH normalisation
    auto legendre_at = [&](long double z, std::vector<long double>& out) {
      out.resize(static_cast<std::size_t>(n) * (n + 1) / 2);
      normalized_legendre_all(n, z, std::sqrt((1.0L - z) * (1.0L + z)), p00, out);
    };
    for (int t = 0; t < pairs; ++t) {
      // nodes ascend; the positive ones are at the end
      legendre_at(gl.nodes[rings - 1 - t], leg[t]);
      weight[t] = gl.weights[rings - 1 - t];
    }
    if (equator) {
      legendre_at(0.0L, leg[pairs]);
      weight[pairs] = gl.weights[pairs];
    }
    auto lp = [&](int t, int l, int m) { return leg[t][static_cast<std::size_t>(l) * (l + 1) / 2 + m]; };

    syn_off.resize(n + 1);
    syn_eq.assign(static_cast<std::size_t>(n) * n, T(0));
    for (int m = 0; m < n; ++m) {
      syn_off[m] = syn.size();
      const long double c = m == 0 ? 1.0L : rs2;
      for (int l = m; l < n; ++l) {
        for (int t = 0; t < pairs; ++t) syn.push_back(static_cast<T>(c * lp(t, l, m)));
        if (equator) syn_eq[static_cast<std::size_t>(m) * n + l] = static_cast<T>(c * lp(pairs, l, m));
      }
    }
    syn_off[n] = syn.size();

    ana_off.resize(n + 1);
    const long double dphi = 2 * pi / nphi;
    for (int m = 0; m < n; ++m) {
      ana_off[m] = ana.size();
      const long double c = m == 0 ? 1.0L : std::sqrt(2.0L);
      for (int t = 0; t < static_cast<int>(leg.size()); ++t) {
        for (int parity = 0; parity < 2; ++parity)
          for (int l = m + parity; l < n; l += 2)
            ana.push_back(static_cast<T>(weight[t] * dphi * c * lp(t, l, m)));
      }
    }
    ana_off[n] = ana.size();
    acc.assign(4 * static_cast<std::size_t>(std::max(pairs, n) + 1), T(0));

    const std::size_t spec_count = static_cast<std::size_t>(ncplx) * q * rings;
    const std::size_t grid_count = static_cast<std::size_t>(q) * rings * nphi;
    spec = static_cast<Complex*>(F::alloc(sizeof(Complex) * spec_count));
    grid = static_cast<T*>(F::alloc(sizeof(T) * grid_count));
    prod = static_cast<T*>(F::alloc(sizeof(T) * static_cast<std::size_t>(rings) * nphi));
    out = static_cast<Complex*>(F::alloc(sizeof(Complex) * static_cast<std::size_t>(ncplx) * rings));
    if (!spec || !grid || !prod || !out) {
      release();
      throw std::bad_alloc();
    }
    std::memset(spec, 0, sizeof(Complex) * spec_count);
    {
      std::lock_guard<std::mutex> lock(fftw_planner_mutex());
      c2r = F::c2r(nphi, q * rings, spec, q * rings, grid);
      r2c = F::r2c(nphi, rings, prod, out, rings);
    }
    if (!c2r || !r2c) {
      release();
      throw std::runtime_error("GridProduct: FFTW could not make a plan");
    }
  }

  void release() {
    {
      std::lock_guard<std::mutex> lock(fftw_planner_mutex());
      if (c2r) F::destroy(c2r);
      if (r2c) F::destroy(r2c);
      c2r = r2c = nullptr;
    }
    F::release(spec);
    F::release(grid);
    F::release(prod);
    F::release(out);
    spec = nullptr;
    grid = nullptr;
    prod = nullptr;
    out = nullptr;
  }
  ~Impl() { release(); }

  // Half spectra of input `q` on every ring: spec[m][q rings + t] = sum_l c_m K P_l^m(x_t)
  // (f_lm - i f_l,-m); the ring at -x_t takes the same sums with (-1)^(l+m).
  void synthesize(int q, const T* f) {
    const int n = order, p = pairs, stride = inputs * rings;
    T* er = acc.data();
    T* ei = er + p;
    T* od = ei + p;
    T* oi = od + p;
    for (int m = 0; m < n; ++m) {
      std::fill(er, er + 4 * p, T(0));
      T eqr = 0, eqi = 0;
      const T* row = syn.data() + syn_off[m];
      for (int l = m; l < n; ++l, row += p) {
        const T a = f[l * (l + 1) + m];
        const T b = m > 0 ? f[l * (l + 1) - m] : T(0);
        if (((l - m) & 1) == 0) {
          for (int t = 0; t < p; ++t) {
            er[t] += row[t] * a;
            ei[t] -= row[t] * b;
          }
          if (equator) {
            const T e = syn_eq[static_cast<std::size_t>(m) * n + l];
            eqr += e * a;
            eqi -= e * b;
          }
        } else {
          for (int t = 0; t < p; ++t) {
            od[t] += row[t] * a;
            oi[t] -= row[t] * b;
          }
        }
      }
      T* s = reinterpret_cast<T*>(spec + static_cast<std::size_t>(m) * stride + q * rings);
      for (int t = 0; t < p; ++t) {
        s[2 * t] = er[t] + od[t];
        s[2 * t + 1] = ei[t] + oi[t];
        s[2 * (p + t)] = er[t] - od[t];
        s[2 * (p + t) + 1] = ei[t] - oi[t];
      }
      if (equator) {
        s[4 * p] = eqr;
        s[4 * p + 1] = eqi;
      }
    }
  }

  // Inputs to grid values, pointwise product into prod, forward transform into out.
  void product_spectrum(std::span<const std::span<const T>> f) {
    // c2r may overwrite its input: the padding m >= N is cleared every call.
    const std::size_t stride = static_cast<std::size_t>(inputs) * rings;
    std::memset(static_cast<void*>(spec + order * stride), 0,
                sizeof(Complex) * (ncplx - order) * stride);
    for (int q = 0; q < inputs; ++q) synthesize(q, f[q].data());
    F::execute(c2r);
    const std::size_t cells = static_cast<std::size_t>(rings) * nphi;
    std::copy(grid, grid + cells, prod);
    for (int q = 1; q < inputs; ++q) {
      const T* g = grid + q * cells;
      for (std::size_t i = 0; i < cells; ++i) prod[i] *= g[i];
    }
    F::execute(r2c);
  }

  // Gauss-weighted projection of the product's half spectra onto order N.
  void project(T* g) {
    const int n = order, p = pairs;
    for (int m = 0; m < n; ++m) {
      const int ne = (n - m + 1) / 2, no = (n - m) / 2;
      T* ger = acc.data();
      T* gei = ger + ne;
      T* gor = gei + ne;
      T* goi = gor + no;
      std::fill(ger, ger + 2 * (ne + no), T(0));
      const T* o = reinterpret_cast<const T*>(out + static_cast<std::size_t>(m) * rings);
      const T* row = ana.data() + ana_off[m];
      for (int t = 0; t < p; ++t, row += ne + no) {
        const T nr = o[2 * t], ni = o[2 * t + 1], sr = o[2 * (p + t)], si = o[2 * (p + t) + 1];
        const T ar = nr + sr, ai = ni + si, dr = nr - sr, di = ni - si;
        for (int j = 0; j < ne; ++j) {
          ger[j] += row[j] * ar;
          gei[j] += row[j] * ai;
        }
        const T* rowo = row + ne;
        for (int j = 0; j < no; ++j) {
          gor[j] += rowo[j] * dr;
          goi[j] += rowo[j] * di;
        }
      }
      if (equator) {  // odd l - m vanish at x = 0
        const T er = o[4 * p], ei = o[4 * p + 1];
        for (int j = 0; j < ne; ++j) {
          ger[j] += row[j] * er;
          gei[j] += row[j] * ei;
        }
      }
      // cos m p takes Re H[m], sin m p takes -Im H[m] (H = sum_j h_j e^{-i m p_j})
      for (int j = 0; j < ne; ++j) {
        const int l = m + 2 * j;
        g[l * (l + 1) + m] = ger[j];
        if (m > 0) g[l * (l + 1) - m] = -gei[j];
      }
      for (int j = 0; j < no; ++j) {
        const int l = m + 1 + 2 * j;
        g[l * (l + 1) + m] = gor[j];
        if (m > 0) g[l * (l + 1) - m] = -goi[j];
      }
    }
  }
};

template <class T>
GridProduct<T>::GridProduct(int order, int inputs) {
  if (order < 1 || order > kMaxFourierProductOrder)
    throw std::invalid_argument("GridProduct: order " + std::to_string(order) + " outside 1.." +
                                std::to_string(kMaxFourierProductOrder));
  if (inputs < 1 || inputs > kMaxProductInputs)
    throw std::invalid_argument("GridProduct: " + std::to_string(inputs) + " inputs (1.." +
                                std::to_string(kMaxProductInputs) + ")");
  impl_ = std::make_unique<Impl>(order, inputs);
}

template <class T>
GridProduct<T>::~GridProduct() = default;
template <class T>
GridProduct<T>::GridProduct(GridProduct&&) noexcept = default;
template <class T>
GridProduct<T>& GridProduct<T>::operator=(GridProduct&&) noexcept = default;

template <class T>
int GridProduct<T>::order() const {
  return impl_->order;
}
template <class T>
int GridProduct<T>::inputs() const {
  return impl_->inputs;
}
template <class T>
int GridProduct<T>::grid_theta() const {
  return impl_->rings;
}
template <class T>
int GridProduct<T>::grid_phi() const {
  return impl_->nphi;
}

template <class T>
void GridProduct<T>::multiply(std::span<const std::span<const T>> f, std::span<T> g) {
  if (static_cast<int>(f.size()) != impl_->inputs)
    throw std::invalid_argument("GridProduct: " + std::to_string(f.size()) + " inputs given, " +
                                std::to_string(impl_->inputs) + " expected");
  impl_->product_spectrum(f);
  impl_->project(g.data());
}

template <class T>
void GridProduct<T>::multiply(std::span<const T> f1, std::span<const T> f2, std::span<T> g) {
  const std::span<const T> f[2] = {f1, f2};
  multiply(std::span<const std::span<const T>>(f, 2), g);
}

template <class T>
T GridProduct<T>::integral(std::span<const std::span<const T>> f) {
  if (static_cast<int>(f.size()) != impl_->inputs + 1)
    throw std::invalid_argument("GridProduct::integral: " + std::to_string(f.size()) +
                                " functions given, " + std::to_string(impl_->inputs + 1) +
                                " expected");
  // integral (f_1 ... f_q) f_{q+1} = <P_N(f_1 ... f_q), f_{q+1}> exactly, since f_{q+1}
  // has order N: the projection of the first q is all that is needed.
  impl_->product_spectrum(f.first(impl_->inputs));
  const int count = sh_count(impl_->order);
  T* g = impl_->prod;  // free after the forward transform, and >= N^2 long
  impl_->project(g);
  T sum = 0;
  const T* last = f[impl_->inputs].data();
  for (int i = 0; i < count; ++i) sum += g[i] * last[i];
  return sum;
}

template class GridProduct<float>;
template class GridProduct<double>;

}  // namespace shtool
