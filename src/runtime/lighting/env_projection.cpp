#include "shtool/env_projection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <utility>

#include "basis/legendre_recurrence.h"
#include "shtool/legendre.h"
#include "shtool/orthogonal_map.h"
#include "shtool/quadrature.h"
#include "precondition.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr long double kPiL = std::numbers::pi_v<long double>;

std::size_t legendre_count(int order) { return static_cast<std::size_t>(order) * (order + 1) / 2; }
std::size_t legendre_index(int l, int m) { return static_cast<std::size_t>(l) * (l + 1) / 2 + m; }

Error order_error(int order) {
  return Error{"order " + std::to_string(order) + " is outside 1.." + std::to_string(kMaxEnvOrder)};
}

// Fourier coefficients of f_l^m(t) = K_l^m P_l^m(cos t) sin t, a trigonometric
// polynomial of degree l+1: a sine series for even m, a cosine series for odd m (P_l^m
// is sin^m t times a polynomial in cos t). coeffs[legendre_index(l, m) * (N+1) + k] is the
// factor of sin(k t) (m even) or cos(k t) (m odd). Found exactly by a DFT of 2N+4
// samples over a whole period, where the recurrence continues the polynomial in
// (cos t, sin t) to sin t < 0.
std::vector<long double> legendre_fourier_coefficients(int order) {
  const int samples = 2 * order + 4;
  const std::size_t count = legendre_count(order);
  std::vector<long double> values(static_cast<std::size_t>(samples) * count);
  std::vector<long double> p(count);
  for (int j = 0; j < samples; ++j) {
    const long double t = 2 * kPiL * j / samples;
    const long double s = std::sin(t);
    normalized_legendre_all(order, std::cos(t), s, 1 / std::sqrt(4 * kPiL), p);
    for (std::size_t i = 0; i < count; ++i) values[j * count + i] = p[i] * s;
  }
  // k t_j is 2 pi ((k j) mod samples) / samples: one table of the samples' sines and cosines.
  std::vector<long double> sines(samples), cosines(samples);
  for (int j = 0; j < samples; ++j) {
    sines[j] = std::sin(2 * kPiL * j / samples);
    cosines[j] = std::cos(2 * kPiL * j / samples);
  }
  std::vector<long double> coeffs(count * (order + 1), 0.0L);
  for (int l = 0; l < order; ++l) {
    for (int m = 0; m <= l; ++m) {
      const std::size_t i = legendre_index(l, m);
      const std::vector<long double>& basis = m % 2 == 0 ? sines : cosines;
      for (int k = 0; k <= l + 1; ++k) {
        long double sum = 0;
        for (int j = 0; j < samples; ++j) sum += values[j * count + i] * basis[(k * j) % samples];
        coeffs[i * (order + 1) + k] = sum * (k == 0 ? 1 : 2) / samples;
      }
    }
  }
  return coeffs;
}

// Index of the azimuthal sum that multiplies coefficient (l, m): 0 for m = 0, 2m-1 for
// the cosines (m > 0), 2|m| for the sines (m < 0).
int azimuth_slot(int m) { return m == 0 ? 0 : (m > 0 ? 2 * m - 1 : -2 * m); }

Error non_finite_error(const char* where, int x, int y, int c, float v) {
  return Error{std::string(where) + "texel (" + std::to_string(x) + ", " + std::to_string(y) + ") channel " +
               std::to_string(c) + " is " + (std::isnan(v) ? "NaN" : "infinite")};
}

}  // namespace

Result<EquirectProjector> EquirectProjector::create(int width, int height, int order) {
  if (order < 1 || order > kMaxEnvOrder) return order_error(order);
  if (height < 1 || width != 2 * height)
    return Error{"an equirect image must be 2:1 (width = 2 height), got " + std::to_string(width) + " x " +
                 std::to_string(height)};
  EquirectProjector p;
  p.width_ = width;
  p.height_ = height;
  p.order_ = order;
  const int slots = 2 * order - 1;
  // The left half: the right half mirrors it (row_sums).
  p.column_weights_.resize(static_cast<std::size_t>(width / 2) * slots);
  const long double half = kPiL / width;  // half a column's width in p
  const std::size_t pairs = static_cast<std::size_t>(width / 2);
  for (std::size_t x = 0; x < pairs; ++x) {
    // The integrals of cos(m p), sin(m p) over [c - h, c + h] are 2 cos(m c) sin(m h) / m
    // and 2 sin(m c) sin(m h) / m: no cancellation for thin columns.
    const long double centre = kPiL - 2 * kPiL * (x + 0.5L) / width;
    p.column_weights_[x] = static_cast<double>(2 * half);
    for (int m = 1; m < order; ++m) {
      const long double f = std::numbers::sqrt2_v<long double> * 2 * std::sin(m * half) / m;
      p.column_weights_[(2 * m - 1) * pairs + x] = static_cast<double>(f * std::cos(m * centre));
      p.column_weights_[(2 * m) * pairs + x] = static_cast<double>(f * std::sin(m * centre));
    }
  }
  const std::vector<long double> fourier = legendre_fourier_coefficients(order);
  const std::size_t count = legendre_count(order);
  p.row_integrals_.resize(static_cast<std::size_t>(height) * count);
  std::vector<long double> moment_sin(order + 2), moment_cos(order + 2), width_factor(order + 2);
  const long double h = kPiL / (2 * height);  // half a row's height in t
  for (int k = 1; k <= order; ++k) width_factor[k] = 2 * std::sin(k * h) / k;
  for (int y = 0; y < height; ++y) {
    const long double centre = kPiL * (y + 0.5L) / height;
    const long double s1 = std::sin(centre), c1 = std::cos(centre);
    moment_cos[0] = 2 * h;
    moment_sin[0] = 0;
    // sin(k c), cos(k c) by the angle-addition recurrence: k roundings of long double,
    // far below what the double results keep.
    long double sk = 0, ck = 1;
    for (int k = 1; k <= order; ++k) {
      const long double next_s = sk * c1 + ck * s1, next_c = ck * c1 - sk * s1;
      sk = next_s, ck = next_c;
      moment_sin[k] = width_factor[k] * sk;
      moment_cos[k] = width_factor[k] * ck;
    }
    for (int l = 0; l < order; ++l) {
      for (int m = 0; m <= l; ++m) {
        const std::size_t i = legendre_index(l, m);
        const long double* a = &fourier[i * (order + 1)];
        const std::vector<long double>& moment = m % 2 == 0 ? moment_sin : moment_cos;
        long double sum = 0;
        for (int k = 0; k <= l + 1; ++k) sum += a[k] * moment[k];
        p.row_integrals_[static_cast<std::size_t>(y) * count + i] = static_cast<double>(sum);
      }
    }
  }
  return p;
}

