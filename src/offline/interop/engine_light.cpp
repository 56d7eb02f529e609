#include "interop/engine_light.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>

#include "common/enum_names.h"
#include "common/finite.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "shtool/irradiance.h"
#include "shtool/orthogonal_map.h"
#include "shtool/sh.h"

namespace shtool::interop {
namespace {

using lighting::Lighting;
using lighting::Quantity;
constexpr double kPi = std::numbers::pi;

// |K_i| of bands 0..2 (the engines' basis constants) and the Condon-Shortley sign
// (-1)^m of each index: without the phase, c_i = (-1)^m c_i(shtool).
const std::array<double, 9> kAbsK = {0.28209479177387814, 0.4886025119029199, 0.4886025119029199,
                                     0.4886025119029199,  1.0925484305920792, 1.0925484305920792,
                                     0.31539156525252005, 1.0925484305920792, 0.5462742152960396};
constexpr std::array<double, 9> kSigma = {1, -1, 1, -1, 1, -1, 1, -1, 1};
double band_a(int i) { return clamped_cosine_band(sh_band(i)); }

// 9 x 3 values, [i * 3 + c].
using Nine = std::array<double, 27>;

// The light in `want` quantity, as order-3 coefficients (bands above 2 dropped, with a
// note; missing bands are zero).
Nine first_nine(const Lighting& l, Quantity want, std::vector<std::string>& notes) {
  if (l.order > 3)
    notes.push_back("the format holds bands 0..2: bands 3.." + std::to_string(l.order - 1) + " of the order-" +
                    std::to_string(l.order) + " light are dropped");
  Nine out{};
  for (int i = 0; i < std::min(9, sh_count(l.order)); ++i) {
    // A_l != 0 for l <= 2, so both directions are exact.
    const double scale = l.quantity == want ? 1 : (want == Quantity::irradiance ? band_a(i) : 1 / band_a(i));
    for (int c = 0; c < 3; ++c) out[3 * i + c] = l.coefficients[3 * i + c] * scale;
  }
  return out;
}

Nine engine(const FrameMap& f, const Nine& x) {
  const std::vector<double> g = to_engine_frame(f, std::vector<double>(x.begin(), x.end()));
  Nine out{};
  std::copy(g.begin(), g.end(), out.begin());
  return out;
}

Lighting from_nine(const FrameMap& f, const Nine& g, Quantity stored, Quantity want) {
  Lighting l;
  l.order = 3;
  l.quantity = stored;
  l.coefficients = from_engine_frame(f, std::vector<double>(g.begin(), g.end()));
  if (want != stored) {
    for (int i = 0; i < 9; ++i)
      for (int c = 0; c < 3; ++c) l.coefficients[3 * i + c] *= want == Quantity::irradiance ? band_a(i) : 1 / band_a(i);
    l.quantity = want;
  }
  return l;
}

[[noreturn]] void bad(const std::filesystem::path& name, const std::string& why) {
  throw InputError(name.string() + ": " + why);
}

double finite_number(const nlohmann::json& v, const std::filesystem::path& name, const std::string& what) {
  if (!v.is_number() || !std::isfinite(v.get<double>())) bad(name, what + " is not a finite number");
  return v.get<double>();
}

// A light's optional intensity field: 1 when absent; a negative one (an engine would
// take light away) is refused, zero (a light switched off) read.
double intensity_field(const nlohmann::json& holder, const std::filesystem::path& name) {
  if (!holder.contains("intensity")) return 1;
  const double s = finite_number(holder["intensity"], name, "intensity");
  if (s < 0) bad(name, "intensity " + holder["intensity"].dump() + " is negative");
  return s;
}

// 9 [r, g, b] rows.
Nine rows_of(const nlohmann::json& rows, const std::filesystem::path& name, const std::string& what) {
  if (!rows.is_array() || rows.size() != 9) bad(name, what + " must hold 9 [r, g, b] rows");
  Nine out{};
  for (int i = 0; i < 9; ++i) {
    if (!rows[i].is_array() || rows[i].size() != 3) bad(name, what + " row " + std::to_string(i) + " is not [r, g, b]");
    for (int c = 0; c < 3; ++c) out[3 * i + c] = finite_number(rows[i][c], name, what + " row " + std::to_string(i));
  }
  return out;
}

nlohmann::json rows_json(const Nine& v) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 9; ++i) rows.push_back({v[3 * i], v[3 * i + 1], v[3 * i + 2]});
  return rows;
}

