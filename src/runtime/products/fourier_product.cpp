#include "shtool/fourier_product.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "products/fftw.h"
#include "products/fft_products.h"
#include "shtool/fourier_tensors.h"
#include "shtool/sh.h"
#include "precondition.h"

namespace shtool {

namespace detail {
std::mutex& fftw_planner_mutex() {
  static std::mutex m;
  return m;
}
}  // namespace detail

namespace {

using detail::Fftw;
template <class T, class E>
using AlignedBuffer = detail::FftwBuffer<T, E>;

// Smallest m >= need whose prime factors are 2, 3 and 5 (FFTW's fastest sizes), even
// if asked (the halved real dimension).
int fft_size(int need, bool even) {
  for (int m = std::max(need, 1);; ++m) {
    if (even && m % 2 != 0) continue;
    int r = m;
    for (int p : {2, 3, 5})
      while (r % p == 0) r /= p;
    if (r == 1) return m;
  }
}

// Size of the complex (phi) dimension: the smallest 2^a or 3 * 2^a >= need. With
// FFTW_ESTIMATE plans, 2D transforms whose complex dimension is a power of two ran
// 1.5-3x faster here than with factors 5 or 9 (e.g. 80x64 vs 80x60, 40x32 vs 40x30).
int fft_size_phi(int need) {
  int best = 1;
  while (best < need) best *= 2;
  for (int m = 3; m < best; m *= 2)
    if (m >= need) return m;
  return best;
}

}  // namespace

template <class T>
struct FourierProduct<T>::Impl {
  using F = Fftw<T>;
  using C = typename F::Complex;

  int n = 0;       // order
  int inputs = 0;  // k - 1

  // Compact SH -> Fourier weights (Eq. 17): for every t = |m| and band l >= t, the
  // coefficients of frequencies s = l%2, l%2 + 2, ..., l, scaled so that they give the
  // complex 2D coefficients directly (docs/products.md, "SH to Fourier").
  std::vector<T> to_fourier;
  std::vector<std::size_t> to_fourier_start;  // index t * n + l
  // Compact Fourier -> SH weights (Eq. 29) for the top node: for every t and parity p,
  // a [frequency][band] matrix over s = p, p + 2, ..., <= D and l >= t with l % 2 = p,
  // including the 1 / (M_theta M_phi) of the inverse FFT.
  std::vector<T> to_sh;
  std::vector<std::size_t> to_sh_start;  // index 2 * t + p

  struct Node {
    int first = 0, count = 1;  // inputs [first, first + count)
    int degree = 0;            // count * (n - 1)
    int left = -1, right = -1;
    bool top = false;
    int m_theta = 0, m_phi = 0, half = 0;  // grid, half = m_theta / 2 + 1
    typename F::Plan c2r = nullptr, r2c = nullptr;
    AlignedBuffer<T, C> spec_a, spec_b;
    AlignedBuffer<T, T> grid_a, grid_b;
    std::vector<std::complex<T>> coeff;  // non-top: rows t = -D..D, columns s = 0..D
  };
  std::vector<Node> nodes;  // nodes[0] is the root

  // Scratch for the conversions (sized once).
  std::vector<T> acc_p, acc_m;

  Impl(int order, int count) : n(order), inputs(count) {
    detail::check_product_sizes("FourierProduct", order, count);
    nodes.reserve(2 * count);
    build_node(0, count, true);
    const int degree = std::max(nodes[0].degree, n - 1);
    const ShFourierTensors tensors = ShFourierTensors::compute(n, degree);
    build_to_fourier(tensors);
    if (nodes[0].left >= 0) build_to_sh(tensors, nodes[0]);
    const int width = std::max(2 * ((n + 1) / 2), degree + 1);
    acc_p.assign(width, 0);
    acc_m.assign(width, 0);
  }

  ~Impl() {
    std::lock_guard<std::mutex> lock(detail::fftw_planner_mutex());
    for (Node& node : nodes) {
      if (node.c2r) F::destroy(node.c2r);
      if (node.r2c) F::destroy(node.r2c);
    }
  }

