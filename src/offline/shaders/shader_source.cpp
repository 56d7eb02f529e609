#include "shaders/shader_source.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <numbers>
#include <sstream>
#include <utility>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/source_text.h"
#include "shtool/irradiance.h"
#include "shtool/probe_encoding.h"
#include "shtool/table.h"
#include "shtool/version.h"
#include "tensors/rotation_helpers_gen.h"
#include "tensors/tripling.h"

namespace shtool {
namespace {

// The two languages differ in type names and in how a 3x3 matrix is indexed; the rest
// of what is generated (declarations, arithmetic, arrays, loops) is common syntax.
struct Syntax {
  ShaderLanguage language;
  bool half;

  bool glsl() const { return language == ShaderLanguage::glsl; }
  std::string real() const { return half ? (glsl() ? "mediump float" : "min16float") : "float"; }
  std::string vec3() const { return half ? (glsl() ? "mediump vec3" : "min16float3") : (glsl() ? "vec3" : "float3"); }
  // The rotation matrix stays float at both precisions (glslang has no min16float3x3).
  std::string mat3() const { return glsl() ? "mat3" : "float3x3"; }
  // R(i, j), row i and column j of the mathematical matrix. GLSL's mat3 is a list of
  // columns (R[c][r]); HLSL's float3x3 a list of rows (R[r][c]).
  std::string r(int i, int j) const {
    return "R[" + std::to_string(glsl() ? j : i) + "][" + std::to_string(glsl() ? i : j) + "]";
  }
};

// A constant as the shader's float: rounded once from long double, then 9 significant
// digits, which read back to the same float.
std::string literal(long double v) {
  // A constant beyond float (or NaN) would be "inf" in the source, which no compiler takes.
  if (!finite_as_float(static_cast<double>(v))) throw InputError("a shader constant is not finite as a float");
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(static_cast<float>(v)));
  std::string s = buf;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

// c1 * t1 + c2 * t2 + ... with exact zeros dropped and unit factors without a
// multiplication; "" if every coefficient is zero.
std::string linear_sum(const std::vector<std::pair<long double, std::string>>& terms) {
  std::string s;
  for (const auto& [c, name] : terms) {
    if (static_cast<float>(c) == 0.0f) continue;
    const long double a = std::fabs(c);
    const std::string term = static_cast<float>(a) == 1.0f ? name : literal(a) + " * " + name;
    if (s.empty()) s = c < 0 ? "-" + term : term;
    else s += (c < 0 ? " - " : " + ") + term;
  }
  return s;
}

// Binary operations written in code (comments skipped): what the generated function
// asks the compiler for, before its own folding.
void count_ops(std::string_view code, long times, ShaderSource& out) {
  std::size_t start = 0;
  while (start < code.size()) {
    std::size_t end = code.find('\n', start);
    if (end == std::string_view::npos) end = code.size();
    std::string_view line = code.substr(start, end - start);
    if (const std::size_t c = line.find("//"); c != std::string_view::npos) line = line.substr(0, c);
    for (std::size_t i = 0; i + 3 <= line.size(); ++i) {
      const std::string_view op = line.substr(i, 3);
      if (op == " * ") out.multiplications += times;
      else if (op == " + " || op == " - ") out.additions += times;
    }
    start = end + 1;
  }
}

// Normalisation of the associated Legendre recurrence with the azimuthal factor
// (x + i y)^m taken out: y_l^m = q_l^m(z) Re (x + i y)^m for m > 0 (Im for m < 0), with
//   q_m^m     = (-1)^m sqrt2 K_m^m (2m - 1)!!   (no sqrt2 at m = 0),
//   q_m+1^m   = sqrt(2m + 3) z q_m^m,
//   q_l^m     = a_lm z q_l-1^m + b_lm q_l-2^m,
//   a_lm = sqrt((4l^2 - 1) / (l^2 - m^2)),  b_lm = -sqrt(((l-1)^2 - m^2)(2l + 1) / ((2l - 3)(l^2 - m^2))),
// the three-term recurrence of the orthonormal associated Legendre functions with K_l^m
// folded in.
long double sectoral_constant(int m) {
  long double q = std::sqrt(1.0L / (4.0L * std::numbers::pi_v<long double>));
  for (int k = 1; k <= m; ++k) q *= -std::sqrt((2.0L * k + 1.0L) / (2.0L * k));
  return m > 0 ? q * std::numbers::sqrt2_v<long double> : q;
}

// (append: GCC 12 warns, wrongly, -Wrestrict about "literal" + std::string at -O3)
std::string basis_name(int i) { return std::string("b").append(std::to_string(i)); }

// Statements that compute the basis at the unit direction `dir`: y_i into `out[i]` when
// `out` is an array name, else into locals b<i>. Bands with wanted[l] false are not
// formed (their Legendre factors still are, as the recurrence needs them).
std::string basis_code(const Syntax& s, int n, const std::string& dir, const std::string& out,
                       const std::vector<bool>& wanted, const std::string& indent) {
  std::ostringstream o;
  const std::string real = s.real();
  auto assign = [&](int l, int m, const std::string& expr) {
    if (!wanted[l]) return;
    const int i = l * (l + 1) + m;
    if (out.empty()) o << indent << real << " " << basis_name(i) << " = " << expr << ";\n";
    else o << indent << out << "[" << i << "] = " << expr << ";\n";
  };
  if (n > 1) o << indent << real << " px = " << dir << ".x;\n" << indent << real << " py = " << dir << ".y;\n"
               << indent << real << " pz = " << dir << ".z;\n";
  // Re and Im of (x + i y)^m, m >= 1.
  for (int m = 1; m < n; ++m) {
    const std::string c = indexed("c", m), sn = indexed("s", m);
    if (m == 1) {
      o << indent << real << " c1 = px;\n" << indent << real << " s1 = py;\n";
      continue;
    }
    const std::string pc = indexed("c", m - 1), ps = indexed("s", m - 1);
    o << indent << real << " " << c << " = px * " << pc << " - py * " << ps << ";\n"
      << indent << real << " " << sn << " = px * " << ps << " + py * " << pc << ";\n";
  }
  for (int m = 0; m < n; ++m) {
    const long double qmm = sectoral_constant(m);
    auto q = [m](int l) { return indexed("q", l).append("_").append(std::to_string(m)); };
    auto with_azimuth = [&](int l, const std::string& factor) {
      if (m == 0) {
        assign(l, 0, factor);
        return;
      }
      assign(l, m, factor + " * c" + std::to_string(m));
      assign(l, -m, factor + " * s" + std::to_string(m));
    };
    with_azimuth(m, literal(qmm));
    if (m + 1 >= n) continue;
    o << indent << real << " " << q(m + 1) << " = " << literal(std::sqrt(2.0L * m + 3.0L) * qmm) << " * pz;\n";
    with_azimuth(m + 1, q(m + 1));
    for (int l = m + 2; l < n; ++l) {
      const long double ll = l, mm = m;
      const long double a = std::sqrt((4 * ll * ll - 1) / (ll * ll - mm * mm));
      const long double b =
          -std::sqrt(((ll - 1) * (ll - 1) - mm * mm) * (2 * ll + 1) / ((2 * ll - 3) * (ll * ll - mm * mm)));
      o << indent << real << " " << q(l) << " = " << literal(a) << " * pz * " << q(l - 1);
      if (l - 2 == m) o << (b * qmm < 0 ? " - " : " + ") << literal(std::fabs(b * qmm)) << ";\n";
      else o << " - " << literal(-b) << " * " << q(l - 2) << ";\n";
      with_azimuth(l, q(l));
    }
  }
  return o.str();
}

// The band sums of a dot product with the basis locals, each scaled by factor[l]
// (bands whose factor is 0 are left out): factor_l * (c[l^2] * b_l^2 + ...).
std::string band_dot(int n, const std::string& coeffs, const std::vector<long double>& factor,
                     const std::vector<std::string>& band_weight) {
  std::string sum;
  for (int l = 0; l < n; ++l) {
    if (factor[l] == 0) continue;
    std::string band;
    for (int m = -l; m <= l; ++m) {
      const int i = l * (l + 1) + m;
      if (!band.empty()) band += " + ";
      band += coeffs + "[" + std::to_string(i) + "] * " + basis_name(i);
    }
    std::string term = "(" + band + ")";
    if (!band_weight.empty()) term = band_weight[l] + " * " + term;
    if (static_cast<float>(factor[l]) != 1.0f) term = literal(factor[l]) + " * " + term;
    sum += (sum.empty() ? "" : " + ") + term;
  }
  return sum.empty() ? "0.0" : sum;
}

std::string array(const std::string& type, const std::string& name, const std::string& size) {
  return type + " " + name + "[" + size + "]";
}

const char* kCount = "SHTOOL_ORDER * SHTOOL_ORDER";

// y_l^m(dir) for every l < N.
void sh_eval(const Syntax& s, int n, std::ostringstream& o, ShaderSource& out) {
  const std::string head = "void shtool_sh_eval(" + s.vec3() + " dir, out " + array(s.real(), "y", kCount) + ")";
  const std::string body = basis_code(s, n, "dir", "y", std::vector<bool>(n, true), "  ");
  count_ops(body, 1, out);
  out.signature = head + ";";
  o << "// y[l * (l + 1) + m] = y_l^m(dir) for l < SHTOOL_ORDER, dir a unit vector (not normalised here).\n"
    << head << " {\n" << body << "}\n";
}

// E(n) = sum_l A_l sum_m L_lm y_l^m(n), the clamped-cosine kernel A_l folded in.
void sh_irradiance(const Syntax& s, int n, std::ostringstream& o, ShaderSource& out) {
  std::vector<long double> a(n);
  std::vector<bool> wanted(n);
  for (int l = 0; l < n; ++l) {
    a[l] = clamped_cosine_band(l);
    wanted[l] = a[l] != 0;
  }
  const std::string basis = basis_code(s, n, "n", "", wanted, "  ");
  // One body for both: L[i] * b_i is a float or a vec3 product.
  const std::string scalar = "  return " + band_dot(n, "L", a, {}) + ";\n";
  const std::string head1 = s.real() + " shtool_sh_irradiance(" + s.vec3() + " n, " + array(s.real(), "L", kCount) + ")";
  const std::string head3 = s.vec3() + " shtool_sh_irradiance_rgb(" + s.vec3() + " n, " + array(s.vec3(), "L", kCount) + ")";
  count_ops(basis + scalar, 1, out);
  out.signature = head1 + ";\n" + head3 + ";";
  o << "// Irradiance E(n) = integral L(w) max(n . w, 0) dw of radiance coefficients L (no 1/pi folded\n"
       "// in: divide by pi for the exit radiance of a white Lambertian surface); n a unit vector.\n"
    << head1 << " {\n" << basis << scalar << "}\n\n"
    << "// The same for RGB radiance coefficients.\n"
    << head3 << " {\n" << basis << scalar << "}\n";
}

// Band sums as cube-map textures: texture k (RGBA) holds the band sums of bands 4k..4k+3
// (channel c = band 4k + c), as shtool_sh_band_sums computes them, at nodes that include
// the face edges: texel (i, j) of an S x S face at face coordinates sc = 2i / (S-1) - 1,
// tc = 2j / (S-1) - 1 (the runtime's ZhLightTable layout). A face's edge nodes are the same
// points as its neighbour's, so interpolation is continuous across faces and never needs
// the neighbour's texels; hardware seamless filtering of texel-centre values would instead
// blend across the fold with a first-order error.
int band_textures(int n) { return (n + 3) / 4; }

// Preamble of a function that fetches band textures: band_k = (S-1)/S, which maps face
// coordinates onto the node layout (texture_fetches). Every band texture has bands0's size.
std::string texture_preamble(const Syntax& s) {
  if (s.glsl()) return "  float band_k = float(textureSize(bands0, 0).x - 1) / float(textureSize(bands0, 0).x);\n";
  return "  uint band_w, band_h;\n  bands0.GetDimensions(band_w, band_h);\n"
         "  float band_k = float(band_w - 1u) / float(band_w);\n";
}

// The texture parameters of a function: GLSL combined samplers, HLSL textures and one sampler.
std::string texture_params(const Syntax& s, int n) {
  std::string p;
  for (int k = 0; k < band_textures(n); ++k)
    // GLSL ES gives samplers a default precision of lowp: a fetch would come back with an
    // 8-bit step and a range of (-2, 2). Desktop GLSL accepts the qualifier and ignores it.
    p += (k ? ", " : "") +
         std::string(s.glsl() ? (s.half ? "mediump samplerCube bands" : "highp samplerCube bands")
                              : "TextureCube<float4> bands") +
         std::to_string(k);
  if (!s.glsl()) p += ", SamplerState bands_sampler";
  return p;
}

// Statements fetching every band texture at `dir` (level 0: compute and vertex shaders have
// no derivatives) into <prefix>0, <prefix>1, ... A face coordinate x in [-1, 1] lies at
// texel position (x + 1) / 2 (S - 1) on the node layout, i.e. at hardware coordinate
// ((x + 1) / 2 (S - 1) + 1/2) / S, which is the face coordinate x (S - 1) / S: the two
// minor components of the direction are scaled by band_k = (S - 1) / S and the major one
// kept, whatever the face's orientation (the map is odd). The scaled direction stays on
// its face and between the first and last texel centres, so filtering never crosses a fold.
std::string texture_fetches(const Syntax& s, int n, const std::string& dir, const std::string& prefix,
                            const std::string& indent) {
  const std::string v3 = s.glsl() ? "vec3" : "float3";
  std::string o = indent + v3 + " " + prefix + "a = abs(" + dir + ");\n" + indent + v3 + " " + prefix + "d = " +
                  dir + " * (" + prefix + "a.x >= " + prefix + "a.y && " + prefix + "a.x >= " + prefix + "a.z ? " +
                  v3 + "(1.0, band_k, band_k) : (" + prefix + "a.y >= " + prefix + "a.z ? " + v3 +
                  "(band_k, 1.0, band_k) : " + v3 + "(band_k, band_k, 1.0)));\n";
  const std::string type = s.half ? (s.glsl() ? "mediump vec4" : "min16float4") : (s.glsl() ? "vec4" : "float4");
  const std::string at = prefix + "d";
  for (int k = 0; k < band_textures(n); ++k) {
    const std::string t = "bands" + std::to_string(k);
    o += indent + type + " " + prefix + std::to_string(k) + " = " +
         (s.glsl() ? "textureLod(" + t + ", " + at + ", 0.0)" : t + ".SampleLevel(bands_sampler, " + at + ", 0)") +
         ";\n";
  }
  return o;
}

// Band l of the fetched texels: <prefix><l / 4>.<xyzw[l % 4]>.
std::string texel_band(const std::string& prefix, int l) {
  return prefix + std::to_string(l / 4) + "." + "xyzw"[l % 4];
}

// shtool_sh_band_sums: the per-band sums sum_m c_lm y_l^m(dir), what the band textures hold.
// Guarded on its own, as two files of one order may both define it.
void band_sums(const Syntax& s, int n, std::ostringstream& o, ShaderSource& out) {
  const std::string head = "void shtool_sh_band_sums(" + s.vec3() + " dir, " + array(s.real(), "c", kCount) +
                           ", out " + array(s.real(), "bands", "SHTOOL_ORDER") + ")";
  std::string body = basis_code(s, n, "dir", "", std::vector<bool>(n, true), "  ");
  for (int l = 0; l < n; ++l) {
    std::vector<long double> only(n, 0);
    only[l] = 1;
    body += "  bands[" + std::to_string(l) + "] = " + band_dot(n, "c", only, {}) + ";\n";
  }
  out.signature += head + ";\n";
  o << "#define SHTOOL_BAND_TEXTURES " << band_textures(n) << "\n"
    << "#ifndef SHTOOL_SH_BAND_SUMS_DEFINED\n#define SHTOOL_SH_BAND_SUMS_DEFINED\n"
    << "// bands[l] = sum_m c[l * (l + 1) + m] y_l^m(dir), dir a unit vector. Band texture k (cube map,\n"
       "// RGBA float, SHTOOL_BAND_TEXTURES of them, all S x S, S >= 2, linear filtering) holds bands\n"
       "// 4k..4k+3 in its channels x, y, z, w; texel (i, j) of a face holds them at the direction of face\n"
       "// coordinates (sc, tc) = (2i / (S-1) - 1, 2j / (S-1) - 1), edges and corners included (the API's\n"
       "// face selection rule otherwise). Interpolation error: about l (l + 1) / (2 (S-1)^2) of band l's size.\n"
    << head << " {\n" << body << "}\n#endif\n\n";
}

// Exit radiance of ZH lobes under SH lighting, Eq. 13 of [4].
void zh_shade(const Syntax& s, int n, int lobes, std::ostringstream& o, ShaderSource& out) {
  const std::string head = s.real() + " shtool_zh_shade(" + array(s.vec3(), "axes", "SHTOOL_ZH_LOBES") + ", " +
                           array(s.real(), "g", "SHTOOL_ZH_LOBES * SHTOOL_ORDER") + ", " +
                           array(s.real(), "e", kCount) + ")";
  const std::string basis = basis_code(s, n, "axes[i]", "", std::vector<bool>(n, true), "    ");
  std::vector<std::string> weight(n);
  for (int l = 0; l < n; ++l) weight[l] = "g[i * SHTOOL_ORDER + " + std::to_string(l) + "]";
  const std::string dot = "    r += " + band_dot(n, "e", std::vector<long double>(n, 1), weight) + ";\n";
  count_ops(basis + dot, lobes, out);
  out.signature = head + ";\n";
  o << "#define SHTOOL_ZH_LOBES " << lobes << "\n\n"
    << "// r = sum_i sum_l g[i * SHTOOL_ORDER + l] sum_m y_l^m(axes[i]) e[l * (l + 1) + m]: lobe i has unit\n"
       "// axis axes[i] and convolved ZH coefficients g_il (a lobe adds g_il y_l^m(axis) to coefficient\n"
       "// (l, m)); e is the SH lighting.\n"
    << head << " {\n  " << s.real() << " r = 0.0;\n  for (int i = 0; i < SHTOOL_ZH_LOBES; ++i) {\n"
    << basis << dot << "  }\n  return r;\n}\n\n";
  // Eq. 24-25: the band sums of the lighting e^_l(s) tabulated (band textures), then per
  // lobe one fetch per four bands and an N-term dot product.
  band_sums(s, n, o, out);
  const std::string head2 = s.real() + " shtool_zh_shade_table(" + array(s.vec3(), "axes", "SHTOOL_ZH_LOBES") +
                            ", " + array(s.real(), "g", "SHTOOL_ZH_LOBES * SHTOOL_ORDER") + ", " +
                            texture_params(s, n) + ")";
  std::string sum;
  for (int l = 0; l < n; ++l)
    sum += (l ? " + " : "") + weight[l] + " * " + texel_band("t", l);
  out.signature += head2 + ";";
  o << "// The same r from the lighting's band textures (filled by shtool_sh_band_sums with c = e).\n"
    << head2 << " {\n" << texture_preamble(s) << "  " << s.real()
    << " r = 0.0;\n  for (int i = 0; i < SHTOOL_ZH_LOBES; ++i) {\n"
    << texture_fetches(s, n, "axes[i]", "t", "    ") << "    r += " << sum << ";\n  }\n  return r;\n}\n";
}

// z-rotation of band l by the angle whose multiple-angle cosines and sines are
// <angle>c<m>, <angle>s<m>: (f_m, f_-m) turns by m times the angle.
std::string z_rotation(const Syntax& s, int l, const std::string& angle, const std::string& src,
                       const std::string& dst) {
  std::ostringstream o;
  const std::string real = s.real();
  o << "  " << real << " " << dst << l << " = " << src << l << ";\n";
  for (int m = 1; m <= l; ++m) {
    const std::string c = angle + "c" + std::to_string(m), sn = angle + "s" + std::to_string(m);
    const std::string p = src + std::to_string(l + m), q = src + std::to_string(l - m);
    o << "  " << real << " " << dst << l + m << " = " << c << " * " << p << " - " << sn << " * " << q << ";\n"
      << "  " << real << " " << dst << l - m << " = " << sn << " * " << p << " + " << c << " * " << q << ";\n";
  }
  return o.str();
}

// g = M(R) f by zxzxz ([2] Sec. 2.2, App. C): band 1 is R itself, band 2 at order 3 the
// rotated quadratic form, the other bands Z(a) X90^T Z(b) X90 Z(g) with the zyz angles
// of R taken from its entries (no trigonometric call).
void zxzxz_rotate(const Syntax& s, int n, std::ostringstream& o, ShaderSource& out, std::uint32_t& crc) {
  const std::string real = s.real();
  std::ostringstream b;
  auto r = [&](int i, int j) { return s.r(i, j); };
  b << "  g[0] = f[0];\n";
  // Band 1: y_1^-1 = -c y, y_1^0 = c z, y_1^1 = -c x, so the band is R in (y, z, x) order with signs.
  b << "  " << real << " fx = -f[3];\n  " << real << " fy = -f[1];\n  " << real << " fz = f[2];\n"
    << "  g[1] = -(" << r(1, 0) << " * fx + " << r(1, 1) << " * fy + " << r(1, 2) << " * fz);\n"
    << "  g[2] = " << r(2, 0) << " * fx + " << r(2, 1) << " * fy + " << r(2, 2) << " * fz;\n"
    << "  g[3] = -(" << r(0, 0) << " * fx + " << r(0, 1) << " * fy + " << r(0, 2) << " * fz);\n";
  if (n == 3) {
    // Band 2 as w^T A w rotated to w^T (R A R^T) w (docs/shaders.md).
    b << "  " << real << " kf0 = " << literal(1.0L / std::sqrt(3.0L)) << " * f[6];\n"
      << "  " << real << " a00 = f[8] - kf0;\n  " << real << " a11 = -f[8] - kf0;\n  " << real
      << " a22 = kf0 + kf0;\n  " << real << " a01 = f[4];\n  " << real << " a12 = -f[5];\n  " << real
      << " a02 = -f[7];\n";
    const char* a[3][3] = {{"a00", "a01", "a02"}, {"a01", "a11", "a12"}, {"a02", "a12", "a22"}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        b << "  " << real << " c" << i << j << " = " << r(i, 0) << " * " << a[0][j] << " + " << r(i, 1) << " * "
          << a[1][j] << " + " << r(i, 2) << " * " << a[2][j] << ";\n";
    auto bij = [&](int i, int j) {
      return "c" + std::to_string(i) + "0 * " + r(j, 0) + " + c" + std::to_string(i) + "1 * " + r(j, 1) + " + c" +
             std::to_string(i) + "2 * " + r(j, 2);
    };
    b << "  g[4] = " << bij(0, 1) << ";\n  g[5] = -(" << bij(1, 2) << ");\n  g[6] = "
      << literal(std::sqrt(3.0L) / 2) << " * (" << bij(2, 2) << ");\n  g[7] = -(" << bij(0, 2) << ");\n  g[8] = 0.5 * ("
      << bij(0, 0) << " - (" << bij(1, 1) << "));\n";
  }
  if (n >= 4) {
    // Declares c and sn in the shader: the unit vector along (c_value, s_value).
    auto unit_pair = [&](const std::string& c, const std::string& sn, const std::string& c_value,
                         const std::string& s_value) {
      b << "    " << real << " " << c << " = " << c_value << ";\n"
        << "    " << real << " " << sn << " = " << s_value << ";\n"
        << "    " << real << " inv = 1.0 / sqrt(" << c << " * " << c << " + " << sn << " * " << sn << ");\n"
        << "    " << c << " = " << c << " * inv;\n    " << sn << " = " << sn << " * inv;\n";
    };
    // R = Rz(a) Ry(b) Rz(g): (R02, R12) = sin b (cos a, sin a), R22 = cos b, and the
    // well-conditioned a + g (b < pi/2) or a - g combination gives g, exact at the locks.
    b << "  " << real << " cb = " << r(2, 2) << ";\n  " << real << " sb = sqrt(" << r(0, 2) << " * " << r(0, 2)
      << " + " << r(1, 2) << " * " << r(1, 2) << ");\n"
      << "  " << real << " ac1 = 1.0;\n  " << real << " as1 = 0.0;\n"
      << "  if (sb > 0.0) {\n    ac1 = " << r(0, 2) << " / sb;\n    as1 = " << r(1, 2) << " / sb;\n  }\n"
      << "  " << real << " gc1;\n  " << real << " gs1;\n"
      << "  if (cb >= 0.0) {\n";
    unit_pair("cs", "ss", r(0, 0) + " + " + r(1, 1), r(1, 0) + " - " + r(0, 1));
    b << "    gc1 = cs * ac1 + ss * as1;\n    gs1 = ss * ac1 - cs * as1;\n"
      << "  } else {\n";
    unit_pair("cd", "sd", r(1, 1) + " - " + r(0, 0), "-(" + r(1, 0) + " + " + r(0, 1) + ")");
    b << "    gc1 = ac1 * cd + as1 * sd;\n    gs1 = as1 * cd - ac1 * sd;\n"
      << "  }\n"
      << "  " << real << " bc1 = cb;\n  " << real << " bs1 = sb;\n";
    for (const char* angle : {"a", "b", "g"})
      for (int m = 2; m < n; ++m) {
        const std::string c = angle + std::string("c"), sn = angle + std::string("s");
        const std::string pm = std::to_string(m - 1), m1 = "1";
        b << "  " << real << " " << c << m << " = " << c << pm << " * " << c << m1 << " - " << sn << pm << " * "
          << sn << m1 << ";\n  " << real << " " << sn << m << " = " << sn << pm << " * " << c << m1 << " + " << c
          << pm << " * " << sn << m1 << ";\n";
      }
    const RotationHelpers h = compute_rotation_helpers(n);
    for (int l = 2; l < n; ++l) {
      const int size = 2 * l + 1, first = l * l;
      const auto x = x90_band_block(h, l);
      for (const auto& row : x)
        crc = table_crc32(std::as_bytes(std::span(row)), crc);
      const std::string p = "l" + std::to_string(l) + "_";
      b << "  // band " << l << "\n";
      for (int j = 0; j < size; ++j) b << "  " << real << " " << p << "x" << j << " = f[" << first + j << "];\n";
      b << z_rotation(s, l, "g", p + "x", p + "t");
      for (int i = 0; i < size; ++i) {
        std::vector<std::pair<long double, std::string>> terms;
        for (int j = 0; j < size; ++j) terms.emplace_back(x[i][j], p + "t" + std::to_string(j));
        b << "  " << real << " " << p << "u" << i << " = " << linear_sum(terms) << ";\n";
      }
      b << z_rotation(s, l, "b", p + "u", p + "w");
      for (int i = 0; i < size; ++i) {
        std::vector<std::pair<long double, std::string>> terms;
        for (int j = 0; j < size; ++j) terms.emplace_back(x[j][i], p + "w" + std::to_string(j));
        b << "  " << real << " " << p << "v" << i << " = " << linear_sum(terms) << ";\n";
      }
      b << z_rotation(s, l, "a", p + "v", p + "y");
      for (int j = 0; j < size; ++j) b << "  g[" << first + j << "] = " << p << "y" << j << ";\n";
    }
  }
  const std::string head = "void shtool_rotate(" + s.mat3() + " R, " + array(s.real(), "f", kCount) + ", out " +
                           array(s.real(), "g", kCount) + ")";
  count_ops(b.str(), 1, out);
  out.signature = head + ";";
  o << "// g = M(R) f: g(w) = f(R^-1 w), so a lobe along d ends up along R d. R is the rotation matrix\n"
       "// acting on column vectors (orthonormal, det +1; "
    << (s.glsl() ? "GLSL mat3 is column-major: R[c][r] = R_rc" : "HLSL float3x3 is indexed R[r][c] = R_rc")
    << ").\n" << head << " {\n" << b.str() << "}\n";
}

// The bands (from first_band up) whose lobe sets hold shared direction d, and 1 + the
// highest of them (0: none).
struct LobeUse {
  std::vector<bool> wanted;
  int top = 0;
};
LobeUse bands_using(const ZhfLobes& lobes, int n, int d, int first_band) {
  LobeUse use{std::vector<bool>(n, false), 0};
  for (int l = first_band; l < n; ++l)
    if (d >= lobes.band_offset[l] && d <= lobes.band_offset[l] + 2 * l) {
      use.wanted[l] = true;
      use.top = l + 1;
    }
  return use;
}

std::string vec3_literal(const Syntax& s, const Vec3<double>& w) {
  return (s.glsl() ? "vec3(" : "float3(") + literal(w.x()) + ", " + literal(w.y()) + ", " + literal(w.z()) + ")";
}

// g = M(R) f by the standard ZHF rotation ([1] Sec. 7.1, Eq. 10): per band the lobe
// weights h_l = A^_l^T f_l (the table's sparse rows, zeros never touched), then
// g_l = sum_d y_l(R w_d) h_ld with the basis evaluated once per rotated lobe direction w_d
// (shared lobes: one direction serves every band from its own up).
void zhf_rotate(const Syntax& s, int n, const ZhfLobes& lobes, std::ostringstream& o, ShaderSource& out) {
  const std::string real = s.real();
  std::ostringstream b;
  b << "  g[0] = f[0];\n";
  for (int i = 1; i < n * n; ++i) b << "  g[" << i << "] = 0.0;\n";
  auto h = [](int l, int d) {
    return std::string("h").append(std::to_string(l)).append("_").append(std::to_string(d));
  };
  for (int l = 1; l < n; ++l) {
    std::vector<std::vector<std::pair<long double, std::string>>> columns(2 * l + 1);
    for (int m = -l; m <= l; ++m) {
      const int i = l * (l + 1) + m;
      for (int k = lobes.row_start[i]; k < lobes.row_start[i + 1]; ++k)
        columns[lobes.col[k]].emplace_back(lobes.val[k], "f[" + std::to_string(i) + "]");
    }
    for (int d = 0; d <= 2 * l; ++d) {
      const std::string sum = linear_sum(columns[d]);
      b << "  " << real << " " << h(l, d) << " = " << (sum.empty() ? "0.0" : sum) << ";\n";
    }
  }
  long direction_products = 0;
  for (int d = 0; d < static_cast<int>(lobes.directions.size()); ++d) {
    const auto [wanted, top] = bands_using(lobes, n, d, 1);
    if (top == 0) continue;
    const std::string lit = vec3_literal(s, lobes.directions[d]);
    b << "  {  // lobe direction " << d << "\n    " << s.vec3() << " w = "
      << (s.glsl() ? "R * " + lit : "mul(R, " + lit + ")") << ";\n";
    b << basis_code(s, top, "w", "", wanted, "    ");
    for (int l = 1; l < top; ++l) {
      if (!wanted[l]) continue;
      for (int m = -l; m <= l; ++m) {
        const int i = l * (l + 1) + m;
        b << "    g[" << i << "] = g[" << i << "] + " << basis_name(i) << " * " << h(l, d - lobes.band_offset[l])
          << ";\n";
      }
    }
    b << "  }\n";
    ++direction_products;
  }
  const std::string head = "void shtool_zhf_rotate(" + s.mat3() + " R, " + array(s.real(), "f", kCount) + ", out " +
                           array(s.real(), "g", kCount) + ")";
  count_ops(b.str(), 1, out);
  // R w_d: 9 multiplications and 6 additions per direction, written as one product.
  out.multiplications += 9 * direction_products - (s.glsl() ? direction_products : 0);
  out.additions += 6 * direction_products;
  out.signature = head + ";";
  o << "// g = M(R) f as shtool_rotate of zxzxz-rotate does (g(w) = f(R^-1 w); R acts on column vectors, "
    << (s.glsl() ? "GLSL mat3 column-major: R[c][r] = R_rc" : "HLSL float3x3 indexed R[r][c] = R_rc")
    << "),\n// through " << lobes.directions.size() << " ZH lobe directions.\n"
    << head << " {\n" << b.str() << "}\n";
}

// g = M(R) f by the signal-tailored ZHF rotation ([1] Sec. 7.1, Eq. 11): the band-l part of
// f sampled at the inversely rotated lobe directions R^T w_d, then g_l = A^_l s_l (the
// table's sparse rows). Two forms: the samples from the band textures of f (prepared once
// per signal with shtool_sh_band_sums), or computed from f's coefficients.
void zhf_tailored_rotate(const Syntax& s, int n, const ZhfLobes& lobes, std::ostringstream& o, ShaderSource& out) {
  const std::string real = s.real();
  auto sample = [](int l, int d) {
    return std::string("s").append(std::to_string(l)).append("_").append(std::to_string(d));
  };
  // One body per form: per direction the samples of the bands that use it, then the rows.
  auto body = [&](bool textures) {
    std::ostringstream b;
    if (!textures) b << "  g[0] = f[0];\n";
    const int first_band = textures ? 0 : 1;
    for (int d = 0; d < static_cast<int>(lobes.directions.size()); ++d) {
      const auto [wanted, top] = bands_using(lobes, n, d, first_band);
      if (top == 0) continue;
      const std::string lit = vec3_literal(s, lobes.directions[d]);
      // R^T w_d: GLSL's row-vector product w * R, HLSL's mul(w, R).
      const std::string rotated = s.glsl() ? lit + " * R" : "mul(" + lit + ", R)";
      for (int l = first_band; l < top; ++l)
        if (wanted[l]) b << "  " << real << " " << sample(l, d - lobes.band_offset[l]) << ";\n";
      b << "  {  // lobe direction " << d << "\n    " << s.vec3() << " w = " << rotated << ";\n";
      if (textures) {
        b << texture_fetches(s, top, "w", "t", "    ");
        for (int l = 0; l < top; ++l)
          if (wanted[l]) b << "    " << sample(l, d - lobes.band_offset[l]) << " = " << texel_band("t", l) << ";\n";
      } else {
        b << basis_code(s, top, "w", "", wanted, "    ");
        for (int l = 1; l < top; ++l) {
          if (!wanted[l]) continue;
          std::vector<long double> only(top, 0);
          only[l] = 1;
          b << "    " << sample(l, d - lobes.band_offset[l]) << " = " << band_dot(top, "f", only, {}) << ";\n";
        }
      }
      b << "  }\n";
    }
    for (int i = textures ? 0 : 1; i < n * n; ++i) {
      const int l = static_cast<int>(std::sqrt(static_cast<double>(i)));
      std::vector<std::pair<long double, std::string>> terms;
      for (int k = lobes.row_start[i]; k < lobes.row_start[i + 1]; ++k)
        terms.emplace_back(lobes.val[k], sample(l, lobes.col[k]));
      const std::string sum = linear_sum(terms);
      b << "  g[" << i << "] = " << (sum.empty() ? "0.0" : sum) << ";\n";
    }
    return b.str();
  };
  const std::string textured = body(true), arithmetic = body(false);
  const long directions = static_cast<long>(lobes.directions.size());
  count_ops(textured, 1, out);  // the texture form is the operation's figure (the paper's GPU path)
  // Per direction, written as one product each: R^T w_d (9 multiplications, 6 additions;
  // HLSL's mul() is not counted at all) and the node-layout scaling (3 multiplications).
  out.multiplications += 9 * directions - (s.glsl() ? directions : 0) + 2 * directions;
  out.additions += 6 * directions;
  for (int d = 0; d < static_cast<int>(lobes.directions.size()); ++d)
    out.texture_fetches += band_textures(bands_using(lobes, n, d, 0).top);
  band_sums(s, n, o, out);
  const std::string head1 = "void shtool_zhf_tailored_rotate(" + s.mat3() + " R, " + texture_params(s, n) +
                            ", out " + array(s.real(), "g", kCount) + ")";
  const std::string head2 = "void shtool_zhf_tailored_rotate_arithmetic(" + s.mat3() + " R, " +
                            array(s.real(), "f", kCount) + ", out " + array(s.real(), "g", kCount) + ")";
  out.signature += head1 + ";\n" + head2 + ";";
  o << "// g = M(R) f (g(w) = f(R^-1 w); R acts on column vectors, "
    << (s.glsl() ? "GLSL mat3 column-major: R[c][r] = R_rc" : "HLSL float3x3 indexed R[r][c] = R_rc")
    << ")\n// through " << lobes.directions.size()
    << " ZH lobe directions, f given by its band textures (shtool_sh_band_sums with c = f).\n"
    << head1 << " {\n" << texture_preamble(s) << textured << "}\n\n"
    << "// The same rotation with the samples computed from f's coefficients.\n"
    << head2 << " {\n" << arithmetic << "}\n";
}

// c_k = sum_ij C_ijk a_i b_j with the tripling tensor C_ijk = integral y_i y_j y_k ([3] Eq. 5):
// each pair product a_i b_j + a_j b_i is formed once and shared by every output it feeds.
void triple_product(const Syntax& s, int n, std::ostringstream& o, ShaderSource& out, std::uint32_t& crc) {
  const TriplingTensor t = compute_tripling_tensor_exact(n);
  crc = table_crc32(std::as_bytes(std::span(t.value)), crc);
  // output k -> (coefficient, pair (p, q) with p <= q)
  std::map<int, std::vector<std::pair<double, std::pair<int, int>>>> terms;
  for (std::size_t e = 0; e < t.size(); ++e) {
    const int i = static_cast<int>(t.index[3 * e]), j = static_cast<int>(t.index[3 * e + 1]),
              k = static_cast<int>(t.index[3 * e + 2]);
    const double c = t.value[e];
    // Each distinct value of {i, j, k} as the output, the other two as the input pair.
    terms[k].push_back({c, {i, j}});
    if (j != k) terms[j].push_back({c, {i, k}});
    if (i != j) terms[i].push_back({c, {j, k}});
  }
  std::map<std::pair<int, int>, bool> used;
  for (const auto& [k, list] : terms)
    for (const auto& term : list) used[term.second] = true;
  std::ostringstream b;
  auto pair_name = [](std::pair<int, int> pq) {
    return std::string("p").append(std::to_string(pq.first)).append("_").append(std::to_string(pq.second));
  };
  for (const auto& [pq, u] : used) {
    const std::string p = std::to_string(pq.first), q = std::to_string(pq.second);
    b << "  " << s.real() << " " << pair_name(pq) << " = a[" << p << "] * b[" << q << "]";
    if (pq.first != pq.second) b << " + a[" << q << "] * b[" << p << "]";
    b << ";\n";
  }
  for (int k = 0; k < n * n; ++k) {
    std::vector<std::pair<long double, std::string>> list;
    for (const auto& [c, pq] : terms[k]) list.emplace_back(c, pair_name(pq));
    const std::string sum = linear_sum(list);
    b << "  c[" << k << "] = " << (sum.empty() ? "0.0" : sum) << ";\n";
  }
  const std::string head = "void shtool_triple_product(" + array(s.real(), "a", kCount) + ", " +
                           array(s.real(), "b", kCount) + ", out " + array(s.real(), "c", kCount) + ")";
  count_ops(b.str(), 1, out);
  out.signature = head + ";";
  o << "// c = projection of the product of the functions a and b onto the order-SHTOOL_ORDER basis:\n"
       "// c_k = sum_ij C_ijk a_i b_j, C_ijk = integral y_i y_j y_k.\n"
    << head << " {\n" << b.str() << "}\n";
}

// A vec3 constructor's name: GLSL takes no precision qualifier there.
std::string vec3_constructor(const Syntax& s) { return s.glsl() ? "vec3" : s.vec3(); }

// The L1 vector d = (-c_11, -c_1-1, c_10) of channel `ch` of RGB coefficients L[0..3].
std::string l1_vector_code(const Syntax& s, const std::string& ch) {
  return vec3_constructor(s) + "(-L[3]." + ch + ", -L[1]." + ch + ", L[2]." + ch + ")";
}

// Geomerics' non-linear L1 irradiance (Hazel 2017; shtool/probe_encoding.h):
// E = pi R0 (a + (1 - a)(p + 1) q^p), R0 = c00 / sqrt(4 pi), R1 = d / sqrt(12 pi).
void l1_irradiance(const Syntax& s, std::ostringstream& o, ShaderSource& out) {
  const long double pi = std::numbers::pi_v<long double>;
  const std::string real = s.real(), v3 = s.vec3();
  std::ostringstream b;
  b << "  " << real << " r0 = " << literal(1 / std::sqrt(4 * pi)) << " * c00;\n"
    << "  if (!(r0 > 0.0)) return 0.0;\n"
    << "  " << v3 << " r1 = " << literal(1 / std::sqrt(12 * pi)) << " * d;\n"
    << "  " << real << " len = length(r1);\n"
    << "  " << real << " r = len / r0;\n"
    << "  " << real << " q = len > 0.0 ? max(0.5 + 0.5 * dot(n, r1) / len, 0.0) : 0.5;\n"
    << "  " << real << " p = 1.0 + 2.0 * r;\n"
    << "  " << real << " a = (1.0 - r) / (1.0 + r);\n"
    << "  return " << literal(pi) << " * r0 * (a + (1.0 - a) * (p + 1.0) * pow(q, p));\n";
  const std::string head1 = real + " shtool_l1_irradiance_channel(" + v3 + " n, " + real + " c00, " + v3 + " d)";
  const std::string head3 = v3 + " shtool_l1_irradiance(" + v3 + " n, " + array(v3, "L", "4") + ")";
  const std::string rgb = "  return " + vec3_constructor(s) + "(shtool_l1_irradiance_channel(n, L[0].x, " + l1_vector_code(s, "x") +
                          "),\n    shtool_l1_irradiance_channel(n, L[0].y, " + l1_vector_code(s, "y") +
                          "),\n    shtool_l1_irradiance_channel(n, L[0].z, " + l1_vector_code(s, "z") + "));\n";
  count_ops(b.str(), 3, out);
  count_ops(rgb, 1, out);
  out.signature = head1 + ";\n" + head3 + ";";
  o << "// Geomerics' non-linear L1 irradiance (Hazel 2017) of one channel: c00 its band-0 radiance\n"
       "// coefficient, d = (-c_11, -c_1-1, c_10) its band-1 vector, n a unit normal. E without 1/pi;\n"
       "// exact for a constant light and, at n = s, for one directional light along s.\n"
    << head1 << " {\n" << b.str() << "}\n\n"
    << "// The same for an RGB probe: L[i] = radiance coefficient i (shtool's basis, i = 0..3).\n"
    << head3 << " {\n" << rgb << "}\n";
}

// ZH3 (Roughton et al. 2024): L1 plus a zonal band-2 coefficient per channel along an axis
// from the L1 band (shtool/probe_encoding.h), explicit (stored) or hallucinated.
void zh3_irradiance(const Syntax& s, std::ostringstream& o, ShaderSource& out) {
  const long double pi = std::numbers::pi_v<long double>;
  const std::string real = s.real(), v3 = s.vec3();
  const std::string l = array(v3, "L", "4");
  std::ostringstream body;
  // Axis: luminance-weighted L1 vector, or the channel's own; +z for a zero band.
  const std::string axis_head = v3 + " shtool_zh3_axis(" + v3 + " d)";
  const std::string axis = "  " + real + " len = length(d);\n  return len > 0.0 ? d / len : " +
                           vec3_constructor(s) + "(0.0, 0.0, 1.0);\n";
  const std::string lum_head = v3 + " shtool_zh3_luminance_axis(" + l + ")";
  const std::string lum = "  return shtool_zh3_axis(" + literal(kZh3LuminanceWeights[0]) + " * " +
                          l1_vector_code(s, "x") + " + " + literal(kZh3LuminanceWeights[1]) + " * " +
                          l1_vector_code(s, "y") + " + " + literal(kZh3LuminanceWeights[2]) + " * " +
                          l1_vector_code(s, "z") + ");\n";
  const std::string ch_head = real + " shtool_zh3_irradiance_channel(" + v3 + " n, " + real + " c00, " + v3 + " d, " +
                              real + " f, " + v3 + " a)";
  const std::string ch = "  " + real + " t = dot(a, n);\n  return " + literal(pi / std::sqrt(4 * pi)) + " * c00 + " +
                         literal(2 * pi / 3 * std::sqrt(3 / (4 * pi))) + " * dot(d, n) + " +
                         literal(pi / 4 * std::sqrt(5 / (16 * pi))) + " * f * (3.0 * t * t - 1.0);\n";
  const std::string hal_head = real + " shtool_zh3_hallucinated_zonal(" + real + " c00, " + v3 + " d, " + v3 + " a)";
  const std::string hal = "  if (!(c00 > 0.0)) return 0.0;\n  " + real + " r = abs(dot(d, a)) / c00;\n"
                          "  return c00 * r * (0.08 + 0.6 * r);\n";
  auto rgb = [&](const std::string& name, bool per_channel, bool hallucinated) {
    std::string h = v3 + " " + name + "(" + v3 + " n, " + l + (hallucinated ? "" : ", " + v3 + " zonal") + ")";
    std::string b;
    if (!per_channel) b += "  " + v3 + " a = shtool_zh3_luminance_axis(L);\n";
    std::string ret = "  return " + vec3_constructor(s) + "(";
    for (int c = 0; c < 3; ++c) {
      const std::string x(1, "xyz"[c]);
      const std::string d = "d" + x;
      b += "  " + v3 + " " + d + " = " + l1_vector_code(s, x) + ";\n";
      const std::string a = per_channel ? "a" + x : "a";
      if (per_channel) b += "  " + v3 + " " + a + " = shtool_zh3_axis(" + d + ");\n";
      const std::string f = hallucinated ? "shtool_zh3_hallucinated_zonal(L[0]." + x + ", " + d + ", " + a + ")"
                                         : "zonal." + x;
      ret += (c ? ",\n    " : "") + std::string("shtool_zh3_irradiance_channel(n, L[0].") + x + ", " + d + ", " + f +
             ", " + a + ")";
    }
    b += ret + ");\n";
    return std::make_pair(h, b);
  };
  const auto explicit_lum = rgb("shtool_zh3_irradiance", false, false);
  const auto explicit_per = rgb("shtool_zh3_irradiance_per_channel", true, false);
  const auto hal_lum = rgb("shtool_zh3_hallucinate_irradiance", false, true);
  const auto hal_per = rgb("shtool_zh3_hallucinate_irradiance_per_channel", true, true);
  // The figure is the default path: the luminance axis, stored zonal coefficients.
  count_ops(lum + ch + ch + ch + axis + explicit_lum.second, 1, out);
  out.signature = axis_head + ";\n" + lum_head + ";\n" + ch_head + ";\n" + hal_head + ";\n" + explicit_lum.first +
                  ";\n" + explicit_per.first + ";\n" + hal_lum.first + ";\n" + hal_per.first + ";";
  o << "// ZH3 irradiance (Roughton, Sloan, Silvennoinen, Iwanicki, Shirley, i3D 2024). A probe stores per\n"
       "// channel the band-0 and band-1 radiance coefficients (L[i], shtool's basis, i = 0..3) and one zonal\n"
       "// band-2 coefficient f along an axis recomputed from the L1 band: the luminance-weighted one\n"
       "// (Rec. 709 weights; the default) or each channel's own. E without 1/pi; n a unit normal.\n"
    << "// The unit axis of an L1 vector d (+z when d = 0).\n"
    << axis_head << " {\n" << axis << "}\n\n"
    << "// normalise(sum_c w_c d_c), w = (0.2126, 0.7152, 0.0722).\n"
    << lum_head << " {\n" << lum << "}\n\n"
    << "// E(n) = pi c00 y00 + (2 pi / 3) k1 d . n + (pi / 4) f sqrt(5 / (16 pi)) (3 (a . n)^2 - 1).\n"
    << ch_head << " {\n" << ch << "}\n\n"
    << "// The hallucinated zonal coefficient from L1 alone: r = |d . a| / c00, f = c00 r (0.08 + 0.6 r).\n"
    << hal_head << " {\n" << hal << "}\n\n"
    << "// Stored zonal coefficients, luminance axis.\n" << explicit_lum.first << " {\n" << explicit_lum.second << "}\n\n"
    << "// Stored zonal coefficients, per-channel axes.\n" << explicit_per.first << " {\n" << explicit_per.second << "}\n\n"
    << "// Hallucinated zonal coefficients (nothing stored beyond L1), luminance axis.\n" << hal_lum.first << " {\n"
    << hal_lum.second << "}\n\n"
    << "// Hallucinated zonal coefficients, per-channel axes.\n" << hal_per.first << " {\n" << hal_per.second << "}\n";
}

std::string guard_name(ShaderOperation op) {
  std::string name = "SHTOOL_" + std::string(shader_operation_name(op)) + "_INCLUDED";
  for (char& c : name) c = c == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

}  // namespace

const std::vector<ShaderOperation>& shader_operations() {
  static const std::vector<ShaderOperation> all = {ShaderOperation::sh_eval, ShaderOperation::sh_irradiance,
                                                   ShaderOperation::zxzxz_rotate, ShaderOperation::zhf_rotate,
                                                   ShaderOperation::zhf_tailored_rotate, ShaderOperation::triple_product,
                                                   ShaderOperation::zh_shade, ShaderOperation::l1_irradiance,
                                                   ShaderOperation::zh3_irradiance};
  return all;
}

std::string_view shader_operation_name(ShaderOperation operation) {
  switch (operation) {
    case ShaderOperation::sh_eval: return "sh-eval";
    case ShaderOperation::sh_irradiance: return "sh-irradiance";
    case ShaderOperation::zxzxz_rotate: return "zxzxz-rotate";
    case ShaderOperation::zhf_rotate: return "zhf-rotate";
    case ShaderOperation::zhf_tailored_rotate: return "zhf-tailored-rotate";
    case ShaderOperation::triple_product: return "triple-product";
    case ShaderOperation::zh_shade: return "zh-shade";
    case ShaderOperation::l1_irradiance: return "l1-irradiance";
    case ShaderOperation::zh3_irradiance: return "zh3-irradiance";
  }
  return "?";
}

int shader_min_order(ShaderOperation operation) {
  return operation == ShaderOperation::zxzxz_rotate || operation == ShaderOperation::l1_irradiance ||
                 operation == ShaderOperation::zh3_irradiance || operation == ShaderOperation::zhf_rotate ||
                 operation == ShaderOperation::zhf_tailored_rotate || operation == ShaderOperation::triple_product
             ? 2
             : 1;
}

int shader_max_order(ShaderOperation operation) {
  switch (operation) {
    case ShaderOperation::zxzxz_rotate: return 8;
    case ShaderOperation::triple_product: return 6;
    default: return 10;
  }
}

ShaderSource shader_source(const ShaderRequest& request) {
  const Syntax s{request.language, request.precision == ShaderPrecision::half};
  const int n = request.order;
  ShaderSource out;
  std::ostringstream body;
  std::uint32_t crc = 0;
  std::string constants;
  switch (request.operation) {
    case ShaderOperation::sh_eval:
      sh_eval(s, n, body, out);
      constants = "K_l^m and the Legendre recurrence, from their closed forms";
      break;
    case ShaderOperation::sh_irradiance:
      sh_irradiance(s, n, body, out);
      constants = "the basis as sh-eval; A_l of the clamped-cosine kernel (A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4)";
      break;
    case ShaderOperation::zh_shade:
      zh_shade(s, n, request.zh_lobes, body, out);
      constants = "the basis as sh-eval";
      break;
    case ShaderOperation::zxzxz_rotate:
      zxzxz_rotate(s, n, body, out, crc);
      constants = n >= 4 ? "X90 = M(Rx(+90 deg)) of bands 2.." + std::to_string(n - 1) +
                               " (computed by projection, as in rotation-helpers tables)"
                         : "none (bands 1 and 2 by closed forms in R)";
      break;
    case ShaderOperation::zhf_rotate:
    case ShaderOperation::zhf_tailored_rotate: {
      const bool tailored = request.operation == ShaderOperation::zhf_tailored_rotate;
      if (tailored) zhf_tailored_rotate(s, n, *request.lobes, body, out);
      else zhf_rotate(s, n, *request.lobes, body, out);
      crc = request.lobes_crc;
      // The tailored texture form takes band 0 through the table too.
      constants = "lobe directions and sparse A^_l rows of bands " + std::string(tailored ? "0.." : "1..") +
                  std::to_string(n - 1) +
                  " from the zhf-lobes table whose file has the CRC-32 below; the basis as sh-eval";
      break;
    }
    case ShaderOperation::l1_irradiance:
      l1_irradiance(s, body, out);
      constants = "1 / sqrt(4 pi), 1 / sqrt(12 pi) and pi, from their closed forms";
      break;
    case ShaderOperation::zh3_irradiance:
      zh3_irradiance(s, body, out);
      constants = "pi y00, (2 pi / 3) k1, (pi / 4) sqrt(5 / (16 pi)) from their closed forms; Rec. 709 luminance "
                  "weights; the paper's hallucination curve 0.08, 0.6";
      break;
    case ShaderOperation::triple_product:
      triple_product(s, n, body, out, crc);
      constants = "the tripling tensor of order " + std::to_string(n) + " (Wigner 3j construction)";
      break;
  }
  const std::string_view name = shader_operation_name(request.operation);
  const std::string guard = guard_name(request.operation);
  char crc_text[16];
  std::snprintf(crc_text, sizeof crc_text, "%08x", crc);
  std::ostringstream o;
  o << "// " << name << ", order " << n << ", " << (s.glsl() ? "GLSL" : "HLSL") << ", "
    << (s.half ? "half (relaxed) precision" : "float") << ": generated by shtool " << kVersion << "\n"
    << "//   " << request.command << "\n"
    << "// Constants: " << constants << ".\n";
  if (crc != 0)
    o << "// CRC-32 " << (request.operation == ShaderOperation::zhf_rotate ||
                                   request.operation == ShaderOperation::zhf_tailored_rotate
                               ? "of the table file"
                               : "of those constants (float64, little-endian, in generation order)")
      << ": " << crc_text << "\n";
  o << "// Real orthonormal SH with the Condon-Shortley phase, flat index l * (l + 1) + m, order N = bands\n"
       "// 0..N-1. An include file: it declares no shader version, entry point or resource. Do not edit;\n"
       "// regenerate.\n"
    << "#ifndef " << guard << "\n#define " << guard << "\n\n"
    << "#define SHTOOL_ORDER " << n << "\n\n"
    << body.str() << "\n#endif  // " << guard << "\n";
  out.text = o.str();
  return out;
}

}  // namespace shtool
