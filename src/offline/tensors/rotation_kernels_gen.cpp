#include "tensors/rotation_kernels_gen.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/source_text.h"
#include "kernels/rotation_kernels.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool {
namespace {

using detail::kKernelMaxBand;
using detail::kKernelMaxOrder;
using detail::kBandKernelMaxBand;

// Sum of coefficient * variable terms as C++, accumulated left to right, each term after
// the first through madd<F> (rotation_kernels.h: fused in the FMA kernels, two roundings
// otherwise); exact zeros dropped, unit coefficients added without a multiplication.
// Empty sums give "".
std::string linear_sum(const std::vector<std::pair<double, std::string>>& terms) {
  std::string s;
  for (const auto& [c, name] : terms) {
    if (c == 0.0) continue;
    const bool neg = c < 0;
    const double a = std::abs(c);
    if (s.empty()) s = a == 1.0 ? (neg ? "-" + name : name) : "T(" + cpp_literal(c) + ") * " + name;
    else if (a == 1.0) s += (neg ? " - " : " + ") + name;
    else s = "madd<F>(T(" + cpp_literal(c) + "), " + name + ", " + s + ")";
  }
  return s;
}

// The pairs (m, -m) of band l that run in the lanes of one 4-float vector: groups
// m = m0 .. m0 + count - 1, count 2..4, from m0 = 1 in steps of 4; a lone last pair
// (count 1) stays scalar.
std::vector<std::pair<int, int>> lane_groups(int l) {
  std::vector<std::pair<int, int>> groups;
  for (int m = 1; l - m + 1 >= 2; m += 4) groups.emplace_back(m, std::min(4, l - m + 1));
  return groups;
}

// z-rotation of band l by angle x ([2] App. C: (f_m, f_-m) turns by m x), from
// variables src<j> (or src[j]) into dst<j>. cos(m x), sin(m x) are read from the state's
// tables (s.c<x>, s.s<x>) where they are used, which keeps few values live at a time.
// lanes (one float vector, P = float): groups of two to four pairs m run in the lanes of
// one 4-float vector, each lane doing the scalar pair's operations (so the same bits):
// 4 vector operations for up to 16 scalar ones; the tables are read four entries at a
// time (they are padded for it) and a lone last pair stays scalar. From and to arrays,
// the +m and the -m side of a group each move in one load or store (pairs_plus,
// pairs_minus, store_pairs_*), not lane by lane. src_vectors: the groups' inputs are
// already lane vectors, <src>p<m0> (+m side) and <src>m<m0> (-m side), as x90_lanes
// writes them; dst_vectors: the groups' results stay in their vectors zh<x><m0> (+m) and
// zl<x><m0> (-m), for x90_lanes to read. The m = 0 entry and a lone pair are scalars.
void z_rotation(std::ostream& o, int l, const std::string& angle, const std::string& src, bool src_array,
                const std::string& dst, bool dst_array, bool lanes = false, bool src_vectors = false,
                bool dst_vectors = false) {
  auto in = [&](int j) { return src_array ? src + "[" + std::to_string(j) + "]" : src + std::to_string(j); };
  auto out = [&](int j) {
    return dst_array ? std::string("  ").append(dst).append("[").append(std::to_string(j)).append("] = ")
                     : std::string("  const P ").append(dst).append(std::to_string(j)).append(" = ");
  };
  o << out(l) << in(l) << ";\n";
  int m = 1;
  for (const std::pair<int, int>& group : lanes ? lane_groups(l) : std::vector<std::pair<int, int>>{}) {
    // Plain names rather than a structured binding: the lambda below captures them, which
    // clang before 16 rejects for bindings.
    const int m0 = group.first, count = group.second;
    m = m0 + count;
    const std::string id = angle + std::to_string(m0);
    auto lanes_of = [&](int sign) {  // in(l + sign * (m0 + i)), i = 0..3, zero padded
      std::string v = "{";
      for (int i = 0; i < 4; ++i) v.append(i ? ", " : "").append(i < count ? in(l + sign * (m0 + i)) : "0");
      return v + "}";
    };
    o << "  const Lanes4 zc" << id << " = table_lanes(s.c" << angle << " + " << m0 << "), zs" << id
      << " = table_lanes(s.s" << angle << " + " << m0 << ");\n";
    if (src_vectors) {
      o << "  const Lanes4 zp" << id << " = " << src << "p" << m0 << ", zq" << id << " = " << src << "m" << m0 << ";\n";
    } else if (src_array) {
      o << "  const Lanes4 zp" << id << " = pairs_plus<" << count << ">(" << src << " + " << l + m0 << "), zq" << id
        << " = pairs_minus<" << count << ">(" << src << " + " << l - m0 << ");\n";
    } else {
      o << "  const Lanes4 zp" << id << " = " << lanes_of(1) << ", zq" << id << " = " << lanes_of(-1) << ";\n";
    }
    o << "  const Lanes4 zh" << id << " = madd<F>(zc" << id << ", zp" << id << ", -(zs" << id << " * zq" << id
      << "));\n";
    o << "  const Lanes4 zl" << id << " = madd<F>(zs" << id << ", zp" << id << ", zc" << id << " * zq" << id
      << ");\n";
    if (dst_array) {
      o << "  store_pairs_plus<" << count << ">(" << dst << " + " << l + m0 << ", zh" << id << ");\n";
      o << "  store_pairs_minus<" << count << ">(" << dst << " + " << l - m0 << ", zl" << id << ");\n";
    } else if (!dst_vectors) {
      for (int i = 0; i < count; ++i) o << out(l + m0 + i) << "zh" << id << "[" << i << "];\n";
      for (int i = 0; i < count; ++i) o << out(l - m0 - i) << "zl" << id << "[" << i << "];\n";
    }
  }
  for (; m <= l; ++m) {
    const std::string cm = "c" + angle + std::to_string(m), sm = "s" + angle + std::to_string(m);
    o << "  const P " << cm << " = splat<P>(s.c" << angle << "[" << m << "]), " << sm << " = splat<P>(s.s"
      << angle << "[" << m << "]);\n";
    o << out(l + m) << "madd<F>(" << cm << ", " << in(l + m) << ", -(" << sm << " * " << in(l - m) << "));\n";
    o << out(l - m) << "madd<F>(" << sm << ", " << in(l + m) << ", " << cm << " * " << in(l - m) << ");\n";
  }
}

// Bands up to this one run their X90 products in lanes too (x90_lanes) in the one-float-
// vector kernels; larger bands read each row's inputs from more lane groups, and the
// shuffles that gather them would cost more than the lanes save.
constexpr int kLaneX90MaxBand = 4;

// A lane vector gathered from the lanes of others: lane i of the result is lane
// lanes[i].second of the vector named lanes[i].first. One __builtin_shufflevector for
// two sources, one more for each further source (the compiler picks the instructions).
std::string gather(std::array<std::pair<std::string, int>, 4> lanes) {
  // A lane whose value is never read (empty name) repeats a neighbour's, which keeps the
  // pattern within two sources where it can.
  for (int i = 0; i < 4; ++i)
    if (lanes[i].first.empty()) lanes[i] = !lanes[i ^ 1].first.empty() ? lanes[i ^ 1] : lanes[i ^ 2];
  std::vector<std::string> sources;
  for (const auto& [v, lane] : lanes)
    if (std::find(sources.begin(), sources.end(), v) == sources.end()) sources.push_back(v);
  // at[i]: where lane i's value sits in `cur` so far (-1: not yet gathered).
  std::array<int, 4> at;
  for (int i = 0; i < 4; ++i) at[i] = lanes[i].first == sources[0] ? lanes[i].second : -1;
  if (sources.size() == 1 && at == std::array<int, 4>{0, 1, 2, 3}) return sources[0];
  std::string cur = sources[0];
  for (std::size_t k = sources.size() == 1 ? 0 : 1; k < sources.size(); ++k) {
    std::string next = "__builtin_shufflevector(" + cur + ", " + sources[k];
    for (int i = 0; i < 4; ++i) {
      if (k > 0 && lanes[i].first == sources[k]) at[i] = 4 + lanes[i].second;
      next += ", " + std::to_string(std::max(at[i], 0));
    }
    cur = next + ")";
    for (int i = 0; i < 4; ++i)
      if (at[i] >= 0) at[i] = i;
  }
  return cur;
}

// out_i = sum_j c(i, j) in_j for band l (c: X90's rows, or its columns when transposed),
// with both sides in lanes (one float vector): in_j is lane i of zh<angle><m0> (j = l +
// m0 + i) or zl<angle><m0> (j = l - m0 - i) as z_rotation leaves them, or the scalar
// <src><j> (m = 0, a lone pair); the outputs of each lane group are the vectors
// <dst>p<m0> and <dst>m<m0> that the next z-rotation takes, the others scalars <dst><j>.
// Each lane computes its row's linear_sum, term by term in the same order, so each lane
// has the scalar row's bits: a lane with fewer terms than the longest of its vector
// starts with padding, -1 times a zero lane (-0, which any sum leaves unchanged, as
// madd<F>(c, a, -0) = c * a), where the row's first product stands in the others.
void x90_lanes(std::ostream& o, int l, const std::vector<std::vector<double>>& x, bool transpose,
               const std::string& src, const std::string& angle, const std::string& dst) {
  const int size = 2 * l + 1;
  const auto groups = lane_groups(l);
  auto coefficient = [&](int i, int j) { return transpose ? x[j][i] : x[i][j]; };
  // Where each input sits; scalars (and a zero for padding) in the vector <src>s.
  std::vector<std::pair<std::string, int>> slot(size);
  std::vector<int> scalars;
  for (int j = 0; j < size; ++j) slot[j] = {"", -1};
  for (const auto& [m0, count] : groups)
    for (int i = 0; i < count; ++i) {
      slot[l + m0 + i] = {"zh" + angle + std::to_string(m0), i};
      slot[l - m0 - i] = {"zl" + angle + std::to_string(m0), i};
    }
  const std::string scalar_vector = src + "s";
  for (int j = 0; j < size; ++j)
    if (slot[j].second < 0) {
      slot[j] = {scalar_vector, static_cast<int>(scalars.size())};
      scalars.push_back(j);
    }
  const std::pair<std::string, int> zero = {scalar_vector, static_cast<int>(scalars.size())};
  if (scalars.size() > 3) throw std::logic_error("x90_lanes: more than three scalar entries");
  std::ostringstream vectors;
  bool uses_scalar_vector = false;
  for (const auto& [m0, count] : groups)
    for (const int sign : {1, -1}) {
      // Rows l + sign (m0 + i), i < count; their terms in linear_sum's order.
      std::array<std::vector<std::pair<double, int>>, 4> terms;
      std::size_t longest = 0;
      for (int i = 0; i < count; ++i) {
        const int row = l + sign * (m0 + i);
        for (int j = 0; j < size; ++j)
          if (coefficient(row, j) != 0.0) terms[i].emplace_back(coefficient(row, j), j);
        longest = std::max(longest, terms[i].size());
      }
      std::string sum;
      for (std::size_t k = 0; k < longest; ++k) {
        std::array<std::pair<std::string, int>, 4> lanes;
        std::string c = "Lanes4{";
        for (int i = 0; i < 4; ++i) {
          const std::size_t pad = longest - terms[i].size();
          if (i >= count) {  // a lane past the group: its value is never read
            lanes[i] = {"", -1};
            c += std::string(i ? ", " : "") + "T(0)";
          } else if (k < pad) {
            lanes[i] = zero;
            c += std::string(i ? ", " : "") + "T(-1)";
          } else {
            const auto& [value, j] = terms[i][k - pad];
            lanes[i] = slot[j];
            c += std::string(i ? ", " : "") + "T(" + cpp_literal(value) + ")";
          }
          uses_scalar_vector = uses_scalar_vector || lanes[i].first == scalar_vector;
        }
        c += "}";
        const std::string a = gather(lanes);
        sum = sum.empty() ? c + " * " + a : "madd<F>(" + c + ", " + a + ", " + sum + ")";
      }
      vectors << "  const Lanes4 " << dst << (sign > 0 ? "p" : "m") << m0 << " = " << sum << ";\n";
    }
  if (uses_scalar_vector) {
    o << "  const Lanes4 " << scalar_vector << " = {";
    for (int k = 0; k < 4; ++k)
      o << (k ? ", " : "") << (k < static_cast<int>(scalars.size()) ? indexed(src.c_str(), scalars[k]) : "0");
    o << "};\n";
  }
  o << vectors.str();
  // The scalar rows, from the scalars and lanes of the inputs they read.
  std::vector<bool> extracted(size, false);
  for (const int i : scalars) {
    std::vector<std::pair<double, std::string>> terms;
    for (int j = 0; j < size; ++j) {
      if (coefficient(i, j) == 0.0) continue;
      if (slot[j].first != scalar_vector && !extracted[j]) {
        o << "  const P " << src << j << " = " << slot[j].first << "[" << slot[j].second << "];\n";
        extracted[j] = true;
      }
      terms.emplace_back(coefficient(i, j), indexed(src.c_str(), j));
    }
    o << "  const P " << dst << i << " = " << linear_sum(terms) << ";\n";
  }
}

// The body of zxzxz_band<l>; lanes: the first and last z-rotations in float lanes
// (z_rotation), and up to kLaneX90MaxBand the X90 products and the middle z-rotation too
// (x90_lanes). Above it the middle z-rotation stays scalar: its input and output are the
// X90 rows' scalars, which would cost more shuffles into and out of lanes than the lanes
// save.
void zxzxz_body(std::ostream& o, const std::vector<std::vector<double>>& x, int l, bool lanes) {
  const int size = 2 * l + 1;
  if (lanes && l <= kLaneX90MaxBand) {
    z_rotation(o, l, "g", "x", true, "t", false, true, false, true);
    x90_lanes(o, l, x, false, "t", "g", "u");
    z_rotation(o, l, "b", "u", false, "w", false, true, true, true);
    x90_lanes(o, l, x, true, "w", "b", "v");
    z_rotation(o, l, "a", "v", false, "y", true, true, true, false);
    return;
  }
  z_rotation(o, l, "g", "x", true, "t", false, lanes);
  for (int i = 0; i < size; ++i) {
    std::vector<std::pair<double, std::string>> terms;
    for (int j = 0; j < size; ++j) terms.emplace_back(x[i][j], indexed("t", j));
    o << "  const P u" << i << " = " << linear_sum(terms) << ";\n";
  }
  z_rotation(o, l, "b", "u", false, "w", false);
  for (int i = 0; i < size; ++i) {
    std::vector<std::pair<double, std::string>> terms;
    for (int j = 0; j < size; ++j) terms.emplace_back(x[j][i], indexed("w", j));
    o << "  const P v" << i << " = " << linear_sum(terms) << ";\n";
  }
  z_rotation(o, l, "a", "v", false, "y", true, lanes);
}

void zxzxz_band(std::ostream& o, const RotationHelpers& h, int l) {
  const auto x = x90_band_block(h, l);
  // S: KernelState<T>, or BatchState<T> (a rotation per lane).
  o << "// Band " << l << " of Z(a) X90^T Z(b) X90 Z(g), Ry(b) = Rx(-90) Rz(b) Rx(+90).\n"
    << "template <bool F, class T, class P, class S>\n"
    << "SHTOOL_KERNEL_INLINE void zxzxz_band" << l
    << "(const S& s, const P* __restrict x, P* __restrict y) {\n"
    << "  if constexpr (std::is_same_v<P, float>) {  // one float vector: z-rotations in lanes\n";
  std::ostringstream body;
  zxzxz_body(body, x, l, true);
  std::istringstream lines(body.str());
  for (std::string line; std::getline(lines, line);) o << "  " << line << "\n";
  o << "  } else {\n";
  body.str("");
  zxzxz_body(body, x, l, false);
  lines = std::istringstream(body.str());
  for (std::string line; std::getline(lines, line);) o << "  " << line << "\n";
  o << "  }\n}\n\n";
}

void taylor_band(std::ostream& o, const RotationHelpers& h, int l) {
  const int size = 2 * l + 1, first = l * l;
  // D1[j][j-1] = sub[j], D1[j][j+1] = -sub[j+1] (antisymmetric); D2 diagonal and
  // distance-2 entries D2[j][j-2] = off2[j] = D2[j-2][j].
  auto sub = [&](int j) { return j >= 1 && j < size ? h.dy_sub[first + j] : 0.0; };
  auto off2 = [&](int j) { return j >= 2 && j < size ? h.ddy_off2[first + j] : 0.0; };
  auto t = [](int j) { return indexed("t", j); };
  o << "// Band " << l << " of Z(a) (I + b D1 [+ b^2/2 D2]) Z(g) ([2] Sec. 3).\n"
    << "template <bool F, int Order, class T, class P, class S>\n"
    << "SHTOOL_KERNEL_INLINE void taylor_band" << l
    << "(const S& s, const P* __restrict x, P* __restrict y) {\n";
  z_rotation(o, l, "g", "x", true, "t", false);
  o << "  const auto b = s.beta, h = s.half_beta2;\n  (void)h;\n";
  for (int j = 0; j < size; ++j) {
    std::vector<std::pair<double, std::string>> d1;
    if (j > 0) d1.emplace_back(sub(j), t(j - 1));
    if (j + 1 < size) d1.emplace_back(-sub(j + 1), t(j + 1));
    const std::string s1 = linear_sum(d1);
    if (s1.empty()) o << "  P u" << j << " = " << t(j) << ";\n";
    else o << "  P u" << j << " = madd<F>(b, " << s1 << ", " << t(j) << ");\n";
    const std::string diag = linear_sum({{h.ddy_diag[first + j], t(j)}});
    std::vector<std::pair<double, std::string>> d2 = {{h.ddy_diag[first + j], t(j)}};
    if (j >= 2) d2.emplace_back(off2(j), t(j - 2));
    if (j + 2 < size) d2.emplace_back(off2(j + 2), t(j + 2));
    const std::string full = linear_sum(d2);
    if (!diag.empty())
      o << "  if constexpr (Order == 15) u" << j << " = madd<F>(h, " << diag << ", u" << j << ");\n";
    if (!full.empty())
      o << "  if constexpr (Order == 2) u" << j << " = madd<F>(h, " << full << ", u" << j << ");\n";
  }
  z_rotation(o, l, "a", "u", false, "y", true);
  o << "}\n\n";
}

void order_function(std::ostream& o, bool taylor, int n) {
  const std::string name = (taylor ? "taylor_order" : "zxzxz_order") + std::to_string(n);
  // Bands 0..n-1 on lanes P. S: KernelState<T>, or BatchState<T> (a rotation per lane).
  if (taylor) o << "template <bool F, int Order, class T, class P, class S>\n";
  else o << "template <bool F, class T, class P, class S>\n";
  o << "SHTOOL_KERNEL_INLINE void " << name << "_bands(const S& s, const P* __restrict x, P* __restrict y) {\n"
    << "  y[0] = x[0];\n";
  for (int l = 1; l < n; ++l) {
    const std::string args =
        indexed("(s, x + ", l * l).append(", y + ").append(std::to_string(l * l)).append(");\n");
    if (taylor) o << "  taylor_band" << l << "<F, Order, T, P>" << args;
    // Band 1 is never fused: at order 2 apply() runs it inline, outside the kernels.
    else if (l == 1) o << "  band1_closed<T, P>(s.r, x + 1, y + 1);\n";
    // Bands 2 and 3 by their closed forms only where they save the Euler angles (orders
    // 3 and 4); once the angles are computed anyway, the zxzxz bands cost fewer operations.
    else if (l == 2 && n <= detail::kClosedMaxOrder) o << "  band2_closed<F, T, P>(s.r, x + 4, y + 4);\n";
    else if (l == 3 && n <= detail::kClosedMaxOrder) o << "  band3_closed<F, T, P>(s.r, x + 9, y + 9);\n";
    else o << "  zxzxz_band" << l << "<F, T, P>" << args;
  }
  if (n == 1) o << "  (void)s;\n";
  o << "}\n\n";
}

// The entry points of one function of bands (a whole order, or one band above them):
// one rotation of V lanes (one vector works in place on the caller's array, three
// interleaved channels are loaded into lane vectors and stored back, run_lanes), and a
// batch of rotations in lanes. Fused: the FMA copy, name suffix _fma, compiled for
// AVX2 + FMA (SHTOOL_FMA_TARGET), whose three lanes of doubles fill one AVX register
// (run_lanes' Avx).
void entry_functions(std::ostream& o, bool taylor, const std::string& body, int first, int count, bool fused) {
  const std::string targs = std::string(fused ? "true, " : "false, ") + (taylor ? "Order, T, " : "T, ");
  const bool whole_order = body.ends_with("_bands");
  const std::string base = whole_order ? body.substr(0, body.size() - 6) : body;
  const std::string fma = fused ? "_fma" : "";
  const std::string entry = base + (whole_order ? "" : "_entry") + fma, batch = base + "_batch" + fma;
  const char* attr = fused ? "SHTOOL_FMA_TARGET " : "";
  if (taylor) o << "template <int Order, class T, int V>\n";
  else o << "template <class T, int V>\n";
  o << attr << "void " << entry << "(const KernelState<T>& s, const T* const* in, T* const* out) {\n"
    << "  run_lanes<T, V, " << first << ", " << count << (fused ? ", true" : "")
    << ">(in, out, [&s](const auto* __restrict x, auto* __restrict y) SHTOOL_KERNEL_LAMBDA_INLINE {\n"
    << "    " << body << "<" << targs << "std::remove_cvref_t<decltype(*y)>>(s, x, y);\n"
    << "  });\n}\n\n";
  o << (taylor ? "template <int Order, class T>\n" : "template <class T>\n") << attr << "void " << batch
    << "(const BatchState<T>& s, const T* const* in, T* const* out) {\n"
    << "  run_batch_lanes<T, " << first << ", " << count
    << ">(in, out, [&s](const auto* __restrict x, auto* __restrict y) SHTOOL_KERNEL_LAMBDA_INLINE {\n"
    << "    " << body << "<" << targs << "BatchPack<T>>(s, x, y);\n"
    << "  });\n}\n\n";
}

// Every entry point, baseline or fused.
void all_entries(std::ostream& o, bool fused) {
  for (int l = kKernelMaxOrder; l <= kBandKernelMaxBand; ++l)
    for (bool taylor : {false, true})
      entry_functions(o, taylor, (taylor ? "taylor_band" : "zxzxz_band") + std::to_string(l), l * l, 2 * l + 1,
                      fused);
  for (bool taylor : {false, true})
    for (int n = 1; n <= kKernelMaxOrder; ++n)
      entry_functions(o, taylor, (taylor ? "taylor_order" : "zxzxz_order") + std::to_string(n) + "_bands", 0,
                      n * n, fused);
}

// The switch of a lookup from (method, order) or (method, band l) to the address of a
// generated function: over the four methods and over the whole orders
// 1..kKernelMaxOrder (orders) or the bands kKernelMaxOrder..kBandKernelMaxBand, returning
// &<zxzxz|taylor>_<order|band><n><suffix><[Order, ]targs>.
void lookup_switch(std::ostream& o, const char* var, bool orders, const std::string& suffix,
                   const std::string& targs, bool no_double_zxzxz, const char* indent) {
  const char* methods[4][2] = {{"0", ""}, {"1", "1, "}, {"15", "15, "}, {"2", "2, "}};
  const int lo = orders ? 1 : kKernelMaxOrder, hi = orders ? kKernelMaxOrder : kBandKernelMaxBand;
  o << indent << "switch (method) {\n";
  for (int k = 0; k < 4; ++k) {
    o << indent << "  case " << methods[k][0] << ":\n";
    if (k == 0 && no_double_zxzxz) o << indent << "    if constexpr (std::is_same_v<T, double>) return nullptr;\n";
    o << indent << "    switch (" << var << ") {\n";
    for (int n = lo; n <= hi; ++n)
      o << indent << "      case " << n << ": return &" << (k == 0 ? "zxzxz_" : "taylor_") << (orders ? "order" : "band")
        << n << suffix << "<" << methods[k][1] << targs << ">;\n";
    o << indent << "    }\n" << indent << "    break;\n";
  }
  o << indent << "}\n";
}

// A lookup function: `signature` opens it; the fused switch first (where built), then the
// baseline one.
void lookup_function(std::ostream& o, const std::string& signature, const char* var, bool orders,
                     const std::string& suffix, const std::string& targs, bool no_double_zxzxz) {
  o << signature << "#if SHTOOL_FMA_KERNELS\n  if (fused) {\n";
  lookup_switch(o, var, orders, suffix + "_fma", targs, no_double_zxzxz, "    ");
  o << "    return nullptr;\n  }\n#else\n  (void)fused;\n#endif\n";
  lookup_switch(o, var, orders, suffix, targs, no_double_zxzxz, "  ");
  o << "  return nullptr;\n}\n\n";
}

}  // namespace

