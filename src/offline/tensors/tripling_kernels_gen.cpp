#include "tensors/tripling_kernels_gen.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdio>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "kernels/tripling_kernels.h"
#include "tensors/tripling.h"

namespace shtool {
namespace {

using detail::kTriplingKernelMaxOrder;

// The orders generated in the outer-product form (outer_kernel_source); the others in the
// factored form (kernel_source).
constexpr std::array<int, 5> kOuterFormOrders = {2, 3, 4, 5, 6};

// Round-trip text of a double (17 significant digits), identical on every run.
std::string literal(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

struct Entry {
  int a, b, c;
  double value;
};

// A block: the index pair (i, j) and the entries {i, j, k} it carries, each with its
// third index k; for i == j the entry {i, i, i} is the "self" term (k == i).
struct Block {
  int i, j;
  std::vector<std::pair<int, double>> terms;
};

// Every canonical entry C_abc feeds up to three outputs,
//   g_a += C (f_b h_c + f_c h_b),  g_b += C (f_a h_c + f_c h_a),  g_c += C (f_a h_b + f_b h_a).
// Grouped by an index pair (i, j), the entries {i, j, k_1..k_n} of a block cost
//   tf = sum C f_k, th = sum C h_k;  g_i += tf h_j + th f_j;  g_j += tf h_i + th f_i;
//   t = f_i h_j + f_j h_i;  g_k += C t
// 3n + 6 multiplications instead of 9n. Entries with a repeated index r, {r, r, k}, must go
// to the block (r, r) (another pair would count one of their terms twice); each entry
// with three distinct indices can go to any of its three pairs, and a greedy cover puts
// it with the pair that collects the most entries (fewer, larger blocks).
std::vector<Block> make_blocks(const std::vector<Entry>& entries) {
  std::map<std::pair<int, int>, Block> blocks;
  std::vector<const Entry*> distinct;
  for (const Entry& e : entries) {
    if (e.a == e.b || e.b == e.c) {
      const int r = e.a == e.b ? e.a : e.c;  // the repeated index
      const int k = e.a == e.b ? e.c : e.a;  // the other one (r itself for {r, r, r})
      Block& b = blocks[{r, r}];
      b.i = b.j = r;
      b.terms.push_back({k, e.value});
    } else {
      distinct.push_back(&e);
    }
  }
  auto pairs_of = [](const Entry& e) {
    return std::array<std::pair<int, int>, 3>{{{e.a, e.b}, {e.a, e.c}, {e.b, e.c}}};
  };
  std::map<std::pair<int, int>, int> open;  // unassigned entries per candidate pair
  for (const Entry* e : distinct)
    for (const auto& p : pairs_of(*e)) ++open[p];
  std::vector<bool> done(distinct.size(), false);
  for (std::size_t left = distinct.size(); left > 0;) {
    // the pair with the most open entries; ties to the smallest pair (deterministic)
    auto best = open.begin();
    for (auto it = open.begin(); it != open.end(); ++it)
      if (it->second > best->second) best = it;
    const std::pair<int, int> p = best->first;
    Block& b = blocks[p];
    b.i = p.first;
    b.j = p.second;
    for (std::size_t n = 0; n < distinct.size(); ++n) {
      if (done[n]) continue;
      const Entry& e = *distinct[n];
      const auto candidates = pairs_of(e);
      if (std::find(candidates.begin(), candidates.end(), p) == candidates.end()) continue;
      done[n] = true;
      --left;
      for (const auto& q : candidates) --open[q];
      const int k = e.a + e.b + e.c - p.first - p.second;
      b.terms.push_back({k, e.value});
    }
  }
  std::vector<Block> out;
  for (auto& [key, b] : blocks) {
    std::sort(b.terms.begin(), b.terms.end());
    out.push_back(std::move(b));
  }
  return out;
}

// Straight-line code of one order. Outputs are written "=" on their first update and
// "+=" after; y is a plain pointer, so the compiler reloads f and h after each store
// rather than keeping all of them live and spilling them (measured: the kernels then
// compile to the instruction mix of DirectXMath's XMSHMultiplyN). A variant on lane
// pairs, (f_k, h_k) with one vector multiplication for two scalar ones, needed 35-40 %
// fewer multiplications but was no faster (SSE2 moves of the 8-byte pairs ate the gain).
std::string kernel_source(int order, const std::vector<Block>& blocks, std::size_t entries) {
  std::ostringstream s;
  const int count = order * order;
  std::vector<bool> written(count, false);
  int mults = 0;
  auto update = [&](int k, const std::string& expr) {
    s << "  y[" << k << "] " << (written[k] ? "+=" : "=") << " " << expr << ";\n";
    written[k] = true;
  };
  for (const Block& b : blocks) {
    std::vector<std::pair<int, double>> others;
    double self = 0;
    bool has_self = false;
    for (const auto& [k, v] : b.terms) {
      if (b.i == b.j && k == b.i) {
        self = v;
        has_self = true;
      } else {
        others.push_back({k, v});
      }
    }
    s << "  // [" << b.i << "," << b.j << "]:";
    for (const auto& [k, v] : b.terms) s << " " << k;
    s << "\n";
    const std::string i = std::to_string(b.i), j = std::to_string(b.j);
    if (!others.empty()) {
      for (const char* x : {"f", "h"}) {
        s << "  t" << x << " = ";
        for (std::size_t n = 0; n < others.size(); ++n)
          s << (n ? " + " : "") << "T(" << literal(others[n].second) << ") * " << x << "["
            << others[n].first << "]";
        s << ";\n";
      }
      mults += 2 * static_cast<int>(others.size());
      update(b.i, "tf * h[" + j + "] + th * f[" + j + "]");
      mults += 2;
      if (b.i != b.j) {
        update(b.j, "tf * h[" + i + "] + th * f[" + i + "]");
        mults += 2;
      }
    }
    if (b.i == b.j) {
      s << "  t = f[" << i << "] * h[" << i << "];\n";
      mults += 1;
    } else {
      s << "  t = f[" << i << "] * h[" << j << "] + f[" << j << "] * h[" << i << "];\n";
      mults += 2;
    }
    for (const auto& [k, v] : others) {
      update(k, "T(" + literal(v) + ") * t");
      ++mults;
    }
    if (has_self) {
      update(b.i, "T(" + literal(self) + ") * t");
      ++mults;
    }
  }
  std::ostringstream out;
  out << "// Order " << order << ": " << entries << " canonical entries in " << blocks.size()
      << " blocks, " << mults << " multiplications.\n";
  out << "template <class T>\n";
  out << "SHTOOL_KERNEL_CLONES void tripling_kernel_" << order << "(const T* f, const T* h, T* y) {\n";
  out << "  T tf, th, t;\n";
  out << s.str();
  for (int k = 0; k < count; ++k)
    if (!written[k]) out << "  y[" << k << "] = T(0);\n";
  out << "}\n\n";
  return out.str();
}

// A signed sum as a balanced tree, ((a + b) + (c + d)), not a chain: the dependent
// additions behind each output drop from n - 1 to log2 n, which at order 3 is most of the
// kernel's latency. `positive` says whether the tree is the sum or its negation.
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

// The outer-product form, for the orders where it measured faster (kOuterFormOrders):
//   s_ij = f_i h_j + f_j h_i (j >= i),   y_k = sum_{i <= j} C'_ijk s_ij,
// C' = C_ijk for i < j and C_iik / 2 on the diagonal (s_ii = 2 f_i h_i, the halving exact).
// The rows of s are 8-wide vector operations (a broadcast of f_i, h_i against 8 of h, f);
// each y_k then sums its s entries, those with equal |C'| first and multiplied once. At
// order 5 that is 623 scalar terms and 377 multiplications against the factored form's
// 1135 multiplications: measured 1.5x faster there, and no faster at orders 3 and 4,
// where the factored form's blocks are small and s is mostly unused.
std::string outer_kernel_source(int order, const std::vector<Entry>& entries) {
  const int count = order * order;
  const int chunks = count / 8;  // whole 8-wide chunks of columns
  // The terms of each output: (C', i, j), i <= j, sorted.
  std::vector<std::vector<std::array<double, 3>>> terms(count);
  auto add = [&](int i, int j, int k, double c) {
    if (i > j) std::swap(i, j);
    terms[k].push_back({i == j ? c / 2 : c, double(i), double(j)});
  };
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
  int vector_rows = 0, tail = 0, scalar_terms = 0, groups = 0;
  // The chunks cover the last 8 * chunks columns; the first `head` columns (j < head) are
  // scalar, and only rows i <= j < head need them (1 entry at orders 3 and 5). Column j
  // is stored at j + pad, so that every chunk starts on a vector boundary.
  const int head = count % 8, pad = (8 - head) % 8, width = count + pad;
  if (chunks > 0) {
    s << "  typedef T V __attribute__((vector_size(8 * sizeof(T))));\n";
    s << "  alignas(sizeof(V)) T s[" << count << "][" << width << "];\n";
    s << "  V fv[" << chunks << "], hv[" << chunks << "];\n";
  } else {
    s << "  T s[" << count << "][" << width << "];\n";
  }
  for (int c = 0; c < chunks; ++c)
    s << "  __builtin_memcpy(&fv[" << c << "], f + " << head + 8 * c << ", sizeof(V));\n"
      << "  __builtin_memcpy(&hv[" << c << "], h + " << head + 8 * c << ", sizeof(V));\n";
  for (int i = 0; i < count; ++i) {
    for (int c = 0; c < chunks; ++c) {
      if (head + 8 * c + 7 < i) continue;  // the chunk lies below the diagonal
      s << "  { const V r = f[" << i << "] * hv[" << c << "] + h[" << i << "] * fv[" << c
        << "]; __builtin_memcpy(&s[" << i << "][" << head + pad + 8 * c << "], &r, sizeof(V)); }\n";
      ++vector_rows;
    }
    for (int j = i; j < head; ++j) {
      s << "  s[" << i << "][" << j + pad << "] = f[" << i << "] * h[" << j << "] + h[" << i << "] * f[" << j
        << "];\n";
      ++tail;
    }
  }
  // Without this the compiler keeps the rows in registers and takes the lanes out one
  // by one with shuffles (measured 1.5x slower at order 5): here s goes to memory once
  // and each term below is one load.
  if (chunks > 0) s << "  asm volatile(\"\" : : \"r\"(&s[0][0]) : \"memory\");\n";
  for (int k = 0; k < count; ++k) {
    std::sort(terms[k].begin(), terms[k].end());
    // Groups of equal |C'|, in order of first appearance.
    std::vector<std::pair<double, std::vector<std::array<double, 3>>>> by_size;
    for (const auto& t : terms[k]) {
      auto it = std::find_if(by_size.begin(), by_size.end(),
                             [&](const auto& g) { return g.first == std::abs(t[0]); });
      if (it == by_size.end()) by_size.push_back({std::abs(t[0]), {t}});
      else it->second.push_back(t);
    }
    if (by_size.empty()) {
      s << "  y[" << k << "] = T(0);\n";
      continue;
    }
    std::vector<Signed> products;
    for (const auto& [size, members] : by_size) {
      std::vector<Signed> sum;
      for (const auto& t : members) {
        sum.push_back({"s[" + std::to_string(int(t[1])) + "][" + std::to_string(int(t[2]) + pad) + "]", t[0] > 0});
        ++scalar_terms;
      }
      const Signed inner = balanced_sum(sum);
      const std::string c = literal(inner.positive ? size : -size);
      products.push_back({"T(" + c + ") * " + (inner.sum ? "(" + inner.expr + ")" : inner.expr), true});
      ++groups;
    }
    s << "  y[" << k << "] = " << balanced_sum(products).expr << ";\n";
  }
  std::ostringstream out;
  out << "// Order " << order << ": " << entries.size() << " canonical entries, outer-product form: "
      << vector_rows << " 8-wide rows and " << tail << " scalar entries of s (2 multiplications each), "
      << scalar_terms << " terms in " << groups << " groups (" << groups << " multiplications).\n";
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
       "// Orders 2..4 use the factored form of tripling_kernels_gen.cpp: per index pair (i, j),\n"
       "// tf = sum_k C_ijk f_k and th = sum_k C_ijk h_k feed y_i and y_j, and\n"
       "// t = f_i h_j + f_j h_i feeds every y_k. Orders 5 and 6 use its outer-product form:\n"
       "// the rows of s_ij = f_i h_j + f_j h_i as vectors, then y_k = sum C'_ijk s_ij.\n\n";
  std::ostringstream tables;
  for (int order = 2; order <= kTriplingKernelMaxOrder; ++order) {
    const TriplingTensor tensor = compute_tripling_tensor_exact(order);
    std::vector<Entry> entries;
    for (std::size_t e = 0; e < tensor.size(); ++e)
      entries.push_back({static_cast<int>(tensor.index[3 * e]), static_cast<int>(tensor.index[3 * e + 1]),
                         static_cast<int>(tensor.index[3 * e + 2]), tensor.value[e]});
    s << (std::find(kOuterFormOrders.begin(), kOuterFormOrders.end(), order) != kOuterFormOrders.end()
              ? outer_kernel_source(order, entries)
              : kernel_source(order, make_blocks(entries), entries.size()));
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