std::size_t EquirectProjector::partial_size(int channels) const {
  return static_cast<std::size_t>(sh_count(order_)) * channels;
}

std::span<const double> EquirectProjector::row_integrals(int y) const {
  const std::size_t count = legendre_count(order_);
  return std::span<const double>(row_integrals_).subspan(static_cast<std::size_t>(y) * count, count);
}

namespace {

// Built twice on x86-64 with GCC, for the baseline and for x86-64-v3 (AVX2), picked at
// load time. The runtime is compiled with -ffp-contract=off, so the v3 copy fuses
// nothing: both copies make the same operations in the same order per lane and return
// the same bits; only the vector width differs.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define SHTOOL_SAME_BITS_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
// The cube face rule and class sums also run 8 lanes wide (AVX-512), same bits again.
#define SHTOOL_SAME_BITS_CLONES_WIDE __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define SHTOOL_SAME_BITS_CLONES
#define SHTOOL_SAME_BITS_CLONES_WIDE
#endif

// sum_x w[x] v[x] in four lanes (x mod 4), each summed in runs of 16 terms before its
// running total: the rounding error grows with 16 + n / 64 rather than n (a uniform
// 4096-wide row stays within a few ulps). The lanes are what the vector units run.
SHTOOL_SAME_BITS_CLONES double lane_dot(const double* w, const double* v, int n) {
  double total[4] = {0, 0, 0, 0};
  int x = 0;
  for (; x + 64 <= n; x += 64) {
    double acc[4] = {0, 0, 0, 0};
    for (int j = 0; j < 64; j += 4)
      for (int l = 0; l < 4; ++l) acc[l] += w[x + j + l] * v[x + j + l];
    for (int l = 0; l < 4; ++l) total[l] += acc[l];
  }
  double acc[4] = {0, 0, 0, 0};
  for (; x < n; ++x) acc[x % 4] += w[x] * v[x];
  for (int l = 0; l < 4; ++l) total[l] += acc[l];
  return (total[0] + total[1]) + (total[2] + total[3]);
}

}  // namespace

namespace {

bool valid_view(const FloatImageView& v, int width, int height) {
  return v.texels && v.width == width && v.height == height && v.channels >= 1 && v.channels <= 4 &&
         v.stride() >= static_cast<std::size_t>(width) * v.channels;
}

}  // namespace

Result<Ok> EquirectProjector::accumulate_block(const FloatImageView& image, int block,
                                               std::span<double> partial) const {
  if (!valid_view(image, width_, height_) || block < 0 || block >= block_count() ||
      partial.size() < partial_size(image.channels))
    return Error{"equirect block: the image must be the projector's size with 1..4 channels, the block in range "
                 "and the partial of partial_size(channels) values"};
  const int channels = image.channels;
  const int slots = 2 * order_ - 1;
  const int pairs = width_ / 2;
  // Columns x and W-1-x are mirror images (p -> -p): their cosine weights are equal and
  // their sine weights opposite, so the pair's sum a + b meets the cosine weights and its
  // difference a - b the sine weights. When W/2 is even, the pairs x and W/2-1-x fold
  // once more (p -> pi - p: cos(m p) and sin(m p) change sign with the parity of m, of
  // m + 1): the sums of each fold meet even m, the differences odd m, and every azimuthal
  // sum is a lane_dot over W/4 values instead of W, with a row of weights. Per channel,
  // the folded values are planar: one scratch allocation per block of rows.
  constexpr int kSecondFoldOrder = 8;
  // The second fold costs a pass of its own: it pays from order 8 on (measured).
  const bool twice = pairs % 2 == 0 && order_ >= kSecondFoldOrder;
  const int n = twice ? pairs / 2 : pairs;
  // twice: s+, s-, d+, d-; else s, -, d, -. Left uninitialised (every value used is
  // written first): zero-filling them cost a tenth of a projection at order 3.
  std::array<std::unique_ptr<double[]>, 4> folded;
  for (int f = 0; f < 4; ++f)
    if (twice || f % 2 == 0) folded[f].reset(new double[static_cast<std::size_t>(channels) * n]);
  std::array<double, 4 * (2 * kMaxEnvOrder - 1)> sums;
  const int y_end = std::min(height_, (block + 1) * kRowsPerBlock);
  for (int y = block * kRowsPerBlock; y < y_end; ++y) {
    const float* row = image.row(y);
    auto texel = [&](int x) { return row + static_cast<std::size_t>(x) * channels; };
    if (twice) {
      for (int x = 0; x < n; ++x) {
        const float *a = texel(x), *b = texel(width_ - 1 - x);
        const float *e = texel(pairs - 1 - x), *f = texel(pairs + x);  // the pair at pi - p
        for (int c = 0; c < channels; ++c) {
          const std::size_t at = static_cast<std::size_t>(c) * n + x;
          const double s1 = static_cast<double>(a[c]) + b[c], d1 = static_cast<double>(a[c]) - b[c];
          const double s2 = static_cast<double>(e[c]) + f[c], d2 = static_cast<double>(e[c]) - f[c];
          folded[0][at] = s1 + s2;
          folded[1][at] = s1 - s2;
          folded[2][at] = d1 + d2;
          folded[3][at] = d1 - d2;
        }
      }
    } else {
      for (int x = 0; x < n; ++x) {
        const float *a = texel(x), *b = texel(width_ - 1 - x);
        for (int c = 0; c < channels; ++c) {
          const std::size_t at = static_cast<std::size_t>(c) * n + x;
          folded[0][at] = static_cast<double>(a[c]) + b[c];
          folded[2][at] = static_cast<double>(a[c]) - b[c];
        }
      }
    }
    for (int c = 0; c < channels; ++c)
      for (int k = 0; k < slots; ++k) {
        // k = 0: the column widths; k = 2m-1: cos(m p); k = 2m: sin(m p).
        const int m = (k + 1) / 2;
        const bool cosine = k == 0 || k % 2 == 1;
        const int which = cosine ? (twice && m % 2 == 1 ? 1 : 0) : (twice && m % 2 == 0 ? 3 : 2);
        sums[static_cast<std::size_t>(c) * slots + k] =
            lane_dot(&column_weights_[static_cast<std::size_t>(k) * pairs],
                     folded[which].get() + static_cast<std::size_t>(c) * n, n);
      }
    // A non-finite texel makes its row's sums non-finite (floats cannot overflow a
    // double sum), so the texels are only searched when one is there.
    bool finite = true;
    for (int c = 0; c < channels; ++c) finite = finite && std::isfinite(sums[static_cast<std::size_t>(c) * slots]);
    if (!finite) {
      for (int x = 0; x < width_; ++x)
        for (int c = 0; c < channels; ++c)
          if (const float v = row[static_cast<std::size_t>(x) * channels + c]; !std::isfinite(v))
            return non_finite_error("", x, y, c, v);
    }
    const double* t = &row_integrals_[static_cast<std::size_t>(y) * legendre_count(order_)];
    for (int l = 0; l < order_; ++l) {
      for (int m = -l; m <= l; ++m) {
        const double tl = t[legendre_index(l, std::abs(m))];
        const int slot = azimuth_slot(m);
        double* out = &partial[static_cast<std::size_t>(sh_index(l, m)) * channels];
        for (int c = 0; c < channels; ++c) out[c] += tl * sums[static_cast<std::size_t>(c) * slots + slot];
      }
    }
  }
  return Ok{};
}

