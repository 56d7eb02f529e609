#include "shtool/grid_product.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "products/fftw.h"
#include "products/fft_products.h"
#include "shtool/legendre.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "precondition.h"

namespace shtool {
namespace {

using detail::Fftw;

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

// Normalized associated Legendre values K_l^m P_l^m (SH normalisation, 0 <= m <= l < N)
// at the Gauss-Legendre nodes x_t > 0 of a grid of `rings` rings, in descending order, then
// at x = 0 when `rings` is odd; long double whatever T is. The nodes -x_t follow from
// P_l^m(-x) = (-1)^(l+m) P_l^m(x).
struct PolarNodes {
  int pairs = 0;
  bool equator = false;
  std::vector<std::vector<long double>> leg;
  std::vector<long double> weight;

  PolarNodes(int order, int rings) : pairs(rings / 2), equator(rings % 2 == 1) {
    const GaussLegendre gl = gauss_legendre(rings);
    const long double p00 = 0.5L / std::sqrt(std::numbers::pi_v<long double>);  // K_0^0
    leg.resize(pairs + (equator ? 1 : 0));
    weight.resize(leg.size());
    auto legendre_at = [&](long double z, std::vector<long double>& out) {
      out.resize(static_cast<std::size_t>(order) * (order + 1) / 2);
      normalized_legendre_all(order, z, std::sqrt((1.0L - z) * (1.0L + z)), p00, out);
    };
    for (int t = 0; t < pairs; ++t) {  // nodes ascend; the positive ones are at the end
      legendre_at(gl.nodes[rings - 1 - t], leg[t]);
      weight[t] = gl.weights[rings - 1 - t];
    }
    if (equator) {
      legendre_at(0.0L, leg[pairs]);
      weight[pairs] = gl.weights[pairs];
    }
  }
  int size() const { return static_cast<int>(leg.size()); }
  long double value(int t, int l, int m) const {
    return leg[t][static_cast<std::size_t>(l) * (l + 1) / 2 + m];
  }
};

}  // namespace

// Common part of the two azimuthal methods.
template <class T>
struct GridProduct<T>::Impl {
  int order = 0;
  int inputs = 0;
  int rings = 0;  // Gauss-Legendre nodes n_t
  int nphi = 0;   // azimuthal points
  GridAzimuth azimuth = GridAzimuth::fft;
  std::vector<T> scratch;  // N^2: the projection inside integral()

  Impl(int n, int q, GridAzimuth a)
      : order(n), inputs(q), rings((q + 1) * (n - 1) / 2 + 1), azimuth(a), scratch(sh_count(n)) {}
  virtual ~Impl() = default;
  // g = the product of f[0 .. inputs - 1] projected onto order N; g may alias an input.
  virtual void multiply(const std::span<const T>* f, T* g) = 0;
};

namespace {

// Azimuthal transforms by FFTW (real transforms over all rings at once).
template <class T>
struct FftGrid final : GridProduct<T>::Impl {
  using F = Fftw<T>;
  using Complex = typename F::Complex;

  using GridProduct<T>::Impl::order;
  using GridProduct<T>::Impl::inputs;
  using GridProduct<T>::Impl::rings;
  using GridProduct<T>::Impl::nphi;
  int pairs = 0;   // rings with x > 0; ring t and ring pairs + t are x_t and -x_t
  bool equator = false;  // n_t odd: ring 2 pairs is x = 0
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

  FftGrid(int n, int q) : GridProduct<T>::Impl(n, q, GridAzimuth::fft) {
    const int degree = (q + 1) * (n - 1);
    pairs = rings / 2;
    equator = rings % 2 == 1;
    nphi = fft_friendly_even(degree + 1);
    ncplx = nphi / 2 + 1;

    const PolarNodes nodes(n, rings);
    const long double pi = std::numbers::pi_v<long double>;
    const long double rs2 = 1.0L / std::sqrt(2.0L);
    auto lp = [&](int t, int l, int m) { return nodes.value(t, l, m); };
    const std::vector<long double>& weight = nodes.weight;

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
      for (int t = 0; t < nodes.size(); ++t) {
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
      detail::allocation_failed();
    }
    std::memset(spec, 0, sizeof(Complex) * spec_count);
    {
      std::lock_guard<std::mutex> lock(detail::fftw_planner_mutex());
      c2r = F::c2r_many(nphi, q * rings, spec, q * rings, grid);
      r2c = F::r2c_many(nphi, rings, prod, out, rings);
    }
    if (!c2r || !r2c) {
      release();
      detail::dependency_failed("GridProduct: FFTW could not make a plan");
    }
  }