// Engine-frame coefficients g in the phase-free basis (sigma_i drops the Condon-Shortley
// sign), times intensity / pi and, when `pre_scaled`, times the basis constants |K_i| (for
// shaders that evaluate bare polynomials).
Nine phase_free_over_pi(const Nine& g, double intensity, bool pre_scaled) {
  Nine out{};
  for (int i = 0; i < 9; ++i)
    for (int c = 0; c < 3; ++c) {
      double v = intensity * kSigma[i] * g[3 * i + c];
      if (pre_scaled) v *= kAbsK[i];
      out[3 * i + c] = v / kPi;
    }
  return out;
}

std::string rows_text(const nlohmann::json& j) {
  // One row per line inside the document, for reading.
  std::string s = dump_finite(j, "--out", 1);
  return s + "\n";
}

const char* kBandNames[9] = {"00", "1-1", "10", "11", "2-2", "2-1", "20", "21", "22"};

// Babylon's SphericalPolynomial from harmonics h (its updateFromHarmonics, with the
// constants exact: 1.02333 = k1 A_1, 0.886277 ~ k0 pi, 0.247708 = k20 A_2, ...), and back.
constexpr const char* kPolyNames[9] = {"x", "y", "z", "xx", "yy", "zz", "yz", "zx", "xy"};
Nine polynomial_from_harmonics(const Nine& h) {
  const double a1 = 2 * kPi / 3, a2 = kPi / 4;
  Nine p{};
  for (int c = 0; c < 3; ++c) {
    auto H = [&](int i) { return h[3 * i + c]; };
    const double k = kAbsK[0] * kPi * H(0), m20 = kAbsK[6] * a2 * H(6), m22 = kAbsK[8] * a2 * H(8);
    const double v[9] = {-kAbsK[3] * a1 * H(3), -kAbsK[1] * a1 * H(1), kAbsK[2] * a1 * H(2),
                         k - m20 + m22,         k - m20 - m22,         k + 2 * m20,
                         -kAbsK[5] * a2 * H(5), -kAbsK[7] * a2 * H(7), kAbsK[4] * a2 * H(4)};
    for (int i = 0; i < 9; ++i) p[3 * i + c] = v[i] / kPi;
  }
  return p;
}
Nine harmonics_from_polynomial(const Nine& p) {
  const double a1 = 2 * kPi / 3, a2 = kPi / 4;
  Nine h{};
  for (int c = 0; c < 3; ++c) {
    auto P = [&](int i) { return p[3 * i + c] * kPi; };
    h[3 * 0 + c] = (P(3) + P(4) + P(5)) / (3 * kAbsK[0] * kPi);
    h[3 * 1 + c] = -P(1) / (kAbsK[1] * a1);
    h[3 * 2 + c] = P(2) / (kAbsK[2] * a1);
    h[3 * 3 + c] = -P(0) / (kAbsK[3] * a1);
    h[3 * 4 + c] = P(8) / (kAbsK[4] * a2);
    h[3 * 5 + c] = -P(6) / (kAbsK[5] * a2);
    h[3 * 6 + c] = (P(5) - (P(3) + P(4)) / 2) / (3 * kAbsK[6] * a2);
    h[3 * 7 + c] = -P(7) / (kAbsK[7] * a2);
    h[3 * 8 + c] = (P(3) - P(4)) / (2 * kAbsK[8] * a2);
  }
  return h;
}

double raw_scale(int l, RawNormalization n) {
  switch (n) {
    case RawNormalization::orthonormal: return 1;
    case RawNormalization::four_pi: return 1 / std::sqrt(4 * kPi);                   // basis sqrt(4 pi) y
    case RawNormalization::schmidt: return std::sqrt((2 * l + 1) / (4 * kPi));       // basis sqrt(4 pi / (2l+1)) y
  }
  return 1;
}

}  // namespace

const EnumNames<LightFormat>& light_format_names() {
  using enum LightFormat;
  static const EnumNames<LightFormat> names = {
      {"threejs", threejs}, {"filament", filament}, {"filament-radiance", filament_radiance}, {"unity", unity},
      {"gltf", gltf}, {"gltf-khr", gltf_khr}, {"babylon", babylon}, {"godot", godot}, {"raw", raw}};
  return names;
}

const EnumNames<LightFormat>& export_format_names() {
  static const EnumNames<LightFormat> names = [] {
    EnumNames<LightFormat> n = light_format_names();
    n.emplace_back("l1", LightFormat::l1);
    n.emplace_back("zh3", LightFormat::zh3);
    return n;
  }();
  return names;
}

const EnumNames<Zh3Axis>& zh3_axis_names() {
  static const EnumNames<Zh3Axis> names = {
      {std::string(zh3_axis_name(Zh3Axis::luminance)), Zh3Axis::luminance},
      {std::string(zh3_axis_name(Zh3Axis::per_channel)), Zh3Axis::per_channel}};
  return names;
}

