#include "tensors/tripling_kernels_gen.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "kernels/tripling_kernels.h"
#include "tensors/tripling.h"

namespace shtool {
namespace {

using detail::kTriplingKernelMaxOrder;

// Round-trip text of a double (17 significant digits), identical on every run.
std::string literal(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

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

// The kernel of one order, in outer-product form:
//   s_ij = f_i h_j + f_j h_i (j >= i),   y_k = sum_{i <= j} C'_ijk s_ij,
// C' = C_ijk for i < j and C_iik / 2 on the diagonal (s_ii = 2 f_i h_i, the halving exact).
// The rows of s are 8-wide vector operations (f_i and h_i broadcast against 8 of h and f);
// each y_k then sums its s entries, those with equal |C'| first and multiplied once, as
// balanced trees. Against the factored form DirectXMath's XMSHMultiplyN use (per index
// pair (i, j): tf = sum_k C_ijk f_k, th = sum_k C_ijk h_k feed y_i and y_j, and
// t = f_i h_j + f_j h_i feeds every y_k; 20 / 120 / 399 / 1135 / 2527 multiplications at
// N = 2..6), this measured 1.1-1.5x the speed of DirectXMath's fused (-march=native)
// build at N = 3..6 in float, 1.4-2.2x its SSE2 build (docs/products.md, "Product
// layout"): at N = 5, 51 vector rows and 623 scalar terms in 377 groups.
std::string kernel_source(int order, const std::vector<Entry>& entries) {
  const int count = order * order;
  const int chunks = count / 8;  // whole 8-wide chunks of columns
  // The terms C'_ijk s_ij of each output y_k, i <= j.
  struct Term {
    double c;
    int i, j;
    bool operator<(const Term& o) const { return std::tie(c, i, j) < std::tie(o.c, o.i, o.j); }
  };
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
  std::ostringstream s;
  int vector_rows = 0, scalar_entries = 0, scalar_terms = 0, groups = 0, outputs = 0;
  // The chunks cover the last 8 * chunks columns; the first `head` columns (j < head) are
  // scalar, and only rows i <= j < head need them (1 entry at orders 3 and 5). Column j
  // is stored at j + pad, so that every chunk starts on a vector boundary.
  const int head = count % 8, pad = (8 - head) % 8, width = count + pad;
  if (chunks > 0) {
    s << "  typedef T V __attribute__((vector_size(32)));  // 8 floats or 4 doubles\n";
    s << "  constexpr int kPer8 = 8 * sizeof(T) / sizeof(V);  // vectors per 8 columns\n";
    s << "  alignas(sizeof(V)) T s[" << count << "][" << width << "];\n";
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
  if (chunks > 0) s << "  asm volatile(\"\" : : \"r\"(&s[0][0]) : \"memory\");\n";
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
      s << "  y[" << k << "] = T(0);\n";
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
      const std::string c = literal(inner.positive ? size : -size);
      products.push_back({"T(" + c + ") * " + (inner.sum ? "(" + inner.expr + ")" : inner.expr), true});
      ++groups;
    }
    s << "  y[" << k << "] = " << balanced_sum(products).expr << ";\n";
    ++outputs;
  }
  std::ostringstream out;
  out << "// Order " << order << ": " << entries.size() << " canonical entries, outer-product form: "
      << vector_rows << " 8-wide rows and " << scalar_entries << " scalar entries of s (2 multiplications each), "
      << scalar_terms << " terms in " << groups << " groups (" << groups << " multiplications); "
      << 2 * scalar_entries + groups << " scalar multiplications, " << scalar_entries + scalar_terms - outputs
      << " scalar additions.\n";
  out << "template <class T>\n";
  out << "SHTOOL_KERNEL_CLONES void tripling_kernel_" << order << "(const T* f, const T* h, T* y) {\n";
  out << s.str();
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
       "// s_ij = f_i h_j + f_j h_i as 8-wide vectors, then y_k = sum_{i <= j} C'_ijk s_ij.\n\n";
  std::ostringstream tables;
  for (int order = 2; order <= kTriplingKernelMaxOrder; ++order) {
    const TriplingTensor tensor = compute_tripling_tensor_exact(order);
    std::vector<Entry> entries;
    for (std::size_t e = 0; e < tensor.size(); ++e)
      entries.push_back({static_cast<int>(tensor.index[3 * e]), static_cast<int>(tensor.index[3 * e + 1]),
                         static_cast<int>(tensor.index[3 * e + 2]), tensor.value[e]});
    s << kernel_source(order, entries);
    tables << "constexpr TriplingKernelEntry kEntries" << order << "[] = {\n";
    for (const Entry& e : entries)
      tables << "    {" << e.a << ", " << e.b << ", " << e.c << ", " << literal(e.value) << "},\n";
    tables << "};\n\n";
  }
  s << tables.str();
  s << "}  // namespace\n\n";
  s << "template <class T>\nTriplingKernel<T> tripling_kernel(int order) {\n  switch (order) {\n";
  for (int order = 2; order <= kTriplingKernelMaxOrder; ++order)
    s << "    case " << order << ":\n      return &tripling_kernel_" << order << "<T>;\n";
  s << "    default:\n      return nullptr;\n  }\n}\n\n";
  s << "template TriplingKernel<float> tripling_kernel<float>(int);\n";
  s << "template TriplingKernel<double> tripling_kernel<double>(int);\n\n";
  s << "std::span<const TriplingKernelEntry> tripling_kernel_entries(int order) {\n  switch (order) {\n";
  for (int order = 2; order <= kTriplingKernelMaxOrder; ++order)
    s << "    case " << order << ":\n      return kEntries" << order << ";\n";
  s << "    default:\n      return {};\n  }\n}\n\n";
  s << "}  // namespace shtool::detail\n";
  return s.str();
}

}  // namespace shtool