namespace {

// Runs every block in order, each into its own zeroed partial, and adds the partials
// in block order: the same sums a parallel caller gets (docs/lighting.md).
template <class Projector, class Image>
Result<EnvCoefficients> project_in_order(const Projector& p, const Image& image, int channels) {
  EnvCoefficients out{p.order(), channels, std::vector<double>(p.partial_size(channels), 0.0)};
  std::vector<double> partial(out.coefficients.size());
  for (int b = 0; b < p.block_count(); ++b) {
    std::fill(partial.begin(), partial.end(), 0.0);
    if (Result<Ok> r = p.accumulate_block(image, b, partial); !r) return r.error();
    for (std::size_t i = 0; i < partial.size(); ++i) out.coefficients[i] += partial[i];
  }
  return out;
}

}  // namespace

Result<EnvCoefficients> project_equirect(const FloatImageView& image, int order) {
  Result<EquirectProjector> p = EquirectProjector::create(image.width, image.height, order);
  if (!p) return p.error();
  if (!valid_view(image, image.width, image.height))
    return Error{"the image view needs texels, 1..4 channels and a row stride of at least width * channels"};
  return project_in_order(p.value(), image, image.channels);
}

// ---------------------------------------------------------------------------
// Cubemaps

int cubemap_nodes_per_side(int face_size, int order) {
  // One texel is [-1, 1]^2 in its own coordinates, 1/R of the face's half-width per
  // unit. The integrand y_i(w(s, t)) / (1 + s^2 + t^2)^(3/2) is analytic away from
  // 1 + s^2 + t^2 = 0, at least 1 away from the real face in s or t: R in texel units.
  // A Gauss rule of K nodes errs by at most 64/15 M rho^(2-2K) / (rho^2 - 1) for an
  // integrand bounded by M on the Bernstein ellipse rho (semi-minor axis b = beta R);
  // there a degree-l harmonic grows by at most (1 + beta)^l / (1 - beta^2)^((l+3)/2).
  // The smallest K that one of a few ellipses bounds below 1e-13 (two dimensions: twice).
  const double degree = order - 1;
  for (int k = 1; k < 64; ++k) {
    for (double beta : {0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.45}) {
      const double b = beta * face_size;
      const double rho = b + std::sqrt(b * b + 1);
      const double growth = std::pow(1 + beta, degree) / std::pow(1 - beta * beta, (degree + 3) / 2);
      const double bound = 2 * 64.0 / 15 * growth * std::pow(rho, 2.0 - 2.0 * k) / (rho * rho - 1);
      if (bound < 1e-13) return k;
    }
  }
  return 64;
}

namespace {

// The texels of a cubemap come in classes under the cube's symmetries, and the rule runs
// once per class (docs/lighting.md, "Exact projection"):
// - the eight maps of the face square onto itself, as (k, e): the azimuth p about the
//   face normal goes to e p + k pi/2. A texel integral over g(texel) of y_c, y_s (cos-
//   and sine-type, order m) is, over the texel itself, cos(m a) W_c - e sin(m a) W_s and
//   sin(m a) W_c + e cos(m a) W_s (a = k pi/2): summed over the eight images with their
//   values f, only m mod 4 matters, through these sums of E_k = f(k, +) + f(k, -) and
//   D_k = f(k, +) - f(k, -);
// - the antipodal map w -> -w, which carries each face onto the opposite one and
//   multiplies y_lm by (-1)^l: a texel of +X, +Y, +Z and its antipode (on -X, -Y, -Z)
//   are summed (the even bands) and subtracted (the odd bands) before the square's folds.
enum Fold { kP0, kV0, kP2, kV2, kP1, kV1, kU1, kQ1, kFolds };
// Classes whose integrals are computed together: the lanes of Lanes (GCC's vector
// extension, lowered to AVX-512, AVX2 or SSE2 by the clones; one lane, one class).
constexpr int kClassLanes = 8;
using Lanes = double __attribute__((vector_size(kClassLanes * sizeof(double))));
// Buffers of Lanes on the heap, 64-byte aligned: the baseline target aligns a Lanes to 16
// bytes only, while the AVX-512 clones load and store whole aligned Lanes.
struct alignas(64) LaneBox {
  Lanes v;
};
static_assert(sizeof(LaneBox) == sizeof(Lanes));
class LaneBuffer {
 public:
  explicit LaneBuffer(std::size_t size) : boxes_(size, LaneBox{Lanes{}}) {}
  Lanes* data() { return &boxes_.data()->v; }
  Lanes& operator[](std::size_t i) { return boxes_[i].v; }