const EnumNames<RawNormalization>& raw_normalization_names() {
  using enum RawNormalization;
  static const EnumNames<RawNormalization> names = {
      {"orthonormal", orthonormal}, {"4pi", four_pi}, {"schmidt", schmidt}};
  return names;
}

FrameMap parse_frame_map(std::string_view text) {
  FrameMap f;
  f.q.setZero();
  f.text = std::string(text);
  std::stringstream s{std::string(text)};
  std::string item;
  int row = 0;
  std::array<bool, 3> used{};
  while (std::getline(s, item, ',')) {
    if (row >= 3) throw InputError("--frame '" + std::string(text) + "': expected three signed axes such as x,z,-y");
    double sign = 1;
    if (!item.empty() && (item[0] == '-' || item[0] == '+')) sign = item[0] == '-' ? -1 : 1, item = item.substr(1);
    if (item.size() != 1 || item[0] < 'x' || item[0] > 'z' || used[item[0] - 'x'])
      throw InputError("--frame '" + std::string(text) +
                       "': expected three signed, distinct axes such as x,z,-y (engine x, y, z in shtool's axes)");
    used[item[0] - 'x'] = true;
    f.q(row++, item[0] - 'x') = sign;
  }
  if (row != 3 || std::getline(s, item, ',') || text.back() == ',')
    throw InputError("--frame '" + std::string(text) + "': expected three signed axes such as x,z,-y");
  return f;
}

FrameMap default_frame(LightFormat format) {
  switch (format) {
    // y-up right-handed engines: engine = (x, z, -y), the mapping of Blender's glTF exporter.
    case LightFormat::threejs:
    case LightFormat::filament:
    case LightFormat::filament_radiance:
    case LightFormat::godot: return parse_frame_map("x,z,-y");
    // Left-handed y-up engines see the glTF frame with x negated: Unity's glTF importers
    // (UnityGLTF's CoordinateSpaceConversionScale (-1, 1, 1), glTFast) and its FBX importer
    // do so, and a probe must be in the frame the scene's meshes came in with; Babylon's
    // default scene evaluates glTF and .env lighting there too (its loader's root node).
    case LightFormat::unity:
    case LightFormat::gltf:
    case LightFormat::gltf_khr:
    case LightFormat::babylon: return parse_frame_map("-x,z,-y");
    // The encodings and raw stay in shtool's frame unless told.
    case LightFormat::raw:
    case LightFormat::l1:
    case LightFormat::zh3: break;
  }
  return parse_frame_map("x,y,z");
}

std::vector<double> to_engine_frame(const FrameMap& frame, const std::vector<double>& coefficients) {
  std::vector<double> out = coefficients;
  const Result<Ok> r = apply_orthogonal_map(frame.q, 3, out);
  if (!r) throw InputError("--frame '" + frame.text + "': " + r.error().message);
  return out;
}

std::vector<double> from_engine_frame(const FrameMap& frame, const std::vector<double>& coefficients) {
  std::vector<double> out = coefficients;
  const Result<Ok> r = apply_orthogonal_map(frame.q.transpose(), 3, out);
  if (!r) throw InputError("--frame '" + frame.text + "': " + r.error().message);
  return out;
}

std::array<double, 27> threejs_sh3(const std::array<double, 27>& radiance) {
  const Nine g = engine(default_frame(LightFormat::threejs), radiance);
  Nine t{};
  for (int i = 0; i < 9; ++i)
    for (int c = 0; c < 3; ++c) t[3 * i + c] = kSigma[i] * g[3 * i + c];
  return t;
}

