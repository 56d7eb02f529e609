#include "tensors/tripling_kernels_gen.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "common/source_text.h"
#include "kernels/tripling_kernels.h"
#include "tensors/tripling.h"

namespace shtool {
namespace {

using detail::kTriplingKernelMaxOrder;

// One canonical entry C_abc (a <= b <= c) of the exact tripling tensor.
struct Entry {
  int a, b, c;
  double value;
};

// A signed sum as a balanced tree, ((a + b) + (c + d)), not a chain: the dependent
// additions behind each output drop from n - 1 to log2 n (measured 1.1-1.2x faster than
// chains at N = 3..5). `positive` says whether the tree is the sum or its negation.
struct Signed {
  std::string expr;
  bool positive;
  bool sum = false;  // expr is a sum (parenthesised when it is an operand)
};
Signed balanced_sum(const std::vector<Signed>& items) {
  if (items.size() == 1) return items[0];
  const std::size_t half = items.size() / 2;
  const Signed a = balanced_sum({items.begin(), items.begin() + half});
  const Signed b = balanced_sum({items.begin() + half, items.end()});
  auto wrap = [](const Signed& x) { return x.sum ? "(" + x.expr + ")" : x.expr; };
  if (a.positive == b.positive) return {wrap(a) + " + " + wrap(b), a.positive, true};
  return a.positive ? Signed{wrap(a) + " - " + wrap(b), true, true} : Signed{wrap(b) + " - " + wrap(a), true, true};
}

// One term C'_ijk s_ij of an output y_k (i <= j).
struct Term {
  double c;
  int i, j;
  bool operator<(const Term& o) const { return std::tie(c, i, j) < std::tie(o.c, o.i, o.j); }
};

// The terms of each output y_k, k < count: C'_ijk s_ij for i <= j, with C' = C_ijk for
// i < j and C_iik / 2 on the diagonal (s_ii = 2 f_i h_i, the halving exact).
std::vector<std::vector<Term>> output_terms(int count, const std::vector<Entry>& entries) {
  std::vector<std::vector<Term>> terms(count);
  auto add = [&](int i, int j, int k, double c) { terms[k].push_back({i == j ? c / 2 : c, i, j}); };
  for (const Entry& e : entries) {
    // Each distinct index ordering of {a, b, c} as (i, j | k) with i <= j, once.
    const int idx[3] = {e.a, e.b, e.c};
    std::vector<std::array<int, 3>> seen;
    for (int k = 0; k < 3; ++k) {
      std::array<int, 3> t = {std::min(idx[(k + 1) % 3], idx[(k + 2) % 3]),
                              std::max(idx[(k + 1) % 3], idx[(k + 2) % 3]), idx[k]};
      if (std::find(seen.begin(), seen.end(), t) != seen.end()) continue;
      seen.push_back(t);
      add(t[0], t[1], t[2], e.value);
    }
  }
  return terms;
}

// Order 3 in the permutation form. Its 9 coefficients are y_0 and the 8 lanes y_1..y_8,
// and row i of s, (s_i1 .. s_i8) = f_i (h_1..h_8) + h_i (f_1..f_8), is 8 lanes too. Within
// a row, C' sends each s_ij to a few outputs, so the row's part of y_1..y_8 is a sum of
// "layers": each a permutation of the row's lanes (an output lane takes at most one s_ij
// per layer, a lane may feed several) times a vector of coefficients. 12 layers cover the
// 9 rows. Each row and each layer is emitted as two 4-wide halves (outputs y_1..y_4 and
// y_5..y_8), a half without coefficients left out: 18 row halves and 18 multiply-adds into
// 4 partial sums, all in registers, no stack array, and every permutation an in-lane
// shuffle of the row's two halves (146 instructions in the float AVX2 copy, none of them
// a lane-crossing permutation; the 8-wide form was 99 instructions with 11 `vpermd`,
// 1.5x slower on AMD Zen 1, whose 256-bit operations are two 128-bit halves anyway).
// y_0 = C_000 sum_i f_i h_i (the only nonzero C_ij0 are C_ii0 = C_000). At orders 4..6
// the outputs span several vectors and the rows are not kept in registers.
std::string permutation_kernel_source(int order, const std::vector<Entry>& entries) {
  const int count = order * order;
  if (count != 9) throw std::logic_error("tripling kernels: the permutation form is for order 3");
  const std::vector<std::vector<Term>> terms = output_terms(count, entries);
  // y_0: every term diagonal, one coefficient.
  const double c0 = terms[0].at(0).c;
  for (const Term& t : terms[0])
    if (t.i != t.j || t.c != c0) throw std::logic_error("tripling kernels: y_0 is not C_000 f . h");
  // Layers per row, greedily in (j, k) order: lane k - 1 of a layer takes s_ij (lane j - 1).
  struct Layer {
    int row;
    std::array<int, 8> lane{};  // source lane per output lane (0 where unused)
    std::array<double, 8> c{};  // coefficient per output lane (0 where unused)
    std::array<bool, 8> used{};
  };
  std::vector<Layer> layers;
  for (int i = 0; i < count; ++i) {
    std::vector<std::pair<int, std::pair<int, double>>> row;  // (j, (k, c))
    for (int k = 1; k < count; ++k)
      for (const Term& t : terms[k])
        if (t.i == i) {
          if (t.j == 0) throw std::logic_error("tripling kernels: s_00 feeds an output above y_0");
          row.push_back({t.j, {k, t.c}});
        }
    std::sort(row.begin(), row.end());
    const std::size_t first = layers.size();
    for (const auto& [j, kc] : row) {
      const int k = kc.first;
      std::size_t l = first;
      while (l < layers.size() && layers[l].used[k - 1]) ++l;
      if (l == layers.size()) layers.push_back({i, {}, {}, {}});
      layers[l].lane[k - 1] = j - 1;
      layers[l].c[k - 1] = kc.second;
      layers[l].used[k - 1] = true;
    }
  }
  // Each layer splits into its two 4-wide halves (output lanes 1..4 and 5..8), a half
  // with no coefficient dropped: one 4-wide operation there is what an 8-wide one costs
  // on CPUs whose vector units are 128 bits wide, and a permutation into one half reads
  // the row's two halves with in-lane shuffles where an 8-wide one crosses them (the
  // integer permutation, 3 operations there). Unused lanes are left to the compiler (-1).
  struct Half {
    int row;
    std::array<int, 4> lane;
    std::array<double, 4> c;
  };
  std::vector<Half> halves[2];
  for (const Layer& layer : layers)
    for (int h = 0; h < 2; ++h) {
      Half half{layer.row, {}, {}};
      bool any = false;
      for (int k = 0; k < 4; ++k) {
        const int lane = 4 * h + k;
        half.lane[k] = layer.used[lane] ? layer.lane[lane] : -1;
        half.c[k] = layer.used[lane] ? layer.c[lane] : 0.0;
        any |= layer.used[lane];
      }
      if (any) halves[h].push_back(half);
    }
  std::ostringstream s;
  s << "// Order " << order << ": " << entries.size() << " canonical entries, permutation form: 9 rows "
    << "of 8 (2 multiplications each, as two 4-wide halves), " << layers.size() << " layers, as "
    << halves[0].size() << " + " << halves[1].size() << " 4-wide multiply-adds; y_0 from one 8-wide product "
    << "and 8 scalar additions; 2 scalar multiplications, 8 scalar additions.\n";
  s << "template <class T>\n";
  s << "SHTOOL_KERNEL_CLONES void tripling_kernel_" << order << "(const T* f, const T* h, T* y) {\n";
  s << "  typedef T V4 __attribute__((vector_size(4 * sizeof(T))));  // 4 floats or 4 doubles\n";
  s << "  typedef T U4 __attribute__((vector_size(4 * sizeof(T)), aligned(alignof(T)), may_alias));\n";
  s << "  const V4 fl = *reinterpret_cast<const U4*>(f + 1), fh = *reinterpret_cast<const U4*>(f + 5);\n";
  s << "  const V4 hl = *reinterpret_cast<const U4*>(h + 1), hh = *reinterpret_cast<const U4*>(h + 5);\n";
  for (int i = 0; i < count; ++i)
    s << "  const V4 rl" << i << " = f[" << i << "] * hl + h[" << i << "] * fl, rh" << i << " = f[" << i
      << "] * hh + h[" << i << "] * fh;\n";
  const char* names[2] = {"lo", "hi"};
  for (int h = 0; h < 2; ++h) {
    if (halves[h].size() < 2) throw std::logic_error("tripling kernels: a half of order 3 with fewer than 2 layers");
    for (std::size_t n = 0; n < halves[h].size(); ++n) {
      const Half& half = halves[h][n];
      const std::string row = std::to_string(half.row);
      std::string source;
      if (half.lane == std::array<int, 4>{4 * h, 4 * h + 1, 4 * h + 2, 4 * h + 3}) {
        source = (h ? "rh" : "rl") + row;
      } else {
        // A lane whose coefficient is 0 takes the first used lane's value, never -1
        // ("any value"): clang may leave an undefined lane as anything, NaN and infinity
        // among them, and 0 times those is not 0.
        int used = 0;
        for (int k = 3; k >= 0; --k)
          if (half.lane[k] >= 0) used = half.lane[k];
        source = "__builtin_shufflevector(rl" + row + ", rh" + row;
        for (int k = 0; k < 4; ++k) source += ", " + std::to_string(half.lane[k] >= 0 ? half.lane[k] : used);
        source += ")";
      }
      std::string coefficients = "V4{";
      for (int k = 0; k < 4; ++k) coefficients += (k ? ", T(" : "T(") + cpp_literal(half.c[k]) + ")";
      coefficients += "}";
      s << "  " << (n < 2 ? "V4 " : "") << names[h] << n % 2 << " " << (n < 2 ? "= " : "+= ") << coefficients
        << " * " << source << ";\n";
    }
  }
  s << "  const V4 dl = fl * hl, dh = fh * hh;\n";
  s << "  y[0] = T(" << cpp_literal(2 * c0) << ") * (f[0] * h[0] + (((dl[0] + dl[1]) + (dl[2] + dl[3])) + ((dh[0] + dh[1]) + (dh[2] + dh[3]))));\n";
  s << "  *reinterpret_cast<U4*>(y + 1) = lo0 + lo1;\n";
  s << "  *reinterpret_cast<U4*>(y + 5) = hi0 + hi1;\n";
  s << "}\n\n";
  return s.str();
}

// The kernel of one order (2, 4, 5, 6; order 3: permutation_kernel_source), in
// outer-product form with scalar sums:
//   s_ij = f_i h_j + f_j h_i (j >= i),   y_k = sum_{i <= j} C'_ijk s_ij.
// The rows of s are 8-wide vector operations (f_i and h_i broadcast against 8 of h and f);
// each y_k then sums its s entries, those with equal |C'| first and multiplied once, as
// balanced trees. Against the factored form DirectXMath's XMSHMultiplyN use (per index
// pair (i, j): tf = sum_k C_ijk f_k, th = sum_k C_ijk h_k feed y_i and y_j, and
// t = f_i h_j + f_j h_i feeds every y_k; 20 / 120 / 399 / 1135 / 2527 multiplications at
// N = 2..6), this measured 1.36-1.58x the speed of DirectXMath's fused (-march=native)
// build at N = 4..6 in float, 1.85-2.13x its SSE2 build (docs/benchmarks.md, "Against
// DirectXMath"): at N = 5, 51 vector rows and 623 scalar terms in 377 groups.
// From this order on the outer-product kernel is two functions, the rows and the sums,
// called one after the other: compiled as one, GCC 12 allocates the sums' registers
// worse (values moved through general registers, more spills), and the kernel took
// 1.25x / 1.3x as long at orders 5 / 6 in float on AMD Zen 1, measured on the AVX2 copy
// (no difference at order 4). Orders from 5 on have whole 8-wide chunks of columns.
constexpr int kSplitFromOrder = 5;

std::string kernel_source(int order, const std::vector<Entry>& entries) {
  const int count = order * order;
  const int chunks = count / 8;  // whole 8-wide chunks of columns
  std::vector<std::vector<Term>> terms = output_terms(count, entries);
  const bool split = order >= kSplitFromOrder;  // rows and sums as two functions
  std::ostringstream s, sums_out;
  int vector_rows = 0, scalar_entries = 0, scalar_terms = 0, groups = 0, outputs = 0;
  // The chunks cover the last 8 * chunks columns; the first `head` columns (j < head) are
  // scalar, and only rows i <= j < head need them (1 entry at orders 3 and 5). Column j
  // is stored at j + pad, so that every chunk starts on a vector boundary.
  const int head = count % 8, pad = (8 - head) % 8, width = count + pad;
  if (chunks > 0) {
    s << "  typedef T V __attribute__((vector_size(32)));  // 8 floats or 4 doubles\n";
    s << "  constexpr int kPer8 = 8 * sizeof(T) / sizeof(V);  // vectors per 8 columns\n";
    if (!split) s << "  alignas(sizeof(V)) T s[" << count << "][" << width << "];\n";
    s << "  V fv[" << chunks << " * kPer8], hv[" << chunks << " * kPer8];\n";
    s << "  load_rows(f, h, " << head << ", " << chunks << " * kPer8, fv, hv);\n";
  } else {
    s << "  T s[" << count << "][" << width << "];\n";
  }
  for (int i = 0; i < count; ++i) {
    int first = 0;  // the first chunk that reaches the diagonal
    while (first < chunks && head + 8 * first + 7 < i) ++first;
    if (first < chunks) {
      s << "  pair_row(f[" << i << "], h[" << i << "], fv + " << first << " * kPer8, hv + " << first
        << " * kPer8, " << chunks - first << " * kPer8, &s[" << i << "][" << head + pad + 8 * first << "]);\n";
      vector_rows += chunks - first;
    }
    for (int j = i; j < head; ++j) {
      s << "  s[" << i << "][" << j + pad << "] = f[" << i << "] * h[" << j << "] + h[" << i << "] * f[" << j
        << "];\n";
      ++scalar_entries;
    }
  }
  // Without this the compiler keeps the rows in registers and takes the lanes out one
  // by one with shuffles (measured 1.5x slower at order 5): here s goes to memory once
  // and each term below is one load.
  // (In the split form the call between the two functions does the same.)
  if (chunks > 0 && !split) s << "  asm volatile(\"\" : : \"r\"(&s[0][0]) : \"memory\");\n";
  std::ostringstream& y_out = split ? sums_out : s;
  for (int k = 0; k < count; ++k) {
    std::sort(terms[k].begin(), terms[k].end());
    // Groups of equal |C'|, in order of first appearance.
    std::vector<std::pair<double, std::vector<Term>>> by_size;
    for (const Term& t : terms[k]) {
      auto it = std::find_if(by_size.begin(), by_size.end(),
                             [&](const auto& g) { return g.first == std::abs(t.c); });
      if (it == by_size.end()) by_size.push_back({std::abs(t.c), {t}});
      else it->second.push_back(t);
    }
    if (by_size.empty()) {
      y_out << "  y[" << k << "] = T(0);\n";
      continue;
    }
    std::vector<Signed> products;
    for (const auto& [size, members] : by_size) {
      std::vector<Signed> sum;
      for (const Term& t : members) {
        sum.push_back({"s[" + std::to_string(t.i) + "][" + std::to_string(t.j + pad) + "]", t.c > 0});
        ++scalar_terms;
      }
      const Signed inner = balanced_sum(sum);
      const std::string c = cpp_literal(inner.positive ? size : -size);
      products.push_back({"T(" + c + ") * " + (inner.sum ? "(" + inner.expr + ")" : inner.expr), true});
      ++groups;
    }
    y_out << "  y[" << k << "] = " << balanced_sum(products).expr << ";\n";
    ++outputs;
  }
  std::ostringstream out;
  out << "// Order " << order << ": " << entries.size() << " canonical entries, outer-product form: "
      << vector_rows << " 8-wide rows and " << scalar_entries << " scalar entries of s (2 multiplications each), "
      << scalar_terms << " terms in " << groups << " groups (" << groups << " multiplications); "
      << 2 * scalar_entries + groups << " scalar multiplications, " << scalar_entries + scalar_terms - outputs
      << " scalar additions.\n";
  const std::string n = std::to_string(order), shape = "[" + std::to_string(width) + "]";
  if (!split) {
    out << "template <class T>\n";
    out << "SHTOOL_KERNEL_CLONES void tripling_kernel_" << n << "(const T* f, const T* h, T* y) {\n";
    out << s.str();
    out << "}\n\n";
    return out.str();
  }
  out << "template <class T>\n";
  out << "SHTOOL_KERNEL_CLONES __attribute__((noinline)) void tripling_rows_" << n
      << "(const T* f, const T* h, T (*s)" << shape << ") {\n";
  out << s.str();
  out << "}\n\n";
  out << "template <class T>\n";
  out << "SHTOOL_KERNEL_CLONES __attribute__((noinline)) void tripling_sums_" << n << "(T (*s)" << shape
      << ", T* y) {\n";
  out << sums_out.str();
  out << "}\n\n";
  out << "template <class T>\n";
  out << "void tripling_kernel_" << n << "(const T* f, const T* h, T* y) {\n";
  out << "  alignas(32) T s[" << count << "]" << shape << ";\n";
  out << "  tripling_rows_" << n << "(f, h, s);\n";
  out << "  tripling_sums_" << n << "(s, y);\n";
  out << "}\n\n";
  return out.str();
}

}  // namespace

std::string tripling_kernels_source() {
  std::ostringstream s;
  s << "// Generated by `shtool gen-tensors --what tripling-kernels --out src/runtime/kernels`\n"
       "// (src/offline/tensors/tripling_kernels_gen.cpp) from the exact tripling tensor\n"
       "// (compute_tripling_tensor_exact, Wigner 3j). Do not edit: the test test_tripling\n"
       "// regenerates this file and compares the bytes.\n"
       "#include \"tripling_kernels.h\"\n\n"
       "namespace shtool::detail {\n\n"
       "static_assert(kTriplingKernelMaxOrder == "
    << kTriplingKernelMaxOrder
    << ", \"regenerate tripling_kernels_generated.cpp\");\n\n"
       "namespace {\n\n"
       "// Unaligned, aliasing access to 32 bytes of T (one vector load or store; a memcpy\n"
       "// there compiled to two 16-byte halves that the vector load then waited for).\n"
       "template <class T>\n"
       "struct Unaligned32 {\n"
       "  typedef T type __attribute__((vector_size(32), aligned(alignof(T)), may_alias));\n"
       "};\n\n"
       "// fv[q], hv[q] = the q-th vector of f + offset and h + offset, q < n.\n"
       "template <class T, class V>\n"
       "inline void load_rows(const T* f, const T* h, int offset, int n, V* fv, V* hv) {\n"
       "  constexpr int lanes = sizeof(V) / sizeof(T);\n"
       "  for (int q = 0; q < n; ++q) {\n"
       "    fv[q] = *reinterpret_cast<const typename Unaligned32<T>::type*>(f + offset + q * lanes);\n"
       "    hv[q] = *reinterpret_cast<const typename Unaligned32<T>::type*>(h + offset + q * lanes);\n"
       "  }\n"
       "}\n\n"
       "// Columns of one row of s: out = f_i hv + h_i fv, n vectors.\n"
       "template <class T, class V>\n"
       "inline void pair_row(T fi, T hi, const V* fv, const V* hv, int n, T* out) {\n"
       "  constexpr int lanes = sizeof(V) / sizeof(T);\n"
       "  for (int q = 0; q < n; ++q) *reinterpret_cast<typename Unaligned32<T>::type*>(out + q * lanes) = fi * hv[q] + hi * fv[q];\n"
       "}\n\n"
       "// The kernels use the outer-product form of tripling_kernels_gen.cpp: the rows of\n"
       "// s_ij = f_i h_j + f_j h_i as 8-wide vectors, then y_k = sum_{i <= j} C'_ijk s_ij,\n"
       "// order 3 by permutations of the rows, the others by scalar sums.\n\n";
  std::ostringstream tables;
  for (int order = 2; order <= kTriplingKernelMaxOrder; ++order) {
    const TriplingTensor tensor = compute_tripling_tensor_exact(order);
    std::vector<Entry> entries;
    for (std::size_t e = 0; e < tensor.size(); ++e)
      entries.push_back({static_cast<int>(tensor.index[3 * e]), static_cast<int>(tensor.index[3 * e + 1]),
                         static_cast<int>(tensor.index[3 * e + 2]), tensor.value[e]});
    s << (order == 3 ? permutation_kernel_source(order, entries) : kernel_source(order, entries));
    tables << "constexpr TriplingKernelEntry kEntries" << order << "[] = {\n";
    for (const Entry& e : entries)
      tables << "    {" << e.a << ", " << e.b << ", " << e.c << ", " << cpp_literal(e.value) << "},\n";
    tables << "};\n\n";
  }
  s << tables.str();
  s << "}  // namespace\n\n";
  // A function `signature` that returns value(order) for each generated order, `fallback`
  // for any other.
  auto order_switch = [&s](const std::string& signature, const std::function<std::string(int)>& value,
                           const std::string& fallback) {
    s << signature << " {\n  switch (order) {\n";
    for (int order = 2; order <= kTriplingKernelMaxOrder; ++order)
      s << "    case " << order << ":\n      return " << value(order) << ";\n";
    s << "    default:\n      return " << fallback << ";\n  }\n}\n\n";
  };
  order_switch(
      "template <class T>\nTriplingKernel<T> tripling_kernel(int order)",
      [](int order) { return "&tripling_kernel_" + std::to_string(order) + "<T>"; }, "nullptr");
  s << "template TriplingKernel<float> tripling_kernel<float>(int);\n";
  s << "template TriplingKernel<double> tripling_kernel<double>(int);\n\n";
  order_switch(
      "std::span<const TriplingKernelEntry> tripling_kernel_entries(int order)",
      [](int order) { return "kEntries" + std::to_string(order); }, "{}");
  s << "}  // namespace shtool::detail\n";
  return s.str();
}

}  // namespace shtool