 private:
  std::vector<LaneBox> boxes_;
};
// Folded sums of a tile of classes for one face pair (+X -X, +Y -Y or +Z -Z) and C
// channels: F[(fold * 2 + band parity) * C + c].
constexpr int kPlanes = 2 * kFolds;

// The rule of one texel per lane, texels (s_centre[lane], t_centre) of half-width
// `half`, in the face frame: direction (s, t, 1) / r, polar axis the face normal.
// W[i], i < N^2. The basis recurrence of sh.cpp (the Q_l^m of basis/legendre_recurrence.h
// times Re, Im (x + i y)^m), node weights folded into the azimuthal factors, run m by m
// (each Q_l^m from Q_{l-1}^m and Q_{l-2}^m, the diagonal Q_m^m carried from m - 1), so
// that it lives in registers. The nodes are summed row of nodes by row of nodes, as
// texel_integrals does (fewer roundings per sum), NB nodes of a row at a time
// (kNodeChunk: all of them for the 3 nodes of large faces, whose row sums then never
// leave the registers); `row` is scratch of N^2 Lanes for rows of more nodes.
constexpr int kNodeChunk = 4;
template <int NB, bool First>
inline void rule_nodes(int order, const detail::LegendreRecurrence<double>& tab, const Lanes* x, const Lanes* y,
                       const Lanes* z, const Lanes* w, Lanes* out) {
  constexpr double kSqrt2 = std::numbers::sqrt2;
  Lanes cm[NB], sm[NB], diag[NB];
  for (int u = 0; u < NB; ++u) {
    cm[u] = w[u];
    sm[u] = Lanes{};
    diag[u] = Lanes{} + tab.q00;
  }
  for (int m = 0; m < order; ++m) {
    if (m > 0) {
      // cm, sm carry sqrt2 from m = 1 on (y_l^{+-m} = sqrt2 Q_l^m Re, Im (x + i y)^m).
      for (int u = 0; u < NB; ++u) {
        const Lanes c = m == 1 ? kSqrt2 * cm[u] : cm[u];
        const Lanes sp = sm[u];
        cm[u] = x[u] * c - y[u] * sp;
        sm[u] = x[u] * sp + y[u] * c;
        diag[u] = tab.diag[m] * diag[u];
      }
    }
    // Q_l^m of every node times the azimuthal factors, summed over the nodes, into (l, +-m).
    auto put = [&](int l, const Lanes* q) {
      Lanes* centre = out + l * (l + 1);
      Lanes ac = q[0] * cm[0];
      for (int u = 1; u < NB; ++u) ac += q[u] * cm[u];
      centre[m] = First ? ac : centre[m] + ac;
      if (m > 0) {
        Lanes as = q[0] * sm[0];
        for (int u = 1; u < NB; ++u) as += q[u] * sm[u];
        centre[-m] = First ? as : centre[-m] + as;
      }
    };
    Lanes q2[NB], q1[NB];
    for (int u = 0; u < NB; ++u) q1[u] = diag[u];
    put(m, q1);
    if (m + 1 >= order) continue;
    for (int u = 0; u < NB; ++u) {
      q2[u] = q1[u];
      q1[u] = tab.subdiag[m] * z[u] * q1[u];
    }
    put(m + 1, q1);
    const double* ta = tab.a.data();
    const double* tb = tab.b.data();
    for (int l = m + 2, at = detail::LegendreRecurrence<double>::tri(m + 2, m); l < order; at += l + 1, ++l) {
      const double ca = ta[at], cb = tb[at];
      Lanes q0[NB];
      for (int u = 0; u < NB; ++u) q0[u] = ca * (z[u] * q1[u] - cb * q2[u]);
      put(l, q0);
      for (int u = 0; u < NB; ++u) {
        q2[u] = q1[u];
        q1[u] = q0[u];
      }
    }
  }
}

template <int NB>
inline void rule_nodes(int order, const detail::LegendreRecurrence<double>& tab, const Lanes* x, const Lanes* y,
                       const Lanes* z, const Lanes* w, bool first, Lanes* out) {
  if (first) rule_nodes<NB, true>(order, tab, x, y, z, w, out);
  else rule_nodes<NB, false>(order, tab, x, y, z, w, out);
}

SHTOOL_SAME_BITS_CLONES_WIDE void tile_rule(int order, int nodes, const double* node, const double* weight, double half,
                                            const double* s_centre, double t_centre, Lanes* W, Lanes* row) {
  const detail::LegendreRecurrence<double>& tab = detail::legendre_recurrence<double>();
  constexpr int U = kNodeChunk;
  const int n = order * order;
  Lanes sc;
  for (int k = 0; k < kClassLanes; ++k) sc[k] = s_centre[k];
  const bool chunked = nodes > U;
  for (int a = 0; a < nodes; ++a) {
    const double t = t_centre + half * node[a];
    for (int b0 = 0; b0 < nodes; b0 += U) {
      const int nb = std::min(U, nodes - b0);
      Lanes x[U], y[U], z[U], w[U];
      for (int u = 0; u < nb; ++u) {
        const int b = b0 + u;
        const double wab = weight[a] * weight[b] * half * half;
        const Lanes s = sc + half * node[b];
        const Lanes r2 = 1 + s * s + t * t;
        Lanes r;
        for (int k = 0; k < kClassLanes; ++k) r[k] = std::sqrt(r2[k]);
        const Lanes inv = 1 / r;
        x[u] = s * inv;
        y[u] = t * inv;
        z[u] = inv;
        w[u] = wab / (r2 * r);  // ds dt / r^3
      }
      // This chunk's sums start or continue a row of nodes (in `row`, or in W when the
      // row is one chunk), and a row starts or continues W.
      Lanes* out = chunked ? row : W;
      const bool first = chunked ? b0 == 0 : a == 0;
      switch (nb) {
        case 1: rule_nodes<1>(order, tab, x, y, z, w, first, out); break;
        case 2: rule_nodes<2>(order, tab, x, y, z, w, first, out); break;
        case 3: rule_nodes<3>(order, tab, x, y, z, w, first, out); break;
        default: rule_nodes<4>(order, tab, x, y, z, w, first, out); break;
      }
    }
    if (chunked)
      for (int i = 0; i < n; ++i) W[i] = a == 0 ? row[i] : W[i] + row[i];
  }
}

// Adds the folded sums F of a batch of `units` rows of 8 classes times their integrals W
// into the face-frame accumulators A[i * 3 C + pair * C + c], lane by lane (one class per
// lane): coefficient (l, m) meets the fold of its m mod 4 and its type, on the plane of
// its band's parity. W[u * N^2 + i]; F[u * kPlanes * 3 C + plane * 3 C + pair * C + c].
// The accumulators stay in registers over the batch.
template <int C>
SHTOOL_SAME_BITS_CLONES_WIDE void contract_batch(int order, int units, const Lanes* W, const Lanes* F, Lanes* A) {
  constexpr int PC = 3 * C, FS = kPlanes * PC;
  const int n = order * order;
  for (int l = 0; l < order; ++l) {
    const int i0 = l * (l + 1), par = l & 1;
    {
      Lanes* a = A + i0 * PC;
      Lanes acc[PC];
      for (int j = 0; j < PC; ++j) acc[j] = a[j];
      for (int u = 0; u < units; ++u) {
        const Lanes w = W[u * n + i0];
        const Lanes* p = F + u * FS + (2 * kP0 + par) * PC;
        for (int j = 0; j < PC; ++j) acc[j] += w * p[j];
      }
      for (int j = 0; j < PC; ++j) a[j] = acc[j];
    }
    for (int m = 1; m <= l; ++m) {
      Lanes* ac = A + (i0 + m) * PC;
      Lanes* as = A + (i0 - m) * PC;
      Lanes xc[PC], xs[PC];
      for (int j = 0; j < PC; ++j) {
        xc[j] = ac[j];
        xs[j] = as[j];
      }
      const Lanes* wc = W + i0 + m;
      const Lanes* ws = W + i0 - m;
      if ((m & 1) == 0) {
        const int pp = (2 * ((m & 3) == 0 ? kP0 : kP2) + par) * PC, pv = (2 * ((m & 3) == 0 ? kV0 : kV2) + par) * PC;
        for (int u = 0; u < units; ++u) {
          const Lanes c = wc[u * n], s = ws[u * n];
          const Lanes *p = F + u * FS + pp, *v = F + u * FS + pv;
          for (int j = 0; j < PC; ++j) xc[j] += c * p[j];
          for (int j = 0; j < PC; ++j) xs[j] += s * v[j];
        }
      } else {
        const int pp = (2 * kP1 + par) * PC, pq = (2 * kQ1 + par) * PC, pu = (2 * kU1 + par) * PC,
                  pv = (2 * kV1 + par) * PC;
        if ((m & 3) == 1) {
          for (int u = 0; u < units; ++u) {
            const Lanes c = wc[u * n], s = ws[u * n];
            const Lanes *p = F + u * FS + pp, *q = F + u * FS + pq, *uu = F + u * FS + pu, *v = F + u * FS + pv;
            for (int j = 0; j < PC; ++j) xc[j] += c * p[j] - s * q[j];
            for (int j = 0; j < PC; ++j) xs[j] += c * uu[j] + s * v[j];
          }
        } else {
          for (int u = 0; u < units; ++u) {
            const Lanes c = wc[u * n], s = ws[u * n];
            const Lanes *p = F + u * FS + pp, *q = F + u * FS + pq, *uu = F + u * FS + pu, *v = F + u * FS + pv;
            for (int j = 0; j < PC; ++j) xc[j] += c * p[j] + s * q[j];
            for (int j = 0; j < PC; ++j) xs[j] += s * v[j] - c * uu[j];
          }
        }
      }
      for (int j = 0; j < PC; ++j) {
        ac[j] = xc[j];
        as[j] = xs[j];
      }
    }
  }
}

constexpr const char* kFaceNames[6] = {"+X face ", "-X face ", "+Y face ", "-Y face ", "+Z face ", "-Z face "};

Error first_non_finite(std::span<const FloatImageView, 6> faces) {
  for (int f = 0; f < 6; ++f) {
    const FloatImageView& image = faces[static_cast<std::size_t>(f)];
    for (int y = 0; y < image.height; ++y) {
      const float* row = image.row(y);
      for (int x = 0; x < image.width; ++x)
        for (int c = 0; c < image.channels; ++c)
          if (const float v = row[static_cast<std::size_t>(x) * image.channels + c]; !std::isfinite(v))
            return non_finite_error(kFaceNames[f], x, y, c, v);
    }
  }
  return Error{"a cubemap block's sums are not finite, yet every texel is"};
}

}  // namespace