  // Divide and conquer (Eq. 27): a node multiplies the products of its two halves.
  int build_node(int first, int count, bool top) {
    const int id = static_cast<int>(nodes.size());
    nodes.emplace_back();
    nodes[id].first = first;
    nodes[id].count = count;
    nodes[id].degree = count * (n - 1);
    nodes[id].top = top;
    if (count == 1) return id;
    const int left_count = (count + 1) / 2;
    const int left = build_node(first, left_count, false);
    const int right = build_node(first + left_count, count - left_count, false);
    Node& node = nodes[id];
    node.left = left;
    node.right = right;
    const int d = node.degree;
    // Every theta frequency |s| <= D of the product is needed (Eq. 29 sums over all of
    // them), so M_theta > 2D. In phi only |t| <= n - 1 is needed at the top, so there
    // M_phi > D + n - 1 is enough (aliases of |t| <= D land outside); below the top the
    // whole product is passed up, so M_phi > 2D.
    node.m_theta = fft_size(2 * d + 1, true);
    node.m_phi = fft_size_phi(top ? d + n : 2 * d + 1);
    node.half = node.m_theta / 2 + 1;
    const std::size_t spec = static_cast<std::size_t>(node.m_phi) * node.half;
    const std::size_t grid = static_cast<std::size_t>(node.m_phi) * node.m_theta;
    node.spec_a = AlignedBuffer<T, C>(spec);
    node.spec_b = AlignedBuffer<T, C>(spec);
    node.grid_a = AlignedBuffer<T, T>(grid);
    node.grid_b = AlignedBuffer<T, T>(grid);
    {
      std::lock_guard<std::mutex> lock(detail::fftw_planner_mutex());
      node.c2r = F::c2r_2d(node.m_phi, node.m_theta, node.spec_a.data(), node.grid_a.data());
      node.r2c = F::r2c_2d(node.m_phi, node.m_theta, node.grid_a.data(), node.spec_a.data());
    }
    if (!node.c2r || !node.r2c) detail::dependency_failed("FourierProduct: FFTW planning failed");
    if (!top) node.coeff.assign(static_cast<std::size_t>(2 * d + 1) * (d + 1), {});
    return id;
  }

  void build_to_fourier(const ShFourierTensors& tensors) {
    const long double pi = std::numbers::pi_v<long double>;
    to_fourier_start.assign(static_cast<std::size_t>(n) * n + 1, 0);
    to_fourier.clear();
    for (int t = 0; t < n; ++t)
      for (int l = 0; l < n; ++l) {
        to_fourier_start[t * n + l] = to_fourier.size();
        if (l < t) continue;
        for (int s = l % 2; s <= l; s += 2) {
          // Complex coefficient of e^{i(s th + t ph)}: t = 0 carries 1/sqrt(2 pi), t > 0
          // carries 1/(2 sqrt(pi)) from cos and sin; one-sided s > 0 halves once more.
          long double scale = (t == 0) ? 1.0L / std::sqrt(2 * pi) : 1.0L / (2 * std::sqrt(pi));
          if (s > 0) scale /= 2;
          to_fourier.push_back(static_cast<T>(scale * tensors.fourier(l, t, s)));
        }
      }
    to_fourier_start[static_cast<std::size_t>(n) * n] = to_fourier.size();
  }

  void build_to_sh(const ShFourierTensors& tensors, const Node& top) {
    const long double pi = std::numbers::pi_v<long double>;
    const long double norm = 1.0L / (static_cast<long double>(top.m_theta) * top.m_phi);
    const int d = top.degree;
    to_sh_start.assign(2 * n + 1, 0);
    to_sh.clear();
    for (int t = 0; t < n; ++t)
      for (int p = 0; p < 2; ++p) {
        to_sh_start[2 * t + p] = to_sh.size();
        for (int s = p; s <= d; s += 2)
          for (int l = t; l < n; ++l) {
            if (l % 2 != p) continue;  // to_sh vanishes unless s = l (mod 2)
            // sqrt(2 pi) (t = 0) or 2 sqrt(pi) (t > 0) from the phi integral, 2 for the
            // two-sided s > 0 terms, and the inverse-FFT normalisation.
            long double scale = (t == 0) ? std::sqrt(2 * pi) : 2 * std::sqrt(pi);
            if (s > 0) scale *= 2;
            to_sh.push_back(static_cast<T>(scale * norm * tensors.projection(l, t, s)));
          }
      }
    to_sh_start[2 * n] = to_sh.size();
  }