  void multiply(const std::span<const T>* f, T* g) override {
    product_spectrum(std::span<const std::span<const T>>(f, inputs));
    project(g);
  }

  void release() {
    {
      std::lock_guard<std::mutex> lock(detail::fftw_planner_mutex());
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
  ~FftGrid() override { release(); }

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
        detail::accumulate_scaled_complex(row, ne, ar, ai, ger, gei);
        detail::accumulate_scaled_complex(row + ne, no, dr, di, gor, goi);
      }
      if (equator) {  // odd l - m vanish at x = 0
        detail::accumulate_scaled_complex(row, ne, o[4 * p], o[4 * p + 1], ger, gei);
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

// Azimuthal transforms as direct sums over the frequencies |m| < N (the only ones the
// inputs have and the projection keeps): for a few dozen points this is cheaper than
// FFTW's batched plans, and any number of points >= D + 1 will do, so the grid takes the
// minimum. The lanes of the vectors are ring pairs, processed in chunks of up to kChunk
// vectors that run the whole pipeline independently (only the final Gauss sum adds
// across lanes), with the chunk width a template parameter so that the accumulators stay
// in registers. Everything is kept in the equatorial even/odd form: with f(+x) = E + O
// and f(-x) = E - O, a pointwise product keeps that form, (E, O) (E', O') =
// (E E' + O O', E O' + O E'), so the rings -x_t are never materialised.
template <class T>
struct DirectGrid final : GridProduct<T>::Impl {
  using GridProduct<T>::Impl::order;
  using GridProduct<T>::Impl::inputs;
  using GridProduct<T>::Impl::rings;
  using GridProduct<T>::Impl::nphi;
  // 16 bytes: one SSE2 / NEON register, the baseline of every x86-64 and arm64 build.
  typedef T V __attribute__((vector_size(16)));
  static constexpr int kWidth = static_cast<int>(sizeof(V) / sizeof(T));
  static constexpr int kChunk = 4;  // vectors per chunk: 8 accumulators, half the registers
  // Rows of V live in std::vector<T> (a vector type as a template argument loses its
  // attribute); operator new aligns them for V.
  static_assert(__STDCPP_DEFAULT_NEW_ALIGNMENT__ >= alignof(V));
  using Buffer = std::vector<T>;
  static V* vec(Buffer& b) { return reinterpret_cast<V*>(b.data()); }
  static const V* vec(const Buffer& b) { return reinterpret_cast<const V*>(b.data()); }
  static void zero(Buffer& b, std::size_t vectors) { b.assign(vectors * kWidth, T(0)); }

  int nv = 0;     // vectors per table row: ceil((pairs + equator) / kWidth)
  int half = 0;   // nphi / 2: points j = 0..half carry the cosine sums
  int sines = 0;  // (nphi - 1) / 2: points j = 1..sines carry the sine sums

  // Per (l, m), m-major (m, then l = m..N-1), nv vectors: synthesis c_m K P_l^m(x_t)
  // (c_0 = 1, c_m = sqrt2), and projection weights (2 w_t at a node pair, w_0 at the
  // equator) (2 pi / nphi) c_m K P_l^m(x_t). Padding lanes are zero.
  Buffer syn, ana;
  std::vector<std::size_t> row_of_m;  // row of (l = m, m)
  // cos(m phi_j) and sin(m phi_j) as [j][m] (synthesis) and [m][j] (projection),
  // j = 0..half; the sine is stored as 0 at j = 0 and at j = nphi / 2.
  std::vector<T> cos_jm, sin_jm, cos_mj, sin_mj;

  // Work space of one chunk (rows of kChunk vectors, the chunk uses the first NV).
  Buffer coef;     // [even a, odd a, even b, odd b][m]: cos (a) and sin (b) coefficients
  Buffer value;    // [E, O][nphi]: the input being synthesized
  Buffer product;  // [E, O][nphi]: the running product
  Buffer folded;   // [sum, difference][half + 1]: h_j + h_{-j}, h_j - h_{-j}
  Buffer spec;     // like coef: the product's azimuthal coefficients
  std::vector<T> out;  // N^2: the projection, summed over the chunks

  DirectGrid(int n, int q) : GridProduct<T>::Impl(n, q, GridAzimuth::direct) {
    nphi = (q + 1) * (n - 1) + 1;
    half = nphi / 2;
    sines = (nphi - 1) / 2;
    const PolarNodes nodes(n, rings);
    const int lanes = nodes.size();
    nv = (lanes + kWidth - 1) / kWidth;

    const long double pi = std::numbers::pi_v<long double>;
    const long double s2 = std::sqrt(2.0L);
    const long double dphi = 2 * pi / nphi;
    const std::size_t rows = static_cast<std::size_t>(n) * (n + 1) / 2;
    zero(syn, rows * nv);
    zero(ana, rows * nv);
    row_of_m.resize(n);
    std::size_t r = 0;
    for (int m = 0; m < n; ++m) {
      row_of_m[m] = r;
      const long double c = m == 0 ? 1.0L : s2;
      for (int l = m; l < n; ++l, ++r)
        for (int t = 0; t < lanes; ++t) {
          const long double k_p = c * nodes.value(t, l, m);
          const long double w = (t < nodes.pairs ? 2 : 1) * nodes.weight[t] * dphi;
          syn[r * nv * kWidth + t] = static_cast<T>(k_p);
          ana[r * nv * kWidth + t] = static_cast<T>(w * k_p);
        }
    }
    const std::size_t points = static_cast<std::size_t>(half) + 1;
    cos_jm.assign(points * n, T(0));
    sin_jm.assign(points * n, T(0));
    cos_mj.assign(points * n, T(0));
    sin_mj.assign(points * n, T(0));
    for (int j = 0; j <= half; ++j)
      for (int m = 0; m < n; ++m) {
        // m j reduced mod nphi keeps the argument, hence the value, exact to rounding
        const long double angle = dphi * static_cast<long double>((m * j) % nphi);
        const T c = static_cast<T>(std::cos(angle));
        const T sn = j >= 1 && j <= sines ? static_cast<T>(std::sin(angle)) : T(0);
        cos_jm[j * n + m] = cos_mj[m * points + j] = c;
        sin_jm[j * n + m] = sin_mj[m * points + j] = sn;
      }
    zero(coef, 4 * static_cast<std::size_t>(n) * kChunk);
    zero(spec, 4 * static_cast<std::size_t>(n) * kChunk);
    zero(value, 2 * static_cast<std::size_t>(nphi) * kChunk);
    zero(product, 2 * static_cast<std::size_t>(nphi) * kChunk);
    zero(folded, 2 * points * kChunk);
    out.assign(sh_count(n), T(0));
  }

  // Input f on the rings of lanes [c0, c0 + NV) (vectors): E into e, O into o ([nphi][NV]).
  template <int NV>
  void synthesize(const T* f, int c0, V* e, V* o) {
    const int n = order;
    V* coefs = vec(coef);
    // Legendre sums per m: a = sum_l f_lm c K P_l^m, b the same with f_l,-m
    for (int m = 0; m < n; ++m) {
      V ae[NV] = {}, ao[NV] = {}, be[NV] = {}, bo[NV] = {};
      const V* row = vec(syn) + row_of_m[m] * nv + c0;
      for (int l = m; l < n; l += 2, row += 2 * nv) {
        const T fa = f[l * (l + 1) + m], fb = m > 0 ? f[l * (l + 1) - m] : T(0);
        for (int v = 0; v < NV; ++v) {
          ae[v] += fa * row[v];
          be[v] += fb * row[v];
        }
        if (l + 1 == n) break;
        const T ga = f[(l + 1) * (l + 2) + m], gb = m > 0 ? f[(l + 1) * (l + 2) - m] : T(0);
        for (int v = 0; v < NV; ++v) {
          ao[v] += ga * row[nv + v];
          bo[v] += gb * row[nv + v];
        }
      }
      for (int v = 0; v < NV; ++v) {
        coefs[(0 * n + m) * NV + v] = ae[v];
        coefs[(1 * n + m) * NV + v] = ao[v];
        coefs[(2 * n + m) * NV + v] = be[v];
        coefs[(3 * n + m) * NV + v] = bo[v];
      }
    }
    // f(phi_j) = sum_m a_m cos(m phi_j) + b_m sin(m phi_j); phi_{-j} flips the sine sum
    for (int odd = 0; odd < 2; ++odd) {
      const V* a = coefs + odd * n * NV;
      const V* b = a + 2 * n * NV;
      V* dst = odd ? o : e;
      for (int j = 0; j <= half; ++j) {
        const T* c = cos_jm.data() + j * n;
        const T* s = sin_jm.data() + j * n;
        V cs[NV] = {}, sn[NV] = {};
        for (int m = 0; m < n; ++m)
          for (int v = 0; v < NV; ++v) {
            cs[v] += c[m] * a[m * NV + v];
            sn[v] += s[m] * b[m * NV + v];
          }
        if (j == 0 || j > sines) {
          for (int v = 0; v < NV; ++v) dst[j * NV + v] = cs[v];
        } else {
          for (int v = 0; v < NV; ++v) {
            dst[j * NV + v] = cs[v] + sn[v];
            dst[(nphi - j) * NV + v] = cs[v] - sn[v];
          }
        }
      }
    }
  }

  // Adds the Gauss-weighted projection of the running product (lanes c0..) to out.
  template <int NV>
  void project(int c0) {
    const int n = order;
    const int points = half + 1;
    const V* prod = vec(product);
    V* sum = vec(folded);
    V* diff = sum + points * NV;
    V* specs = vec(spec);
    for (int odd = 0; odd < 2; ++odd) {
      const V* h = prod + odd * nphi * NV;
      // h_j + h_{-j} and h_j - h_{-j}; the point nphi / 2 of an even grid is its own mirror
      for (int j = 0; j <= half; ++j)
        for (int v = 0; v < NV; ++v) {
          const bool mirrored = j >= 1 && j <= sines;
          sum[j * NV + v] = mirrored ? h[j * NV + v] + h[(nphi - j) * NV + v] : h[j * NV + v];
          diff[j * NV + v] = mirrored ? h[j * NV + v] - h[(nphi - j) * NV + v] : V{};
        }
      // A_m = sum_j h_j cos(m phi_j), B_m = sum_j h_j sin(m phi_j)
      V* a = specs + odd * n * NV;
      V* b = a + 2 * n * NV;
      for (int m = 0; m < n; ++m) {
        const T* c = cos_mj.data() + m * points;
        const T* s = sin_mj.data() + m * points;
        V ca[NV] = {}, sb[NV] = {};
        for (int j = 0; j <= half; ++j)
          for (int v = 0; v < NV; ++v) {
            ca[v] += c[j] * sum[j * NV + v];
            sb[v] += s[j] * diff[j * NV + v];
          }
        for (int v = 0; v < NV; ++v) {
          a[m * NV + v] = ca[v];
          b[m * NV + v] = sb[v];
        }
      }
    }
    // Gauss sums over the nodes: l - m even takes E (f(x) + f(-x)), odd takes O
    for (int m = 0; m < n; ++m) {
      const V* w = vec(ana) + row_of_m[m] * nv + c0;
      for (int l = m; l < n; ++l, w += nv) {
        const V* a = specs + (((l - m) & 1) * n + m) * NV;
        const V* b = a + 2 * n * NV;
        V sa = w[0] * a[0], sb = w[0] * b[0];
        for (int v = 1; v < NV; ++v) {
          sa += w[v] * a[v];
          sb += w[v] * b[v];
        }
        out[l * (l + 1) + m] += lane_sum(sa);
        if (m > 0) out[l * (l + 1) - m] += lane_sum(sb);
      }
    }
  }

  static T lane_sum(V x) {
    T s = x[0];
    for (int i = 1; i < kWidth; ++i) s += x[i];
    return s;
  }

  template <int NV>
  void run_chunk(const std::span<const T>* f, int c0) {
    const int cells = nphi * NV;
    V* pe = vec(product);
    V* po = pe + cells;
    synthesize<NV>(f[0].data(), c0, pe, po);
    V* e = vec(value);
    V* o = e + cells;
    for (int q = 1; q < inputs; ++q) {
      synthesize<NV>(f[q].data(), c0, e, o);
      for (int i = 0; i < cells; ++i) {
        const V even = pe[i] * e[i] + po[i] * o[i];
        po[i] = pe[i] * o[i] + po[i] * e[i];
        pe[i] = even;
      }
    }
    project<NV>(c0);
  }

  void multiply(const std::span<const T>* f, T* g) override {
    std::fill(out.begin(), out.end(), T(0));
    for (int c0 = 0; c0 < nv; c0 += kChunk) {
      switch (std::min(kChunk, nv - c0)) {
        case 1: run_chunk<1>(f, c0); break;
        case 2: run_chunk<2>(f, c0); break;
        case 3: run_chunk<3>(f, c0); break;
        default: run_chunk<4>(f, c0); break;
      }
    }
    std::copy(out.begin(), out.end(), g);  // after every input was read: g may alias one
  }
};

// The direct sums cost O(N^2 nphi rings), the FFT O(rings nphi log nphi) plus a fixed
// overhead per batched plan. Measured (bench_products, BM_GridAzimuth, N <= 20, k <= 8):
// in float the direct sums are faster everywhere (1.1-4x); in double, where FFTW's codelets
// use twice our vector width (AVX against SSE2), up to N = 11 only.
template <class T>
constexpr int kDirectAzimuthMaxOrder = std::is_same_v<T, float> ? 20 : 11;

}  // namespace

template <class T>
GridProduct<T>::GridProduct(int order, int inputs, GridAzimuth azimuth) {
  detail::check_product_sizes("GridProduct", order, inputs);
  if (azimuth == GridAzimuth::automatic)
    azimuth = order <= kDirectAzimuthMaxOrder<T> ? GridAzimuth::direct : GridAzimuth::fft;
  Impl* impl = nullptr;
  if (azimuth == GridAzimuth::direct)
    impl = new DirectGrid<T>(order, inputs);
  else
    impl = new FftGrid<T>(order, inputs);
  impl_ = detail::ImplPtr<Impl>(impl, detail::delete_impl<Impl>);
  set_sizes(impl->order, impl->inputs, impl->rings, impl->nphi);
}

template <class T>
GridAzimuth GridProduct<T>::azimuth() const {
  return impl_->azimuth;
}

template <class T>
void GridProduct<T>::multiply(std::span<const std::span<const T>> f, std::span<T> g) {
  if (static_cast<int>(f.size()) != impl_->inputs)
    detail::precondition_failed("GridProduct: " + std::to_string(f.size()) + " inputs given, " +
                                std::to_string(impl_->inputs) + " expected");
  const std::size_t n = static_cast<std::size_t>(sh_count(order()));
  for (const std::span<const T>& fi : f) detail::check_span_size("GridProduct::multiply", "an input", fi.size(), n);
  detail::check_span_size("GridProduct::multiply", "g", g.size(), n);
  impl_->multiply(f.data(), g.data());
}

template <class T>
void GridProduct<T>::multiply(std::span<const T> f1, std::span<const T> f2, std::span<T> g) {
  const std::span<const T> f[2] = {f1, f2};
  multiply(std::span<const std::span<const T>>(f, 2), g);
}

template <class T>
T GridProduct<T>::integral(std::span<const std::span<const T>> f) {
  if (static_cast<int>(f.size()) != impl_->inputs + 1)
    detail::precondition_failed("GridProduct::integral: " + std::to_string(f.size()) +
                                " functions given, " + std::to_string(impl_->inputs + 1) +
                                " expected");
  const std::size_t n = static_cast<std::size_t>(sh_count(impl_->order));
  for (const std::span<const T>& fi : f) detail::check_span_size("GridProduct::integral", "a function", fi.size(), n);
  // integral (f_1 ... f_q) f_{q+1} = <P_N(f_1 ... f_q), f_{q+1}> exactly, since f_{q+1}
  // has order N: the projection of the first q is all that is needed.
  T* g = impl_->scratch.data();
  impl_->multiply(f.data(), g);
  T sum = 0;
  const T* last = f[impl_->inputs].data();
  for (int i = 0; i < sh_count(impl_->order); ++i) sum += g[i] * last[i];
  return sum;
}

template class GridProduct<float>;
template class GridProduct<double>;

}  // namespace shtool