Result<CubemapProjector> CubemapProjector::create(int face_size, int order, bool mirror_x) {
  if (order < 1 || order > kMaxEnvOrder) return order_error(order);
  if (face_size < 1) return Error{"a cubemap face must have at least one texel"};
  CubemapProjector p;
  p.size_ = face_size;
  p.order_ = order;
  p.mirror_x_ = mirror_x;
  p.nodes_ = cubemap_nodes_per_side(face_size, order);
  const GaussLegendre g = gauss_legendre(p.nodes_);
  p.nodes_unit_ = g.nodes;
  p.weights_unit_ = g.weights;
  // The face frame's axes in shtool's frame: (s, t, 1) -> cube_vector(s, t) is linear.
  const int n = sh_count(order);
  std::vector<double> map(static_cast<std::size_t>(n) * n);
  // Only the first face of each antipodal pair (+X, +Y, +Z): the second's texels are
  // folded onto it (accumulate_block).
  for (int f = 0; f < 6; f += 2) {
    const CubeFace face = static_cast<CubeFace>(f);
    const Eigen::Vector3d origin = p.cube_vector(face, 0, 0);
    Eigen::Matrix3d q;
    q.col(0) = p.cube_vector(face, 1, 0) - origin;
    q.col(1) = p.cube_vector(face, 0, 1) - origin;
    q.col(2) = origin;
    // Column j of the identity carried along is column j of the map.
    std::fill(map.begin(), map.end(), 0.0);
    for (int i = 0; i < n; ++i) map[static_cast<std::size_t>(i) * n + i] = 1;
    if (Result<Ok> r = apply_orthogonal_map(q, n, map); !r) return r.error();
    for (int l = 0; l < order; ++l)
      for (int a = l * l; a < (l + 1) * (l + 1); ++a)
        for (int b = l * l; b < (l + 1) * (l + 1); ++b) p.face_maps_.push_back(map[static_cast<std::size_t>(a) * n + b]);
    // The antipode of the face's point (s, t) on the opposite face, as a map of the
    // square: one of the eight (s, t) -> (+-s, +-t), (+-t, +-s).
    const CubeFace opposite = static_cast<CubeFace>(f + 1);
    const double s0 = 0.25, t0 = 0.625;  // no map of the square fixes it
    int found = 0;
    for (int m = 0; m < 8; ++m) {
      const bool swap = m & 1, flip_s = m & 2, flip_t = m & 4;
      const double s1 = (flip_s ? -1 : 1) * (swap ? t0 : s0), t1 = (flip_t ? -1 : 1) * (swap ? s0 : t0);
      if ((p.cube_vector(opposite, s1, t1) + p.cube_vector(face, s0, t0)).norm() > 1e-12) continue;
      // That map after image g of a class is another image of the class: which one, read
      // off a texel of a 16-texel face that no map of the square fixes.
      constexpr int kR = 16, x = 13, y = 10, xm = kR - 1 - x, ym = kR - 1 - y;
      const int at[8][2] = {{x, y}, {x, ym}, {ym, x}, {y, x}, {xm, ym}, {xm, y}, {y, xm}, {ym, xm}};
      for (int g = 0; g < 8; ++g) {
        int col = swap ? at[g][1] : at[g][0], row = swap ? at[g][0] : at[g][1];
        if (flip_s) col = kR - 1 - col;
        if (flip_t) row = kR - 1 - row;
        for (int h = 0; h < 8; ++h)
          if (at[h][0] == col && at[h][1] == row) p.antipode_[f / 2][g] = h, ++found;
      }
    }
    if (found != 8) detail::precondition_failed("CubemapProjector: opposite faces are not antipodal");
  }
  return p;
}