ExportedLight export_light(const Lighting& light, LightFormat format, const FrameMap& frame, double intensity,
                           const RawOptions& raw) {
  if (!(intensity > 0) || !std::isfinite(intensity)) throw InputError("--intensity must be a positive number");
  // The conversions multiply by constants below 4: a light that would overflow there is
  // refused here rather than written as JSON null or "inf".
  for (double c : light.coefficients)
    if (!std::isfinite(c * intensity * 16))
      throw InputError("the light times --intensity overflows a double in the export");
  ExportedLight out;
  auto scaled = [&](Nine v) {
    for (double& x : v) x *= intensity;
    return v;
  };
  switch (format) {
    case LightFormat::threejs: {
      // three.js SphericalHarmonics3: the basis without the phase, radiance; getAt gives L,
      // getIrradianceAt E (src/math/SphericalHarmonics3.js); LightProbe.toJSON layout.
      const Nine g = engine(frame, first_nine(light, Quantity::radiance, out.notes));
      nlohmann::json sh = nlohmann::json::array();
      for (int i = 0; i < 9; ++i)
        for (int c = 0; c < 3; ++c) sh.push_back(kSigma[i] * g[3 * i + c]);
      const nlohmann::json doc = {
          {"metadata", {{"version", 4.6}, {"type", "Object"}, {"generator", "shtool export-light"}}},
          {"object",
           {{"uuid", "5c2c1a3e-0000-4000-8000-5e7001000001"},
            {"type", "LightProbe"},
            {"name", "shtool"},
            {"layers", 1},
            {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}},
            {"up", {0, 1, 0}},
            {"color", 16777215},
            {"intensity", intensity},
            {"sh", sh}}}};
      out.text = dump_finite(doc, "--out", 1) + "\n";
      break;
    }
    case LightFormat::filament:
    case LightFormat::filament_radiance: {
      // filament: IndirectLight::Builder::irradiance(3, sh) takes E/pi pre-scaled by the
      // signed basis constants (cmgen's sh.txt, CubemapSH::preprocessSHForShader);
      // Builder::radiance(3, sh) takes radiance in the phase-carrying basis.
      const bool irradiance = format == LightFormat::filament;
      const Nine g =
          engine(frame, first_nine(light, irradiance ? Quantity::irradiance : Quantity::radiance, out.notes));
      char line[256];
      for (int i = 0; i < 9; ++i) {
        double v[3];
        for (int c = 0; c < 3; ++c) v[c] = intensity * (irradiance ? kSigma[i] * g[3 * i + c] * kAbsK[i] / kPi : g[3 * i + c]);
        std::snprintf(line, sizeof line, "(%.17g, %.17g, %.17g); // L%s%s\n", v[0], v[1], v[2], kBandNames[i],
                      irradiance ? ", irradiance, pre-scaled base" : ", radiance");
        out.text += line;
      }
      if (intensity != 1) out.notes.push_back("--intensity is folded into the coefficients (filament's is in lux)");
      break;
    }
    case LightFormat::unity: {
      // SphericalHarmonicsL2 holds E/pi pre-scaled by |K_i| in the phase-free basis of the
      // left-handed frame; ShadeSH9's unity_SH* constants by HDRP's PackCoefficients.
      const Nine sh = phase_free_over_pi(engine(frame, first_nine(light, Quantity::irradiance, out.notes)), intensity,
                                         /*pre_scaled=*/true);
      nlohmann::json l2 = nlohmann::json::array();
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 9; ++i) l2.push_back(sh[3 * i + c]);
      auto s = [&](int i, int c) { return sh[3 * i + c]; };
      nlohmann::json doc = {{"SphericalHarmonicsL2", l2}};
      const char* rgb = "rgb";
      for (int c = 0; c < 3; ++c) {
        doc[std::string("unity_SHA") + rgb[c]] = {s(3, c), s(1, c), s(2, c), s(0, c) - s(6, c)};
        doc[std::string("unity_SHB") + rgb[c]] = {s(4, c), s(5, c), 3 * s(6, c), s(7, c)};
      }
      doc["unity_SHC"] = {s(8, 0), s(8, 1), s(8, 2), 1};
      out.text = dump_finite(doc, "--out", 1) + "\n";
      if (intensity != 1) out.notes.push_back("--intensity is folded into the coefficients");
      break;
    }
    case LightFormat::gltf:
    case LightFormat::gltf_khr: {
      // EXT_lights_image_based: irradianceCoefficients as Babylon's loader reads them
      // (irradiance, phase-carrying basis, its left-handed frame). --intensity is folded
      // into the coefficients and the intensity field written as 1: Babylon's loader
      // applies the field twice (to the SH and as the texture's level), and it makes the
      // SH NaN without one. The scene lists no nodes (an empty list is not valid glTF).
      const Nine g = engine(frame, first_nine(light, Quantity::irradiance, out.notes));
      nlohmann::json doc = {{"asset", {{"version", "2.0"}, {"generator", "shtool export-light"}}}};
      const char* ext = format == LightFormat::gltf ? "EXT_lights_image_based" : "KHR_lights_environment";
      doc["extensionsUsed"] = {ext};
      nlohmann::json record = {{"name", "shtool"}};
      if (format == LightFormat::gltf) record["intensity"] = 1.0, record["rotation"] = {0, 0, 0, 1};
      record["irradianceCoefficients"] = rows_json(scaled(g));
      // json::array: a braced list of one json is a copy of it under clang, an array under GCC.
      doc["extensions"][ext]["lights"] = nlohmann::json::array({record});
      doc["scenes"] = nlohmann::json::array({{{"extensions", {{ext, {{"light", 0}}}}}}});
      if (intensity != 1) out.notes.push_back("--intensity is folded into the coefficients");
      doc["scene"] = 0;
      out.text = rows_text(doc);
      out.notes.push_back(format == LightFormat::gltf
                              ? "only the diffuse part (irradianceCoefficients) is written: the extension requires "
                                "specularImages, without which Babylon's glTF loader stops (engines that read the "
                                "coefficients alone take the file)"
                              : "only the diffuse part (irradianceCoefficients) is written; no specular images");
      break;
    }
    case LightFormat::babylon: {
      // The .env manifest's "irradiance": a SphericalPolynomial, which Babylon turns back
      // into harmonics (E/pi) for its default shader path (Misc/environmentTextureTools).
      Nine h = engine(frame, first_nine(light, Quantity::irradiance, out.notes));
      for (double& v : h) v *= intensity / kPi;
      const Nine p = polynomial_from_harmonics(h);
      nlohmann::json poly;
      for (int i = 0; i < 9; ++i) poly[kPolyNames[i]] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
      nlohmann::json harmonics;
      // Babylon's SphericalHarmonics field names.
      static constexpr const char* kHarmonicNames[9] = {"l00", "l1_1", "l10", "l11", "l2_2", "l2_1", "l20", "l21", "l22"};
      for (int i = 0; i < 9; ++i) harmonics[kHarmonicNames[i]] = {h[3 * i], h[3 * i + 1], h[3 * i + 2]};
      out.text = rows_text({{"irradiance", poly}, {"harmonics", harmonics}});
      if (intensity != 1) out.notes.push_back("--intensity is folded into the coefficients");
      break;
    }
    case LightFormat::godot: {
      // LightmapGI probe captures: the phase-free basis, L/pi (lm_compute.glsl's 4/N).
      const Nine v = phase_free_over_pi(engine(frame, first_nine(light, Quantity::radiance, out.notes)), intensity,
                                        /*pre_scaled=*/false);
      out.text = rows_text({{"godot_lightmap_probe_sh", rows_json(v)}});
      if (intensity != 1) out.notes.push_back("--intensity is folded into the coefficients");
      break;
    }
    case LightFormat::l1:
    case LightFormat::zh3: {
      // The encodings commute with the frame map (d turns as a vector, band 2 with it, f is
      // invariant), so the light is carried to the frame first.
      const Nine g = scaled(engine(frame, first_nine(light, Quantity::radiance, out.notes)));
      const std::span<const double> all(g.data(), g.size());
      nlohmann::json l1 = nlohmann::json::array();
      for (int i = 0; i < 4; ++i) l1.push_back({g[3 * i], g[3 * i + 1], g[3 * i + 2]});
      nlohmann::json doc = {{"encoding", format == LightFormat::l1 ? "l1" : "zh3"},
                            {"quantity", "radiance"},
                            {"basis", "shtool: real orthonormal SH, Condon-Shortley phase, index l(l+1)+m"},
                            {"frame", frame.text},
                            {"coefficients", l1}};
      if (format == LightFormat::zh3) {
        const Zh3Probe<double> fit = encode_zh3<double>(all, raw.zh3_axis, Zh3Fit::explicit_fit);
        const Zh3Probe<double> guess = encode_zh3<double>(all, raw.zh3_axis, Zh3Fit::hallucinated);
        nlohmann::json axes = nlohmann::json::array();
        for (int c = 0; c < 3; ++c) {
          const Vec3<double> a = zh3_axis(fit.l1, raw.zh3_axis, c);
          axes.push_back({a.x(), a.y(), a.z()});
        }
        doc["axis"] = name_of(raw.zh3_axis, zh3_axis_names());
        if (raw.zh3_axis == Zh3Axis::luminance) doc["luminance_weights"] = kZh3LuminanceWeights;
        doc["zonal"] = fit.zonal;
        doc["zonal_hallucinated"] = guess.zonal;
        doc["axes"] = axes;
      }
      out.text = rows_text(doc);
      if (intensity != 1) out.notes.push_back("--intensity is folded into the coefficients");
      break;
    }
    case LightFormat::raw: {
      std::vector<double> g = to_engine_frame(frame, light.coefficients);
      for (int i = 0; i < sh_count(light.order); ++i) {
        const int l = sh_band(i), m = i - l * (l + 1);
        const double s = (raw.condon_shortley || m % 2 == 0 ? 1 : -1) * raw_scale(l, raw.normalization) * intensity;
        for (int c = 0; c < 3; ++c) g[3 * i + c] *= s;
      }
      nlohmann::json rows = nlohmann::json::array();
      for (int i = 0; i < sh_count(light.order); ++i) rows.push_back({g[3 * i], g[3 * i + 1], g[3 * i + 2]});
      const std::string& norm = name_of(raw.normalization, raw_normalization_names());
      out.text = rows_text({{"order", light.order},
                            {"quantity", lighting::quantity_name(light.quantity)},
                            {"condon_shortley", raw.condon_shortley},
                            {"normalization", norm},
                            {"index", "acn"},
                            {"frame", frame.text},
                            {"coefficients", rows}});
      break;
    }
  }
  return out;
}