std::string rotation_kernels_source() {
  const RotationHelpers h = compute_rotation_helpers(kBandKernelMaxBand + 1);
  std::ostringstream o;
  o << "// Generated by `shtool gen-tensors --what rotation-kernels --out src/runtime/kernels`\n"
       "// (src/offline/tensors/rotation_kernels_gen.cpp) from the rotation helpers of\n"
       "// compute_rotation_helpers: X90 = M(Rx(+90 deg)), D1 and D2. Do not edit: the test\n"
       "// test_rotation_kernels regenerates this file and compares the bytes. Templates only:\n"
       "// rotation_kernels_float.cpp and rotation_kernels_double.cpp instantiate them, one\n"
       "// precision per translation unit, so the two compile side by side.\n"
       "#include \"rotation_kernels.h\"\n\n"
       "#include <type_traits>\n\n"
       "namespace shtool::detail {\n\n"
       "static_assert(kKernelMaxBand == "
    << kKernelMaxBand
    << ", \"regenerate rotation_kernels_generated.inc\");\n\n"
       "namespace {\n\n";
  for (int l = 2; l <= kBandKernelMaxBand; ++l) zxzxz_band(o, h, l);
  for (int l = 1; l <= kBandKernelMaxBand; ++l) taylor_band(o, h, l);
  for (int n = 1; n <= kKernelMaxOrder; ++n) order_function(o, false, n);
  for (int n = 1; n <= kKernelMaxOrder; ++n) order_function(o, true, n);
  all_entries(o, false);
  o << "#if SHTOOL_FMA_KERNELS\n\n";
  all_entries(o, true);
  o << "#endif  // SHTOOL_FMA_KERNELS\n\n";
  o << "}  // namespace\n\n";
  lookup_function(o,
                  "template <class T, int V>\nRotationKernel<T, V> rotation_kernel(int method, int order, bool fused) {\n"
                  "  if (order < 1) return nullptr;\n"
                  "  if (order > kKernelMaxOrder) order = kKernelMaxOrder;\n",
                  "order", true, "", "T, V", false);
  // Double zxzxz bands above the whole-order kernels run the paired X90 rows of
  // rotation.cpp, so their band kernels would be dead code (and batches running them
  // would not match apply() bit for bit): not instantiated.
  lookup_function(o, "template <class T, int V>\nRotationKernel<T, V> band_kernel(int method, int l, bool fused) {\n",
                  "l", false, "_entry", "T, V", true);
  lookup_function(o, "template <class T>\nBatchKernel<T> batch_kernel(int method, int order, bool fused) {\n", "order",
                  true, "_batch", "T", false);
  lookup_function(o, "template <class T>\nBatchKernel<T> batch_band_kernel(int method, int l, bool fused) {\n", "l",
                  false, "_batch", "T", true);
  o << "\n}  // namespace shtool::detail\n";
  return o.str();
}

}  // namespace shtool