int CubemapProjector::block_count() const {
  const int rows = size_ - size_ / 2;  // rows of the eighth s >= t >= 0
  return (rows + kRowsPerBand - 1) / kRowsPerBand;
}

std::size_t CubemapProjector::partial_size(int channels) const {
  return static_cast<std::size_t>(sh_count(order_)) * channels;
}

Eigen::Vector3d CubemapProjector::cube_vector(CubeFace face, double s, double t) const {
  Eigen::Vector3d cube = Eigen::Vector3d::Zero();
  switch (face) {
    case CubeFace::px: cube = {1, -t, -s}; break;
    case CubeFace::nx: cube = {-1, -t, s}; break;
    case CubeFace::py: cube = {s, 1, t}; break;
    case CubeFace::ny: cube = {s, -1, -t}; break;
    case CubeFace::pz: cube = {s, -t, 1}; break;
    case CubeFace::nz: cube = {-s, -t, -1}; break;
  }
  if (mirror_x_) cube.x() = -cube.x();
  return Eigen::Vector3d(cube.x(), -cube.z(), cube.y());
}

Eigen::Vector3d CubemapProjector::direction(CubeFace face, double s, double t) const {
  return cube_vector(face, s, t).normalized();
}

void CubemapProjector::texel_integrals(CubeFace face, int x, int y, std::span<double> out) const {
  const int n = sh_count(order_);
  if (out.size() < static_cast<std::size_t>(n) || x < 0 || y < 0 || x >= size_ || y >= size_)
    detail::precondition_failed("texel_integrals: texel outside the face or fewer than N^2 outputs");
  // The nodes are summed row of nodes by row of nodes (fewer roundings per sum).
  std::array<double, kMaxEnvOrder * kMaxEnvOrder> y_values, node_row;
  const double half = 1.0 / size_;  // half a texel's width in face coordinates
  const double s_centre = -1 + (2 * x + 1) * half, t_centre = -1 + (2 * y + 1) * half;
  std::fill(out.begin(), out.begin() + n, 0.0);
  for (int j = 0; j < nodes_; ++j) {
    const double t = t_centre + half * nodes_unit_[j];
    std::fill(node_row.begin(), node_row.begin() + n, 0.0);
    for (int i = 0; i < nodes_; ++i) {
      const double s = s_centre + half * nodes_unit_[i];
      const double r2 = 1 + s * s + t * t;
      // ds dt / r^3 is the solid angle of the face element at (s, t).
      const double w = weights_unit_[i] * weights_unit_[j] * half * half / (r2 * std::sqrt(r2));
      eval_sh<double>(order_, direction(face, s, t), std::span<double>(y_values.data(), n));
      for (int k = 0; k < n; ++k) node_row[k] += w * y_values[k];
    }
    for (int k = 0; k < n; ++k) out[k] += node_row[k];
  }
}

