#include "tensors/rotation_kernels_gen.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/rotation_kernels.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool {
namespace {

using detail::kKernelMaxBand;
using detail::kKernelMaxOrder;
using detail::kBandKernelMaxBand;

// prefix followed by the number (append: GCC 12 warns, wrongly, -Wrestrict about
// "literal" + std::string at -O3).
std::string indexed(const char* prefix, int j) { return std::string(prefix).append(std::to_string(j)); }

// Round-trip text of a double (17 significant digits), identical on every run.
std::string literal(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

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
    if (s.empty()) s = a == 1.0 ? (neg ? "-" + name : name) : "T(" + literal(c) + ") * " + name;
    else if (a == 1.0) s += (neg ? " - " : " + ") + name;
    else s = "madd<F>(T(" + literal(c) + "), " + name + ", " + s + ")";
  }
  return s;
}

// z-rotation of band l by angle x ([2] App. C: (f_m, f_-m) turns by m x), from
// variables src<j> (or src[j]) into dst<j>. cos(m x), sin(m x) are read from the state's
// tables (s.c<x>, s.s<x>) where they are used, which keeps few values live at a time.
// lanes (one float vector, P = float): groups of two to four pairs m run in the lanes of
// one 4-float vector, each lane doing the scalar pair's operations (so the same bits):
// 4 vector operations for up to 16 scalar ones; the tables are read four entries at a
// time (they are padded for it) and a lone last pair stays scalar. From and to arrays,
// the +m and the -m side of a group each move in one load or store (pairs_plus,
// pairs_minus, store_pairs_*), not lane by lane.
void z_rotation(std::ostream& o, int l, const std::string& angle, const std::string& src, bool src_array,
                const std::string& dst, bool dst_array, bool lanes = false) {
  auto in = [&](int j) { return src_array ? src + "[" + std::to_string(j) + "]" : src + std::to_string(j); };
  auto out = [&](int j) {
    return dst_array ? std::string("  ").append(dst).append("[").append(std::to_string(j)).append("] = ")
                     : std::string("  const P ").append(dst).append(std::to_string(j)).append(" = ");
  };
  o << out(l) << in(l) << ";\n";
  int m = 1;
  for (; lanes && l - m + 1 >= 2; m += 4) {
    const int count = std::min(4, l - m + 1);
    const std::string id = angle + std::to_string(m);
    auto lanes_of = [&](int sign) {  // in(l + sign * (m + i)), i = 0..3, zero padded
      std::string v = "{";
      for (int i = 0; i < 4; ++i) v.append(i ? ", " : "").append(i < count ? in(l + sign * (m + i)) : "0");
      return v + "}";
    };
    o << "  const Lanes4 zc" << id << " = table_lanes(s.c" << angle << " + " << m << "), zs" << id
      << " = table_lanes(s.s" << angle << " + " << m << ");\n";
    if (src_array) {
      o << "  const Lanes4 zp" << id << " = pairs_plus<" << count << ">(" << src << " + " << l + m << "), zq" << id
        << " = pairs_minus<" << count << ">(" << src << " + " << l - m << ");\n";
    } else {
      o << "  const Lanes4 zp" << id << " = " << lanes_of(1) << ", zq" << id << " = " << lanes_of(-1) << ";\n";
    }
    o << "  const Lanes4 zh" << id << " = madd<F>(zc" << id << ", zp" << id << ", -(zs" << id << " * zq" << id
      << "));\n";
    o << "  const Lanes4 zl" << id << " = madd<F>(zs" << id << ", zp" << id << ", zc" << id << " * zq" << id
      << ");\n";
    if (dst_array) {
      o << "  store_pairs_plus<" << count << ">(" << dst << " + " << l + m << ", zh" << id << ");\n";
      o << "  store_pairs_minus<" << count << ">(" << dst << " + " << l - m << ", zl" << id << ");\n";
    } else {
      for (int i = 0; i < count; ++i) o << out(l + m + i) << "zh" << id << "[" << i << "];\n";
      for (int i = 0; i < count; ++i) o << out(l - m - i) << "zl" << id << "[" << i << "];\n";
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

// The body of zxzxz_band<l>; lanes: the first and last z-rotations in float lanes
// (z_rotation). The middle one stays scalar: its input and output are the X90 rows'
// scalars, which would cost more shuffles into and out of lanes than the lanes save.
void zxzxz_body(std::ostream& o, const std::vector<std::vector<double>>& x, int l, bool lanes) {
  const int size = 2 * l + 1;
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
// one rotation of V vectors (one vector works in place on the caller's arrays, three are
// gathered into lanes first), and a batch of rotations in lanes. Fused: the FMA copy,
// name suffix _fma, compiled for AVX2 + FMA (SHTOOL_FMA_TARGET).
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
    << "  run_lanes<T, V, " << first << ", " << count
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
       "// test_rotation_kernels regenerates this file and compares the bytes.\n"
       "#include \"rotation_kernels.h\"\n\n"
       "#include <type_traits>\n\n"
       "namespace shtool::detail {\n\n"
       "static_assert(kKernelMaxBand == "
    << kKernelMaxBand
    << ", \"regenerate rotation_kernels_generated.cpp\");\n\n"
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
  for (const char* type : {"float", "double"})
    o << "template BatchKernel<" << type << "> batch_kernel<" << type << ">(int, int, bool);\n"
      << "template BatchKernel<" << type << "> batch_band_kernel<" << type << ">(int, int, bool);\n";
  for (const char* type : {"float", "double"})
    for (int v : {1, 3})
      o << "template RotationKernel<" << type << ", " << v << "> rotation_kernel<" << type << ", " << v
        << ">(int, int, bool);\n"
        << "template RotationKernel<" << type << ", " << v << "> band_kernel<" << type << ", " << v
        << ">(int, int, bool);\n";
  o << "\n}  // namespace shtool::detail\n";
  return o.str();
}

}  // namespace shtool