  // Writes the Fourier coefficients of one SH input into a half spectrum (rows = phi
  // frequency t mod M_phi, columns = theta frequency s >= 0). Zeroes it first.
  void sh_to_spectrum(const T* f, Node& node, C* spec) {
    std::memset(static_cast<void*>(spec), 0,
                sizeof(C) * static_cast<std::size_t>(node.m_phi) * node.half);
    for (int t = 0; t < n; ++t) {
      // P: cos/sin series of F_t = sum_l f_{l,t} Theta_l^t; M: same with f_{l,-t}.
      // Kept by parity class (s = 2j + p) so the inner loops are contiguous.
      T* pe = acc_p.data();
      T* me = acc_m.data();
      std::fill(acc_p.begin(), acc_p.begin() + 2 * ((n + 1) / 2), T(0));
      std::fill(acc_m.begin(), acc_m.begin() + 2 * ((n + 1) / 2), T(0));
      for (int l = t; l < n; ++l) {
        const T fp = f[sh_index(l, t)];
        const T fm = f[sh_index(l, -t)];
        const T* w = to_fourier.data() + to_fourier_start[t * n + l];
        const int len = static_cast<int>(to_fourier_start[t * n + l + 1] - to_fourier_start[t * n + l]);
        T* pp = pe + (l % 2) * ((n + 1) / 2);
        T* mm = me + (l % 2) * ((n + 1) / 2);
        for (int j = 0; j < len; ++j) {
          pp[j] += fp * w[j];
          mm[j] += fm * w[j];
        }
      }
      T* row_pos = reinterpret_cast<T*>(spec + static_cast<std::size_t>(t) * node.half);
      T* row_neg = reinterpret_cast<T*>(
          spec + static_cast<std::size_t>((node.m_phi - t) % node.m_phi) * node.half);
      for (int s = 0; s < n; ++s) {
        const T P = pe[(s % 2) * ((n + 1) / 2) + s / 2];
        const T M = me[(s % 2) * ((n + 1) / 2) + s / 2];
        if (t == 0) {
          row_pos[2 * s] = P;
        } else if (t % 2 == 0) {  // cosine series in theta
          row_pos[2 * s] = P;
          row_pos[2 * s + 1] = -M;
          row_neg[2 * s] = P;
          row_neg[2 * s + 1] = M;
        } else {  // sine series in theta
          row_pos[2 * s] = -M;
          row_pos[2 * s + 1] = -P;
          row_neg[2 * s] = M;
          row_neg[2 * s + 1] = -P;
        }
      }
    }
  }

  // Eq. 29: SH coefficients of order n from the product's half spectrum (top node).
  void spectrum_to_sh(const Node& node, const C* spec, T* g) {
    const int d = node.degree;
    for (int t = 0; t < n; ++t) {
      const T* row = reinterpret_cast<const T*>(spec + static_cast<std::size_t>(t) * node.half);
      for (int p = 0; p < 2; ++p) {
        // Bands l >= t with l % 2 = p, in order.
        const int l0 = t + ((t % 2 == p) ? 0 : 1);
        if (l0 >= n) continue;
        const int count_l = (n - 1 - l0) / 2 + 1;
        T* are = acc_p.data();
        T* aim = acc_m.data();
        std::fill(are, are + count_l, T(0));
        std::fill(aim, aim + count_l, T(0));
        const T* w = to_sh.data() + to_sh_start[2 * t + p];
        for (int s = p; s <= d; s += 2, w += count_l) {
          detail::accumulate_scaled_complex(w, count_l, row[2 * s], row[2 * s + 1], are, aim);
        }
        for (int j = 0; j < count_l; ++j) {
          const int l = l0 + 2 * j;
          if (t == 0) {
            g[sh_index(l, 0)] = are[j];
          } else if (t % 2 == 0) {
            g[sh_index(l, t)] = are[j];
            g[sh_index(l, -t)] = -aim[j];
          } else {
            g[sh_index(l, t)] = -aim[j];
            g[sh_index(l, -t)] = -are[j];
          }
        }
      }
    }
  }