namespace {

bool valid_faces(std::span<const FloatImageView, 6> faces, int size) {
  for (const FloatImageView& f : faces)
    if (!valid_view(f, size, size) || f.channels != faces[0].channels) return false;
  return true;
}

// A tile of T x T classes (x0 + k, y0 + j), T = kTile, and the texels of its eight images
// on each face: texels[((f * 8 + g) * C + c) * T^2 + j * T + k] is channel c of image g of
// class (x0 + k, y0 + j) on face f. Images, as (column, row) of texel (x, y), in the order
// (k, e) = (0,+) (0,-) (1,+) (1,-) (2,+) (2,-) (3,+) (3,-): p, -p, p + pi/2, pi/2 - p,
// p + pi, pi - p, p - pi/2, -pi/2 - p. Each image of the tile is a T x T block of a face:
// images 0, 1, 4, 5 keep its rows (read forwards or backwards), images 2, 3, 6, 7 swap s
// and t and are transposed as they are read, a row of T texels at a time. Classes
// outside the face are clamped to its edge (their sums are weighted by zero).
constexpr int kTile = 16;
template <int C>
void load_tile(const float* const* bases, const std::size_t* strides, int R, int x0, int y0, float* texels) {
  constexpr int T = kTile, TT = T * T;
  int xs[T], ys[T], xms[T], yms[T];
  for (int k = 0; k < T; ++k) {
    xs[k] = std::min(x0 + k, R - 1);
    ys[k] = std::min(y0 + k, R - 1);
    xms[k] = R - 1 - xs[k];
    yms[k] = R - 1 - ys[k];
  }
  // Per image: the face rows and columns its rows (j for images along rows, k for the
  // transposed ones) and columns (k, j) follow.
  const int* const cols[8] = {xs, xs, yms, ys, xms, xms, ys, yms};
  const int* const rows[8] = {ys, yms, xs, xs, yms, ys, xms, xms};
  constexpr bool kTransposed[8] = {false, false, true, true, false, false, true, true};
  for (int f = 0; f < 6; ++f) {
    const float* base = bases[f];
    const std::size_t stride = strides[f];
    for (int g = 0; g < 8; ++g) {
      float* out = texels + static_cast<std::size_t>(f * 8 + g) * C * TT;
      const int* col = cols[g];
      // Away from the face's edge the block's columns run forwards or backwards.
      const bool forward = col[T - 1] - col[0] == T - 1, backward = col[0] - col[T - 1] == T - 1;
      for (int r = 0; r < T; ++r) {
        // Row r of the block: T texels of one face row.
        const float* src = base + static_cast<std::size_t>(rows[g][r]) * stride;
        float line[C][T];
        if (forward) {
          const float* p = src + static_cast<std::size_t>(col[0]) * C;
          for (int i = 0; i < T; ++i)
            for (int c = 0; c < C; ++c) line[c][i] = p[i * C + c];
        } else if (backward) {
          const float* p = src + static_cast<std::size_t>(col[T - 1]) * C;
          for (int i = 0; i < T; ++i)
            for (int c = 0; c < C; ++c) line[c][T - 1 - i] = p[i * C + c];
        } else {
          for (int i = 0; i < T; ++i)
            for (int c = 0; c < C; ++c) line[c][i] = src[static_cast<std::size_t>(col[i]) * C + c];
        }
        if (kTransposed[g]) {
          for (int c = 0; c < C; ++c)
            for (int i = 0; i < T; ++i) out[c * TT + i * T + r] = line[c][i];
        } else {
          for (int c = 0; c < C; ++c)
            for (int i = 0; i < T; ++i) out[c * TT + r * T + i] = line[c][i];
        }
      }
    }
  }
}

// The eight folds of a class's eight values v (in the order of its images) into
// out[fold * stride], each times `scale`.
inline void fold_square(const Lanes* v, const Lanes& scale, Lanes* out, int stride) {
  const Lanes e0 = v[0] + v[1], d0 = v[0] - v[1], e1 = v[2] + v[3], d1 = v[2] - v[3];
  const Lanes e2 = v[4] + v[5], d2 = v[4] - v[5], e3 = v[6] + v[7], d3 = v[6] - v[7];
  const Lanes e02 = e0 + e2, e13 = e1 + e3, d02 = d0 + d2, d13 = d1 + d3;
  out[kP0 * stride] = scale * (e02 + e13);
  out[kP2 * stride] = scale * (e02 - e13);
  out[kV0 * stride] = scale * (d02 + d13);
  out[kV2 * stride] = scale * (d02 - d13);
  out[kP1 * stride] = scale * (e0 - e2);
  out[kU1 * stride] = scale * (e1 - e3);
  out[kV1 * stride] = scale * (d0 - d2);
  out[kQ1 * stride] = scale * (d1 - d3);
}

// The folded sums of the 8 classes (x0 + k0 + k, y0 + j) of a loaded tile for one face
// pair, F[(fold * 2 + band parity) * plane_stride + c]: the class's eight texels on the pair's first
// face plus (even bands) and minus (odd bands) their antipodes on the second (image
// `antipode[g]` there), then the square's folds, times scale (1 / the class's stabiliser;
// 0 outside the eighth).
template <int C>
SHTOOL_SAME_BITS_CLONES_WIDE void fold_row(const float* texels, int pair, const int* antipode, int j, int k0,
                                           const double* scale, Lanes* F, int plane_stride) {
  constexpr int TT = kTile * kTile;
  Lanes sc;
  for (int k = 0; k < kClassLanes; ++k) sc[k] = scale[k];
  const int at = j * kTile + k0;
  for (int c = 0; c < C; ++c) {
    Lanes sum[8], diff[8];
    for (int g = 0; g < 8; ++g) {
      const float* a = texels + static_cast<std::size_t>((2 * pair * 8 + g) * C + c) * TT + at;
      const float* b = texels + static_cast<std::size_t>(((2 * pair + 1) * 8 + antipode[g]) * C + c) * TT + at;
      Lanes va, vb;
      for (int k = 0; k < kClassLanes; ++k) {
        va[k] = a[k];
        vb[k] = b[k];
      }
      sum[g] = va + vb;
      diff[g] = va - vb;
    }
    fold_square(sum, sc, F + c, 2 * plane_stride);
    fold_square(diff, sc, F + plane_stride + c, 2 * plane_stride);
  }
}

}  // namespace

