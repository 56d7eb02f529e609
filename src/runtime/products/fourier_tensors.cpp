#include "shtool/fourier_tensors.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "io/load_kind.h"
#include "shtool/legendre.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

// integral_0^pi cos(a t) sin t dt = (1 + cos(a pi)) / (1 - a^2): 2 / (1 - a^2) for even a,
// 0 for odd a (a = +-1 included).
long double cos_sin_integral(int a) {
  if (a % 2 != 0) return 0.0L;
  const long double ad = a;
  return 2.0L / (1.0L - ad * ad);
}

Error fourier_error(const std::string& what) {
  return Error{"sh-fourier-tensors table: " + what};
}

}  // namespace

ShFourierTensors ShFourierTensors::compute(int order, int degree) {
  ShFourierTensors t;
  t.order = order;
  t.degree = degree;
  const int n = order;
  t.to_fourier.assign(static_cast<std::size_t>(n) * n * n, 0.0);
  t.to_sh.assign(static_cast<std::size_t>(n) * n * (degree + 1), 0.0);

  // Exact sampling plus a discrete cosine/sine transform. Theta_l^m is sampled at
  // t_j = pi j / J, j = 0..J with J = n, by the pointwise Legendre recurrence (stable,
  // relative accuracy at every point); the trapezoid sums below are exact for
  // trigonometric polynomials of degree < 2J, and Theta_l^m cos(s t) has degree <= 2n - 2.
  // (Running the recurrence on coefficient vectors instead is unstable for m ~ l/2:
  // near the poles Theta_l^m is tiny and grows quickly with l, so absolute rounding
  // errors spread over all t get amplified; measured 3e-13 at l = 39.)
  const int J = n;
  const long double pi = std::numbers::pi_v<long double>;
  std::vector<long double> cos_table(2 * J), sin_table(2 * J);
  for (int r = 0; r < 2 * J; ++r) {  // cos(pi r / J), sin(pi r / J), exact symmetric reduction
    cos_table[r] = std::cos(pi * r / J);
    sin_table[r] = std::sin(pi * r / J);
  }
  // all[j][l (l+1)/2 + m]: sqrt(2 pi) Q_l^m sin^m at every sample (sqrt(2 pi) / sqrt(4 pi)
  // = 1 / sqrt(2) for (0, 0)), with sin exactly 0 at the poles.
  const std::size_t per_point = static_cast<std::size_t>(n) * (n + 1) / 2;
  std::vector<long double> all(per_point * (J + 1));
  for (int j = 0; j <= J; ++j) {
    const long double z = (j == 0) ? 1.0L : (j == J) ? -1.0L : cos_table[j];
    const long double sn = (j == 0 || j == J) ? 0.0L : sin_table[j];
    normalized_legendre_all(n, z, sn, 1.0L / std::sqrt(2.0L),
                            std::span<long double>(all.data() + j * per_point, per_point));
  }
  // samples[l][j] for the current m.
  std::vector<long double> samples(static_cast<std::size_t>(n) * (J + 1));
  std::vector<long double> c(n);
  for (int m = 0; m < n; ++m) {
    for (int j = 0; j <= J; ++j)
      for (int l = m; l < n; ++l)
        samples[static_cast<std::size_t>(l) * (J + 1) + j] = all[j * per_point + static_cast<std::size_t>(l) * (l + 1) / 2 + m];
    for (int l = m; l < n; ++l) {
      const long double* f = samples.data() + static_cast<std::size_t>(l) * (J + 1);
      std::fill(c.begin(), c.end(), 0.0L);
      for (int s = l % 2; s <= l; s += 2) {
        long double sum = 0;
        if (m % 2 == 0) {
          for (int j = 0; j <= J; ++j)
            sum += ((j == 0 || j == J) ? 0.5L : 1.0L) * f[j] * cos_table[(s * j) % (2 * J)];
          c[s] = sum * (s == 0 ? 1.0L : 2.0L) / J;
        } else {
          for (int j = 1; j < J; ++j) sum += f[j] * sin_table[(s * j) % (2 * J)];
          c[s] = sum * 2.0L / J;
        }
        t.to_fourier[(static_cast<std::size_t>(l) * n + m) * n + s] = static_cast<double>(c[s]);
      }
      // Projections: cos(s t) cos(s' t) = [cos((s+s')t) + cos((s-s')t)] / 2 and
      // sin(s t) sin(s' t) = [cos((s-s')t) - cos((s+s')t)] / 2.
      for (int s = l % 2; s <= degree; s += 2) {
        long double sum = 0;
        for (int sp = l % 2; sp <= l; sp += 2) {
          const long double plus = cos_sin_integral(s + sp), minus = cos_sin_integral(s - sp);
          sum += c[sp] * 0.5L * (m % 2 == 0 ? plus + minus : minus - plus);
        }
        t.to_sh[(static_cast<std::size_t>(l) * n + m) * (degree + 1) + s] = static_cast<double>(sum);
      }
    }
  }
  return t;
}

Result<ShFourierTensors> ShFourierTensors::load(const std::filesystem::path& path) {
  return detail::load_kind<ShFourierTensors>(path, kShFourierTensorsKind);
}

Result<ShFourierTensors> ShFourierTensors::from_table(const Table& table) {
  if (table.kind != kShFourierTensorsKind) return fourier_error("wrong kind '" + table.kind + "'");
  if (const auto problem = detail::array_sizes_problem(table)) return fourier_error(*problem);
  if (!is_supported_order(table.order))
    return fourier_error("unsupported order " + std::to_string(table.order));
  const TableArray* tf = table.find("to_fourier");
  const TableArray* ts = table.find("to_sh");
  if (!tf || !ts || tf->dtype != DType::f64 || ts->dtype != DType::f64)
    return fourier_error("missing array or wrong dtype (need f64 'to_fourier', 'to_sh')");
  const std::int64_t n = table.order;
  if (tf->shape != std::vector<std::int64_t>{n, n, n} || ts->shape.size() != 3 ||
      ts->shape[0] != n || ts->shape[1] != n || ts->shape[2] < n || ts->shape[2] > 4097)
    return fourier_error("shapes must be to_fourier [N, N, N] and to_sh [N, N, D + 1] with "
                         "N - 1 <= D <= 4096");
  ShFourierTensors t;
  t.order = table.order;
  t.degree = static_cast<int>(ts->shape[2] - 1);
  t.to_fourier = tf->values<double>();
  t.to_sh = ts->values<double>();
  // Structural zeros must be zeros: a table with another layout fails here.
  for (int l = 0; l < t.order; ++l)
    for (int m = 0; m < t.order; ++m) {
      for (int s = 0; s < t.order; ++s) {
        const double v = t.fourier(l, m, s);
        if (!std::isfinite(v) || (v != 0.0 && (m > l || s > l || (s - l) % 2 != 0)))
          return fourier_error("to_fourier[" + std::to_string(l) + "][" + std::to_string(m) +
                               "][" + std::to_string(s) + "] breaks the reduced layout");
      }
      for (int s = 0; s <= t.degree; ++s) {
        const double v = t.projection(l, m, s);
        if (!std::isfinite(v) || (v != 0.0 && (m > l || (s - l) % 2 != 0)))
          return fourier_error("to_sh[" + std::to_string(l) + "][" + std::to_string(m) + "][" +
                               std::to_string(s) + "] breaks the reduced layout");
      }
    }
  return t;
}

}  // namespace shtool