  // Fills `spec` (the grid of `parent`) with the Fourier coefficients of child `id`.
  void child_spectrum(int id, const T* const* f, Node& parent, C* spec) {
    Node& child = nodes[id];
    if (child.left < 0) {
      sh_to_spectrum(f[child.first], parent, spec);
      return;
    }
    run_node(id, f, nullptr);
    std::memset(static_cast<void*>(spec), 0,
                sizeof(C) * static_cast<std::size_t>(parent.m_phi) * parent.half);
    const int d = child.degree;
    for (int t = -d; t <= d; ++t) {
      const int r = ((t % parent.m_phi) + parent.m_phi) % parent.m_phi;
      std::memcpy(static_cast<void*>(spec + static_cast<std::size_t>(r) * parent.half),
                  child.coeff.data() + static_cast<std::size_t>(t + d) * (d + 1),
                  sizeof(C) * (d + 1));
    }
  }

  void run_node(int id, const T* const* f, T* g) {
    Node& node = nodes[id];
    child_spectrum(node.left, f, node, node.spec_a.data());
    child_spectrum(node.right, f, node, node.spec_b.data());
    F::run_c2r(node.c2r, node.spec_a.data(), node.grid_a.data());
    F::run_c2r(node.c2r, node.spec_b.data(), node.grid_b.data());
    // Pointwise product of the two band-limited functions on the torus grid = the 2D
    // convolution of their Fourier coefficients (Eq. 23-24), without aliasing.
    T* a = node.grid_a.data();
    const T* b = node.grid_b.data();
    const std::size_t size = static_cast<std::size_t>(node.m_phi) * node.m_theta;
    for (std::size_t i = 0; i < size; ++i) a[i] *= b[i];
    F::run_r2c(node.r2c, node.grid_a.data(), node.spec_a.data());
    if (node.top) {
      spectrum_to_sh(node, node.spec_a.data(), g);
      return;
    }
    const int d = node.degree;
    const T norm = static_cast<T>(1.0L / (static_cast<long double>(node.m_theta) * node.m_phi));
    for (int t = -d; t <= d; ++t) {
      const int r = ((t % node.m_phi) + node.m_phi) % node.m_phi;
      const T* row = reinterpret_cast<const T*>(node.spec_a.data() + static_cast<std::size_t>(r) * node.half);
      std::complex<T>* out = node.coeff.data() + static_cast<std::size_t>(t + d) * (d + 1);
      for (int s = 0; s <= d; ++s) out[s] = {row[2 * s] * norm, row[2 * s + 1] * norm};
    }
  }

  void multiply(const T* const* f, T* g) {
    if (nodes[0].left < 0) {  // a single input: the product is the input itself
      std::memmove(g, f[0], sizeof(T) * sh_count(n));
      return;
    }
    run_node(0, f, g);
  }
};

template <class T>
FourierProduct<T>::FourierProduct(int order, int inputs) : impl_(new Impl(order, inputs), detail::delete_impl<Impl>) {
  set_sizes(impl_->n, impl_->inputs, impl_->nodes[0].m_theta, impl_->nodes[0].m_phi);
}

template <class T>
void FourierProduct<T>::multiply(std::span<const std::span<const T>> f, std::span<T> g) {
  if (static_cast<int>(f.size()) != impl_->inputs)
    detail::precondition_failed("FourierProduct: " + std::to_string(f.size()) + " inputs given, " +
                                std::to_string(impl_->inputs) + " expected");
  const std::size_t n = static_cast<std::size_t>(sh_count(order()));
  const T* ptrs[kMaxProductInputs];
  for (int i = 0; i < impl_->inputs; ++i) {
    detail::check_span_size("FourierProduct::multiply", "an input", f[i].size(), n);
    ptrs[i] = f[i].data();
  }
  detail::check_span_size("FourierProduct::multiply", "g", g.size(), n);
  impl_->multiply(ptrs, g.data());
}

template <class T>
void FourierProduct<T>::multiply(std::span<const T> f1, std::span<const T> f2, std::span<T> g) {
  const std::span<const T> f[2] = {f1, f2};
  multiply(std::span<const std::span<const T>>(f, 2), g);
}

template class FourierProduct<float>;
template class FourierProduct<double>;

}  // namespace shtool