namespace {

Lighting import_light_as_read(std::string_view text, const std::filesystem::path& name, LightFormat format,
                      const FrameMap& frame, Quantity quantity) {
  if (format == LightFormat::filament || format == LightFormat::filament_radiance) {
    const bool irradiance = format == LightFormat::filament;
    // Lines "( r, g, b); // comment": scanned by hand (a regex engine that recurses per
    // character would let a long line exhaust the stack).
    Nine g{};
    int i = 0;
    std::istringstream lines{std::string(text)};
    std::string line;
    while (std::getline(lines, line)) {
      const std::size_t open = line.find('('), close = line.find(')');
      const std::size_t comment = line.find("//");
      if (open == std::string::npos || (comment != std::string::npos && comment < open)) continue;
      if (close == std::string::npos || close < open) bad(name, "a row without its ')': " + line.substr(0, 80));
      if (i >= 9) bad(name, "more than 9 ( r, g, b) rows");
      std::istringstream fields(line.substr(open + 1, close - open - 1));
      std::string v;
      for (int c = 0; c < 3; ++c) {
        if (!std::getline(fields, v, ',')) bad(name, "row " + std::to_string(i) + " does not hold three numbers");
        const std::size_t a = v.find_first_not_of(" \t"), b = v.find_last_not_of(" \t");
        v = a == std::string::npos ? std::string() : v.substr(a, b - a + 1);
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        if (v.empty() || end != v.c_str() + v.size() || !std::isfinite(x))
          bad(name, "'" + v.substr(0, 40) + "' is not a finite number");
        g[3 * i + c] = irradiance ? kSigma[i] * x * kPi / kAbsK[i] : x;
      }
      if (std::getline(fields, v, ',')) bad(name, "row " + std::to_string(i) + " holds more than three numbers");
      const std::string after =
          line.substr(close + 1, comment == std::string::npos ? std::string::npos : comment - close - 1);
      if (after.find_first_not_of(" \t\r;") != std::string::npos)
        bad(name,
            "row " + std::to_string(i) + " is followed by '" + after.substr(0, 40) + "' (one ( r, g, b) row a line)");
      // cmgen tags each row with its variant; a tag that is not this format's means the
      // numbers mean something else (E without 1/pi and the constants, or radiance).
      if (comment != std::string::npos) {
        const std::string tag = line.substr(comment + 2);
        const bool says_irradiance = tag.find("irradiance") != std::string::npos;
        const bool says_radiance = !says_irradiance && tag.find("radiance") != std::string::npos;
        const bool says_prescaled = tag.find("pre-scaled") != std::string::npos;
        const bool other =
            irradiance ? says_radiance || says_irradiance != says_prescaled : says_irradiance || says_prescaled;
        if (other)
          bad(name,
              "row " + std::to_string(i) + " is marked '" + tag.substr(0, 60) + "', another variant than --format " +
                  (irradiance ? "filament reads (irradiance, pre-scaled base)" : "filament-radiance reads (radiance)"));
      }
      ++i;
    }
    if (i != 9) bad(name, "expected 9 ( r, g, b) rows, found " + std::to_string(i));
    return from_nine(frame, g, irradiance ? Quantity::irradiance : Quantity::radiance, quantity);
  }
  const nlohmann::json doc = parse_json_input(text, name, "file");
  if (!doc.is_object()) bad(name, "not a JSON object");
  switch (format) {
    case LightFormat::threejs: {
      const nlohmann::json* object = doc.contains("object") ? &doc["object"] : &doc;
      if (!object->is_object() || !object->contains("sh")) bad(name, "no object.sh (a three.js LightProbe)");
      const nlohmann::json& sh = (*object)["sh"];
      if (!sh.is_array() || sh.size() != 27) bad(name, "object.sh must hold 27 numbers");
      const double s = intensity_field(*object, name);
      Nine g{};
      for (int i = 0; i < 27; ++i) g[i] = kSigma[i / 3] * finite_number(sh[i], name, "sh[" + std::to_string(i) + "]") * s;
      return from_nine(frame, g, Quantity::radiance, quantity);
    }
    case LightFormat::unity: {
      const auto it = doc.find("SphericalHarmonicsL2");
      if (it == doc.end() || !it->is_array() || it->size() != 27) bad(name, "SphericalHarmonicsL2 must hold 27 numbers");
      Nine g{};
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 9; ++i)
          g[3 * i + c] = kSigma[i] * finite_number((*it)[9 * c + i], name, "SphericalHarmonicsL2") * kPi / kAbsK[i];
      return from_nine(frame, g, Quantity::irradiance, quantity);
    }
    case LightFormat::gltf:
    case LightFormat::gltf_khr: {
      const char* ext = format == LightFormat::gltf ? "EXT_lights_image_based" : "KHR_lights_environment";
      const nlohmann::json* lights = nullptr;
      if (doc.contains("extensions") && doc["extensions"].is_object() && doc["extensions"].contains(ext) &&
          doc["extensions"][ext].is_object() && doc["extensions"][ext].contains("lights"))
        lights = &doc["extensions"][ext]["lights"];
      if (!lights || !lights->is_array() || lights->empty())
        bad(name, std::string("no extensions.") + ext + ".lights[0]");
      // The light the default scene names (as Babylon's loader takes it), else the first.
      std::size_t which = 0;
      const std::size_t scene =
          doc.contains("scene") && doc["scene"].is_number_unsigned() ? doc["scene"].get<std::size_t>() : 0;
      if (doc.contains("scenes") && doc["scenes"].is_array() && scene < doc["scenes"].size()) {
        const nlohmann::json& sc = doc["scenes"][scene];
        if (sc.is_object() && sc.contains("extensions") && sc["extensions"].is_object() &&
            sc["extensions"].contains(ext)) {
          const nlohmann::json& ref = sc["extensions"][ext];
          if (!ref.is_object() || !ref.contains("light") || !ref["light"].is_number_unsigned() ||
              ref["light"].get<std::size_t>() >= lights->size())
            bad(name, std::string("scenes[") + std::to_string(scene) + "].extensions." + ext +
                          ".light does not name one of its " + std::to_string(lights->size()) + " lights");
          which = ref["light"].get<std::size_t>();
        }
      }
      if (!(*lights)[which].is_object())
        bad(name, std::string("extensions.") + ext + ".lights[" + std::to_string(which) + "] is not an object");
      const nlohmann::json& light = (*lights)[which];
      if (!light.contains("irradianceCoefficients")) bad(name, "the light has no irradianceCoefficients");
      Nine g = rows_of(light["irradianceCoefficients"], name, "irradianceCoefficients");
      // EXT_lights_image_based's rotation turns the environment; which way in Babylon's
      // left-handed frame is not settled here, so only the identity (what export-light
      // writes) is read: any other would be a differently lit scene.
      if (light.contains("rotation")) {
        const nlohmann::json& q = light["rotation"];
        if (!q.is_array() || q.size() != 4) bad(name, "the light's rotation must be a quaternion [x, y, z, w]");
        double axis = 0;  // the largest of x, y, z
        for (int i = 0; i < 3; ++i) axis = std::max(axis, std::abs(finite_number(q[i], name, "rotation")));
        const double w = std::abs(finite_number(q[3], name, "rotation"));
        if (axis > 1e-9 || std::abs(w - 1) > 1e-9)
          bad(name, "the light's rotation is not the identity [0, 0, 0, 1]: shtool reads unrotated environments only "
                    "(import the coefficients without it, then turn them with shtool rotate)");
      }
      const double s = intensity_field(light, name);
      for (double& v : g) v *= s;
      return from_nine(frame, g, Quantity::irradiance, quantity);
    }
    case LightFormat::babylon: {
      const nlohmann::json* poly = doc.contains("irradiance") ? &doc["irradiance"] : &doc;
      Nine p{};
      for (int i = 0; i < 9; ++i) {
        if (!poly->is_object() || !poly->contains(kPolyNames[i])) bad(name, std::string("irradiance.") + kPolyNames[i] + " is missing");
        const nlohmann::json& v = (*poly)[kPolyNames[i]];
        if (!v.is_array() || v.size() != 3) bad(name, std::string("irradiance.") + kPolyNames[i] + " is not [r, g, b]");
        for (int c = 0; c < 3; ++c) p[3 * i + c] = finite_number(v[c], name, std::string("irradiance.") + kPolyNames[i]);
      }
      Nine h = harmonics_from_polynomial(p);
      for (double& v : h) v *= kPi;
      return from_nine(frame, h, Quantity::irradiance, quantity);
    }
    case LightFormat::godot: {
      if (!doc.contains("godot_lightmap_probe_sh")) bad(name, "no godot_lightmap_probe_sh");
      Nine g = rows_of(doc["godot_lightmap_probe_sh"], name, "godot_lightmap_probe_sh");
      for (int i = 0; i < 27; ++i) g[i] *= kSigma[i / 3] * kPi;
      return from_nine(frame, g, Quantity::radiance, quantity);
    }
    case LightFormat::raw: {
      // The file says how it was written; --frame is the file's frame.
      const auto order = doc.find("order");
      if (order == doc.end() || !order->is_number_integer() || order->get<long long>() < 1 || order->get<long long>() > 32)
        bad(name, "\"order\" must be an integer in 1..32");
      const int n = order->get<int>();
      if (doc.contains("condon_shortley") && !doc["condon_shortley"].is_boolean())
        bad(name, "\"condon_shortley\" must be true or false");
      const bool cs = doc.value("condon_shortley", true);
      for (const char* key : {"normalization", "frame", "quantity"})
        if (doc.contains(key) && !doc[key].is_string()) bad(name, std::string("\"") + key + "\" must be a string");
      RawNormalization norm = RawNormalization::orthonormal;
      if (doc.contains("normalization")) {
        bool known = false;
        for (const auto& [k, v] : raw_normalization_names())
          if (doc["normalization"] == k) norm = v, known = true;
        if (!known) bad(name, "\"normalization\" must be orthonormal, 4pi or schmidt");
      }
      if (doc.contains("index") && doc["index"] != "acn")
        bad(name, "\"index\" must be \"acn\" (raw files hold ACN order: index l(l+1)+m)");
      FrameMap f = frame;
      if (doc.contains("frame") && doc["frame"].is_string()) {
        try {
          f = parse_frame_map(doc["frame"].get<std::string>());
        } catch (const InputError& e) {
          bad(name, std::string("\"frame\": ") + e.what());
        }
      }
      Quantity stored = Quantity::radiance;
      if (doc.contains("quantity")) {
        if (doc["quantity"] == "irradiance") stored = Quantity::irradiance;
        else if (doc["quantity"] != "radiance") bad(name, "\"quantity\" must be radiance or irradiance");
      }
      const auto rows = doc.find("coefficients");
      if (rows == doc.end() || !rows->is_array() || rows->size() != static_cast<std::size_t>(sh_count(n)))
        bad(name, "\"coefficients\" must hold order^2 rows");
      std::vector<double> g(static_cast<std::size_t>(sh_count(n)) * 3);
      for (int i = 0; i < sh_count(n); ++i) {
        const nlohmann::json& r = (*rows)[i];
        if (!r.is_array() || r.size() != 3) bad(name, "coefficient row " + std::to_string(i) + " is not [r, g, b]");
        const int l = sh_band(i), m = i - l * (l + 1);
        const double s = (cs || m % 2 == 0 ? 1 : -1) / raw_scale(l, norm);
        for (int c = 0; c < 3; ++c) g[3 * i + c] = s * finite_number(r[c], name, "coefficient row " + std::to_string(i));
      }
      Lighting l;
      l.order = n;
      l.quantity = stored;
      l.coefficients = from_engine_frame(f, g);
      if (quantity != stored) {
        for (int i = 0; i < sh_count(n); ++i) {
          const double a = clamped_cosine_band(sh_band(i));
          if (a == 0 && quantity == Quantity::radiance) {
            bool zero = true;
            for (int c = 0; c < 3; ++c) zero = zero && l.coefficients[3 * i + c] == 0;
            if (!zero) bad(name, "irradiance band " + std::to_string(sh_band(i)) + " is not zero: no radiance has it");
          }
          for (int c = 0; c < 3; ++c) l.coefficients[3 * i + c] *= quantity == Quantity::irradiance ? a : (a == 0 ? 0 : 1 / a);
        }
        l.quantity = quantity;
      }
      return l;
    }
    default: break;
  }
  bad(name, "unknown format");
}

}  // namespace

Lighting import_light(std::string_view text, const std::filesystem::path& name, LightFormat format,
                      const FrameMap& frame, Quantity quantity) {
  Lighting l = import_light_as_read(text, name, format, frame, quantity);
  // Finite numbers whose conversion overflows (an intensity times a coefficient, pi / A_l).
  for (double c : l.coefficients)
    if (!std::isfinite(c)) bad(name, "its light overflows a double in shtool's convention (values too large)");
  return l;
}

}  // namespace shtool::interop