Result<Ok> CubemapProjector::accumulate_block(std::span<const FloatImageView, 6> faces, int block,
                                              std::span<double> partial) const {
  if (!valid_faces(faces, size_))
    return Error{"cubemap block: six faces of the projector's size and one channel count (1..4)"};
  if (block < 0 || block >= block_count() || partial.size() < partial_size(faces[0].channels))
    return Error{"cubemap block: block out of range or partial smaller than partial_size(channels)"};
  const int channels = faces[0].channels;
  const int n = sh_count(order_);
  const int R = size_;
  const int first_row = R / 2;
  const double half = 1.0 / R;
  const float* bases[6];
  std::size_t strides[6];
  for (int f = 0; f < 6; ++f) {
    bases[f] = faces[static_cast<std::size_t>(f)].texels;
    strides[f] = faces[static_cast<std::size_t>(f)].stride();
  }
  // The coefficients in the frame of each pair's first face, one per lane (class):
  // A[i * 3 C + pair * C + c]; carried to shtool's frame at the end.
  const int pc = 3 * channels;
  const std::size_t folded = static_cast<std::size_t>(kPlanes) * pc;
  // Rows of 8 classes are contracted in batches of up to kBatchBytes of integrals.
  constexpr std::size_t kBatchBytes = 128 * 1024;
  const int batch = static_cast<int>(std::clamp<std::size_t>(kBatchBytes / (sizeof(Lanes) * n), 1, 8));
  LaneBuffer A(static_cast<std::size_t>(n) * pc), W(static_cast<std::size_t>(n) * batch), node_row(n),
      F(folded * batch);
  std::vector<float> texels(static_cast<std::size_t>(6 * 8 * kTile * kTile) * channels);
  static_assert(kRowsPerBand == kTile && kTile % kClassLanes == 0, "a band is one row of tiles");
  // Blocks take the bands from both ends in turn (long rows near the face's centre, short
  // near its edge), so that any contiguous run of blocks holds about its share of work.
  const int bands = block_count();
  const int band = block % 2 == 0 ? block / 2 : bands - 1 - block / 2;
  const int y_begin = first_row + band * kRowsPerBand, y_end = std::min(R, y_begin + kRowsPerBand);
  int units = 0;  // rows of the batch so far
  auto contract = [&] {
    switch (channels) {
      case 1: contract_batch<1>(order_, units, W.data(), F.data(), A.data()); break;
      case 2: contract_batch<2>(order_, units, W.data(), F.data(), A.data()); break;
      case 3: contract_batch<3>(order_, units, W.data(), F.data(), A.data()); break;
      default: contract_batch<4>(order_, units, W.data(), F.data(), A.data()); break;
    }
    units = 0;
  };
  for (int x0 = y_begin; x0 < R; x0 += kTile) {
    switch (channels) {
      case 1: load_tile<1>(bases, strides, R, x0, y_begin, texels.data()); break;
      case 2: load_tile<2>(bases, strides, R, x0, y_begin, texels.data()); break;
      case 3: load_tile<3>(bases, strides, R, x0, y_begin, texels.data()); break;
      default: load_tile<4>(bases, strides, R, x0, y_begin, texels.data()); break;
    }
    for (int y = y_begin; y < y_end; ++y) {
      const int j = y - y_begin, ym = R - 1 - y;
      for (int k0 = 0; k0 < kTile; k0 += kClassLanes) {
        if (x0 + k0 + kClassLanes <= y || x0 + k0 >= R) continue;
        alignas(64) double s_centre[kClassLanes], scale[kClassLanes];
        for (int k = 0; k < kClassLanes; ++k) {
          const int x = std::clamp(x0 + k0 + k, y, R - 1), xm = R - 1 - x;
          s_centre[k] = -1 + (2 * x + 1) * half;
          // A class of fewer than eight texels meets each of them 8 / |class| times.
          const int at[8][2] = {{x, y}, {x, ym}, {ym, x}, {y, x}, {xm, ym}, {xm, y}, {y, xm}, {ym, xm}};
          int stabiliser = 0;
          for (const auto& p : at) stabiliser += p[0] == x && p[1] == y;
          scale[k] = x0 + k0 + k == x ? 1.0 / stabiliser : 0.0;
        }
        tile_rule(order_, nodes_, nodes_unit_.data(), weights_unit_.data(), half, s_centre, -1 + (2 * y + 1) * half,
                  W.data() + static_cast<std::size_t>(units) * n, node_row.data());
        Lanes* f = F.data() + units * folded;
        for (int pair = 0; pair < 3; ++pair) {
          switch (channels) {
            case 1: fold_row<1>(texels.data(), pair, antipode_[pair], j, k0, scale, f + pair * 1, pc); break;
            case 2: fold_row<2>(texels.data(), pair, antipode_[pair], j, k0, scale, f + pair * 2, pc); break;
            case 3: fold_row<3>(texels.data(), pair, antipode_[pair], j, k0, scale, f + pair * 3, pc); break;
            default: fold_row<4>(texels.data(), pair, antipode_[pair], j, k0, scale, f + pair * 4, pc); break;
          }
        }
        if (++units == batch) contract();
      }
    }
  }
  if (units > 0) contract();
  // The lanes summed in a fixed order.
  std::vector<double> sums(static_cast<std::size_t>(n) * pc);
  for (std::size_t i = 0; i < sums.size(); ++i) {
    const Lanes& v = A[i];
    sums[i] = ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]));
  }
  // y_00's integral is positive on every texel: a non-finite texel leaves its sum so.
  for (int pair = 0; pair < 3; ++pair)
    for (int c = 0; c < channels; ++c)
      if (!std::isfinite(sums[static_cast<std::size_t>(pair * channels + c)])) return first_non_finite(faces);
  std::size_t block_at = 0;
  for (int pair = 0; pair < 3; ++pair)
    for (int l = 0; l < order_; ++l) {
      const int width = 2 * l + 1, base = l * l;
      const double* map = &face_maps_[block_at];
      block_at += static_cast<std::size_t>(width) * width;
      for (int a = 0; a < width; ++a)
        for (int c = 0; c < channels; ++c) {
          double sum = 0;
          for (int b = 0; b < width; ++b)
            sum += map[a * width + b] * sums[static_cast<std::size_t>(base + b) * pc + pair * channels + c];
          partial[static_cast<std::size_t>(base + a) * channels + c] += sum;
        }
    }
  return Ok{};
}

Result<EnvCoefficients> project_cubemap(std::span<const FloatImageView, 6> faces, int order, bool mirror_x) {
  const int size = faces[0].width;
  if (!valid_faces(faces, size))
    return Error{"the six cube faces must be square, of one size and one channel count (1..4)"};
  Result<CubemapProjector> p = CubemapProjector::create(size, order, mirror_x);
  if (!p) return p.error();
  return project_in_order(p.value(), faces, faces[0].channels);
}

Result<EnvCoefficients> project_cubemap_reference(std::span<const FloatImageView, 6> faces, int order,
                                                  bool mirror_x) {
  const int size = faces[0].width;
  if (!valid_faces(faces, size))
    return Error{"the six cube faces must be square, of one size and one channel count (1..4)"};
  Result<CubemapProjector> made = CubemapProjector::create(size, order, mirror_x);
  if (!made) return made.error();
  const CubemapProjector& p = made.value();
  const int channels = faces[0].channels;
  const int n = sh_count(order);
  EnvCoefficients out{order, channels, std::vector<double>(p.partial_size(channels), 0.0)};
  std::vector<double> integral(n);
  for (int f = 0; f < 6; ++f) {
    const FloatImageView& image = faces[static_cast<std::size_t>(f)];
    for (int y = 0; y < size; ++y) {
      const float* row = image.row(y);
      for (int x = 0; x < size; ++x) {
        const float* texel = row + static_cast<std::size_t>(x) * channels;
        for (int c = 0; c < channels; ++c)
          if (!std::isfinite(texel[c])) return non_finite_error(kFaceNames[f], x, y, c, texel[c]);
        p.texel_integrals(static_cast<CubeFace>(f), x, y, integral);
        for (int k = 0; k < n; ++k)
          for (int c = 0; c < channels; ++c)
            out.coefficients[static_cast<std::size_t>(k) * channels + c] += integral[k] * texel[c];
      }
    }
  }
  return out;
}

}  // namespace shtool
