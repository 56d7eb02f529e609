// export-light and import-light: round trips for every format; every frame map checked
// by f'(O d) = f(d); three.js and Babylon.js evaluating the exported files with their own
// code in node; filament's, Unity's and Godot's shader formulas written out from their
// sources; bad input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "interop/engine_light.h"
#include "lighting/lighting_output.h"
#include "node_consumers.h"
#include "cli_test.h"
#include "shtool/irradiance.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

using namespace test;
using lighting::Lighting;
using lighting::Quantity;
constexpr double kPi = std::numbers::pi;

const Scratch scratch("engine_light");

Lighting random_light(int order, Quantity q, unsigned seed) {
  Lighting l = random_radiance(order, seed, 1.0, {5, 5, 5});
  l.quantity = q;
  if (q == Quantity::irradiance)  // a real irradiance: A_l times a radiance
    for (int i = 0; i < sh_count(order); ++i)
      for (int c = 0; c < 3; ++c) l.coefficients[3 * i + c] *= clamped_cosine_band(sh_band(i));
  return l;
}

std::array<double, 3> eval(const Lighting& l, const Eigen::Vector3d& w) {
  std::vector<double> y(sh_count(l.order));
  eval_sh<double>(l.order, w, y);
  std::array<double, 3> out{};
  for (int i = 0; i < sh_count(l.order); ++i)
    for (int c = 0; c < 3; ++c) out[c] += l.coefficients[3 * i + c] * y[i];
  return out;
}

// The light's irradiance (any quantity in, order 3 used: what the engines keep).
Lighting irradiance_of(Lighting l) {
  l.order = std::min(l.order, 3);
  l.coefficients.resize(static_cast<std::size_t>(sh_count(l.order)) * 3);
  if (l.quantity == Quantity::radiance)
    for (int i = 0; i < sh_count(l.order); ++i)
      for (int c = 0; c < 3; ++c) l.coefficients[3 * i + c] *= clamped_cosine_band(sh_band(i));
  l.quantity = Quantity::irradiance;
  return l;
}

const std::vector<std::string> kFormats = {"threejs", "filament", "filament-radiance", "unity", "gltf",
                                           "gltf-khr", "babylon", "godot", "raw"};

TEST(EngineLight, ExportThenImportIsTheIdentity) {
  for (Quantity q : {Quantity::radiance, Quantity::irradiance}) {
    for (int order : {2, 3, 5}) {
      const Lighting l = random_light(order, q, 7 + order);
      const fs::path in = scratch("light.json");
      std::ofstream(in) << lighting::lighting_json(l);
      for (const std::string& f : kFormats) {
        const fs::path out = scratch("exported." + f), back = scratch("back.json");
        for (const std::string& intensity : {"1", "2.5"}) {
          auto r = run_shtool({"export-light", in.string(), "--format", f, "--out", out.string(), "--intensity", intensity});
          ASSERT_EQ(r.exit_code, 0) << f << ": " << r.err;
          if (order > 3 && f != "raw") EXPECT_NE(r.err.find("dropped"), std::string::npos) << f << ": " << r.err;
          r = run_shtool({"import-light", out.string(), "--format", f, "--json", back.string(), "--quantity",
                           lighting::quantity_name(q)});
          ASSERT_EQ(r.exit_code, 0) << f << ": " << r.err;
          const Lighting got = lighting::read_lighting_json(back, "back");
          const int kept = f == "raw" ? order : std::min(order, 3);
          const double s = std::stod(intensity);
          for (int i = 0; i < sh_count(kept); ++i)
            for (int c = 0; c < 3; ++c)
              ASSERT_NEAR(got.coefficients[3 * i + c], s * l.coefficients[3 * i + c], 1e-13 * (1 + std::abs(s * l.coefficients[3 * i + c])))
                  << f << " order " << order << " coefficient " << i;
          for (int i = sh_count(kept); i < sh_count(got.order); ++i) EXPECT_EQ(got.coefficients[3 * i], 0.0) << f;
        }
      }
    }
  }
}

// Every signed permutation, proper or not: the engine-frame coefficients evaluated with
// the basis formula at O d equal the light at d (1000 random d), at orders up to 6.
TEST(EngineLight, EveryFrameMapCarriesTheLight) {
  const std::array<std::array<int, 3>, 6> perms = {{{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  const Lighting l = random_light(6, Quantity::radiance, 3);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  int maps = 0;
  for (const auto& p : perms)
    for (int signs = 0; signs < 8; ++signs) {
      std::string text;
      for (int k = 0; k < 3; ++k) text += std::string(k ? "," : "") + ((signs >> k) & 1 ? "-" : "") + char('x' + p[k]);
      const interop::FrameMap f = interop::parse_frame_map(text);
      Lighting e = l;
      e.coefficients = interop::to_engine_frame(f, l.coefficients);
      for (int k = 0; k < 1000; ++k) {
        const Eigen::Vector3d d = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        const auto a = eval(l, d), b = eval(e, f.q * d);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(b[c], a[c], 1e-12) << text;
      }
      const std::vector<double> back = interop::from_engine_frame(f, e.coefficients);
      for (std::size_t i = 0; i < back.size(); ++i) ASSERT_NEAR(back[i], l.coefficients[i], 1e-13) << text;
      ++maps;
    }
  EXPECT_EQ(maps, 48);
}

// Each default frame is the glTF frame (x, z, -y of shtool's: +Y up, right-handed) as
// the engine imports a glTF scene: unchanged by three.js, filament and Godot, x negated
// by Unity's importers (UnityGLTF, glTFast) and Babylon's default left-handed scene.
TEST(EngineLight, DefaultFramesAreTheGltfFrameAsEachEngineImportsIt) {
  Eigen::Matrix3d gltf;
  gltf << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  const Eigen::Matrix3d negate_x = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  using interop::LightFormat;
  for (LightFormat f :
       {LightFormat::threejs, LightFormat::filament, LightFormat::filament_radiance, LightFormat::godot})
    EXPECT_EQ(interop::default_frame(f).q, gltf) << interop::default_frame(f).text;
  for (LightFormat f : {LightFormat::unity, LightFormat::gltf, LightFormat::gltf_khr, LightFormat::babylon})
    EXPECT_EQ(interop::default_frame(f).q, negate_x * gltf) << interop::default_frame(f).text;
  EXPECT_EQ(interop::default_frame(LightFormat::unity).text, "-x,z,-y");
}

// The reflections act on c_lm by signs (docs/interop.md).
TEST(EngineLight, ReflectionsAreSigns) {
  const Lighting l = random_light(5, Quantity::radiance, 9);
  struct Case {
    const char* map;
    int (*sign)(int l, int m);
  };
  const Case cases[] = {
      {"x,y,-z", [](int l, int m) { return (l + m) % 2 == 0 ? 1 : -1; }},
      {"x,-y,z", [](int, int m) { return m < 0 ? -1 : 1; }},
      {"-x,y,z", [](int, int m) { return m >= 0 ? (m % 2 == 0 ? 1 : -1) : ((m + 1) % 2 == 0 ? 1 : -1); }},
  };
  for (const Case& c : cases) {
    const std::vector<double> e = interop::to_engine_frame(interop::parse_frame_map(c.map), l.coefficients);
    for (int lb = 0; lb < 5; ++lb)
      for (int m = -lb; m <= lb; ++m)
        for (int ch = 0; ch < 3; ++ch)
          EXPECT_NEAR(e[3 * sh_index(lb, m) + ch], c.sign(lb, m) * l.coefficients[3 * sh_index(lb, m) + ch], 1e-13) << c.map;
  }
}

// 50 random unit directions of the engine's frame, and the shtool direction each stands for.
struct Directions {
  std::vector<Eigen::Vector3d> engine, shtool;
};
Directions directions(const interop::FrameMap& f) {
  std::mt19937 rng(21);
  std::normal_distribution<double> g;
  Directions d;
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    d.engine.push_back(e);
    d.shtool.push_back(f.q.transpose() * e);
  }
  return d;
}

nlohmann::json consumer_eval(const std::string& format, const fs::path& file, const Directions& d) {
  const fs::path dirs = scratch("dirs.json");
  nlohmann::json j = nlohmann::json::array();
  for (const auto& e : d.engine) j.push_back({e.x(), e.y(), e.z()});
  std::ofstream(dirs) << j.dump();
  const auto r = run_command({"node", (fs::path(SHTOOL_BINARY_DIR) / "node_consumers" / "eval_light.mjs").string(),
                              format, file.string(), dirs.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

TEST(EngineLight, TheConsumersReadWhatWasMeant) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const Lighting l = random_light(4, Quantity::radiance, 13);  // band 3 is dropped on export
  const fs::path in = scratch("consumer.json");
  std::ofstream(in) << lighting::lighting_json(l);
  const Lighting e = irradiance_of(l);
  Lighting l3 = l;
  l3.order = 3;
  l3.coefficients.resize(27);
  // three.js: radiance and irradiance, the intensity field applied by three.
  {
    const fs::path out = scratch("probe.json");
    ASSERT_EQ(run_shtool({"export-light", in.string(), "--format", "threejs", "--intensity", "2", "--out", out.string()}).exit_code, 0);
    const Directions d = directions(interop::default_frame(interop::LightFormat::threejs));
    const nlohmann::json got = consumer_eval("threejs", out, d);
    ASSERT_EQ(got.size(), 50u);
    for (int k = 0; k < 50; ++k) {
      const auto L = eval(l3, d.shtool[k]), E = eval(e, d.shtool[k]);
      for (int c = 0; c < 3; ++c) {
        // three's constants have 6 digits (0.282095, 0.488603, ...).
        EXPECT_NEAR(got[k]["radiance"][c].get<double>(), 2 * L[c], 2e-5 * (1 + std::abs(L[c])));
        EXPECT_NEAR(got[k]["irradiance"][c].get<double>(), 2 * E[c], 2e-5 * (1 + std::abs(E[c])));
      }
    }
  }
  // Babylon.js, through its glTF EXT_lights_image_based loader steps and through a .env
  // manifest's polynomial: E / pi at the direction of its default (left-handed) scene,
  // times the intensity once (Babylon's glTF loader applies the light's intensity twice,
  // to the SH and as the texture's level: shtool folds it into the coefficients).
  for (const std::string f : {"gltf", "babylon"})
    for (const double intensity : {1.0, 2.0}) {
      const fs::path out = scratch("exported_" + f + ".json");
      ASSERT_EQ(run_shtool({"export-light", in.string(), "--format", f, "--intensity", std::to_string(intensity),
                            "--out", out.string()})
                    .exit_code,
                0);
      const Directions d = directions(interop::default_frame(interop::LightFormat::babylon));
      const nlohmann::json got = consumer_eval(f, out, d);
      ASSERT_EQ(got.size(), 50u);
      for (int k = 0; k < 50; ++k) {
        const auto E = eval(e, d.shtool[k]);
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(got[k]["irradiance_over_pi"][c].get<double>(), intensity * E[c] / kPi,
                      2e-5 * (1 + std::abs(intensity * E[c])))
              << f << " at --intensity " << intensity;
      }
    }
}

// A glTF document of several lights: the default scene's reference picks the one read
// (as Babylon's loader takes it), and a reference to no light is refused.
TEST(EngineLight, GltfImportReadsTheLightItsSceneNames) {
  auto document = [](int light) {
    std::string rows = "[1,1,1],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0]";
    return R"({"asset": {"version": "2.0"}, "extensions": {"EXT_lights_image_based": {"lights": [)"
           R"({"intensity": 1, "irradianceCoefficients": [)" +
           rows +
           R"(]},)"
           R"({"intensity": 5, "irradianceCoefficients": [)" +
           rows +
           R"(]}]}},)"
           R"("scene": 0, "scenes": [{"extensions": {"EXT_lights_image_based": {"light": )" +
           std::to_string(light) + "}}}]}";
  };
  const fs::path in = scratch("two_lights.gltf"), out = scratch("two_lights.json");
  double c00[2];
  for (int light : {0, 1}) {
    std::ofstream(in) << document(light);
    ASSERT_EQ(run_shtool({"import-light", in.string(), "--format", "gltf", "--json", out.string()}).exit_code, 0);
    c00[light] = nlohmann::json::parse(read_file(out))["coefficients"][0][0].get<double>();
  }
  EXPECT_DOUBLE_EQ(c00[1], 5 * c00[0]);
  std::ofstream(in) << document(2);
  const auto r = run_shtool({"import-light", in.string(), "--format", "gltf", "--json", scratch("none.json").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("EXT_lights_image_based.light does not name one of its 2 lights"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch("none.json")));
}

// The two glTF documents pass the Khronos validator without an error or warning (an
// empty scenes[0].nodes was one).
TEST(EngineLight, GltfExportsAreValidGltf) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const fs::path in = scratch("valid.json");
  std::ofstream(in) << lighting::lighting_json(random_light(3, Quantity::radiance, 19));
  for (const std::string f : {"gltf", "gltf-khr"}) {
    const fs::path out = scratch("valid_" + f + ".gltf");
    ASSERT_EQ(run_shtool({"export-light", in.string(), "--format", f, "--out", out.string()}).exit_code, 0);
    const auto r = run_command({"node", (node_consumers_dir() / "validate_gltf.mjs").string(), out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json issues = nlohmann::json::parse(r.out)["issues"];
    EXPECT_EQ(issues["numErrors"], 0) << f << issues.dump(1);
    EXPECT_EQ(issues["numWarnings"], 0) << f << issues.dump(1);
  }
}

// Engines that cannot run here: their shader formulas, written out from their sources.
TEST(EngineLight, ShaderFormulasOfFilamentUnityAndGodot) {
  const Lighting l = random_light(3, Quantity::radiance, 17);
  const Lighting e = irradiance_of(l);
  const fs::path in = scratch("shader.json");
  std::ofstream(in) << lighting::lighting_json(l);
  auto exported = [&](const std::string& f) {
    const fs::path out = scratch("shader." + f);
    EXPECT_EQ(run_shtool({"export-light", in.string(), "--format", f, "--out", out.string()}).exit_code, 0);
    return read_file(out);
  };
  // filament shaders/src/surface_light_indirect.fs Irradiance_SphericalHarmonics: the
  // nine pre-scaled values against (1, y, z, x, yx, yz, 3z^2 - 1, zx, x^2 - y^2): E / pi.
  {
    const std::string text = exported("filament");
    std::array<std::array<double, 3>, 9> sh{};
    std::size_t at = 0;
    for (auto& row : sh) {
      at = text.find('(', at) + 1;
      for (double& v : row) {
        v = std::stod(text.substr(at));
        at = text.find_first_of(",)", at) + 1;
      }
    }
    const Directions d = directions(interop::default_frame(interop::LightFormat::filament));
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d n = d.engine[k];
      const auto E = eval(e, d.shtool[k]);
      for (int c = 0; c < 3; ++c) {
        const double v = sh[0][c] + sh[1][c] * n.y() + sh[2][c] * n.z() + sh[3][c] * n.x() + sh[4][c] * n.y() * n.x() +
                         sh[5][c] * n.y() * n.z() + sh[6][c] * (3 * n.z() * n.z() - 1) + sh[7][c] * n.z() * n.x() +
                         sh[8][c] * (n.x() * n.x() - n.y() * n.y());
        EXPECT_NEAR(v, E[c] / kPi, 1e-12) << "filament";
      }
    }
  }
  // Unity UnityCG.cginc ShadeSH9: dot(SHA, (n, 1)) + dot(SHB, n.xyzz * n.yzzx) + SHC (x^2 - y^2).
  {
    const nlohmann::json j = nlohmann::json::parse(exported("unity"));
    const Directions d = directions(interop::default_frame(interop::LightFormat::unity));
    const char* rgb = "rgb";
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d n = d.engine[k];
      const auto E = eval(e, d.shtool[k]);
      const double vb[4] = {n.x() * n.y(), n.y() * n.z(), n.z() * n.z(), n.z() * n.x()};
      for (int c = 0; c < 3; ++c) {
        const auto& a = j[std::string("unity_SHA") + rgb[c]];
        const auto& b = j[std::string("unity_SHB") + rgb[c]];
        double v = a[0].get<double>() * n.x() + a[1].get<double>() * n.y() + a[2].get<double>() * n.z() + a[3].get<double>();
        for (int q = 0; q < 4; ++q) v += b[q].get<double>() * vb[q];
        v += j["unity_SHC"][c].get<double>() * (n.x() * n.x() - n.y() * n.y());
        EXPECT_NEAR(v, E[c] / kPi, 1e-12) << "unity";
      }
    }
  }
  // Godot scene_forward_clustered.glsl, the LightmapGI capture branch: constants
  // 0.886227, 1.023327, 0.858086, 0.247708, 0.429043 on L / pi data give E / pi.
  {
    const nlohmann::json j = nlohmann::json::parse(exported("godot"))["godot_lightmap_probe_sh"];
    const Directions d = directions(interop::default_frame(interop::LightFormat::godot));
    const double c1 = 0.886227, c2 = 1.023327, c3 = 0.858086, c4 = 0.247708, c5 = 0.429043;
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d n = d.engine[k];
      const auto E = eval(e, d.shtool[k]);
      for (int c = 0; c < 3; ++c) {
        auto s = [&](int i) { return j[i][c].get<double>(); };
        const double v = c1 * s(0) + c2 * (s(1) * n.y() + s(2) * n.z() + s(3) * n.x()) +
                         c3 * (s(4) * n.x() * n.y() + s(5) * n.y() * n.z() + s(7) * n.x() * n.z()) +
                         c4 * s(6) * (3 * n.z() * n.z() - 1) + c5 * s(8) * (n.x() * n.x() - n.y() * n.y());
        EXPECT_NEAR(v, E[c] / kPi, 2e-6 * (1 + std::abs(E[c]))) << "godot";  // 6-digit constants
      }
    }
  }
}

TEST(EngineLight, BadInput) {
  const fs::path in = scratch("bad_in.json");
  std::ofstream(in) << lighting::lighting_json(random_light(3, Quantity::radiance, 1));
  const fs::path bad_probe = scratch("bad_probe.json"), bad_txt = scratch("bad_sh.txt");
  std::ofstream(bad_probe) << R"({"object": {"type": "LightProbe", "sh": [1, 2, 3]}})";
  std::ofstream(bad_txt) << "(1, 2, 3); // L00\n(1, 2, nan); // L1-1\n";
  const fs::path short_txt = scratch("short_sh.txt");
  std::ofstream(short_txt) << "(1, 2, 3); // L00\n(1, 2, 3); // L1-1\n";
  // A row of half a million digits (a recursive regex would exhaust the stack on it).
  const fs::path long_line = scratch("long_sh.txt");
  std::ofstream(long_line) << "(" << std::string(500000, '1') << "x, 2, 3); // L00\n";
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  // A raw file in another index order or with a malformed frame; a glTF light turned by
  // a rotation (read as if unrotated, it would light another scene).
  const fs::path raw = scratch("bad_raw.json"), raw_frame = scratch("bad_raw_frame.json");
  std::ofstream(raw) << R"({"order": 1, "index": "fuma", "coefficients": [[1, 1, 1]]})";
  std::ofstream(raw_frame) << R"({"order": 1, "frame": "x,q,z", "coefficients": [[1, 1, 1]]})";
  const fs::path turned = scratch("turned.gltf");
  std::ofstream(turned) << R"({"asset": {"version": "2.0"}, "extensions": {"EXT_lights_image_based": {"lights": [)"
                        << R"({"rotation": [0, 0.7071068, 0, 0.7071068], "irradianceCoefficients": [)"
                        << R"([1,1,1],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0],[0,0,0]]}]}}})";
  // A probe that takes light away; sh.txt rows two to a line, or tagged as another of
  // cmgen's variants than the format read.
  const fs::path negative = scratch("negative_probe.json"), two_rows = scratch("two_rows.txt"),
                 radiance_rows = scratch("radiance_rows.txt"), irradiance_rows = scratch("irradiance_rows.txt");
  {
    std::ofstream n(negative), t(two_rows), r(radiance_rows), e(irradiance_rows);
    n << R"({"object": {"intensity": -2, "sh": [1, 1, 1)";
    for (int i = 3; i < 27; ++i) n << ", 0";
    n << "]}}";
    t << "(1, 1, 1); (2, 2, 2); // L00, irradiance, pre-scaled base\n";
    for (int i = 0; i < 9; ++i) {
      r << "(1, 1, 1); // L" << i << ", radiance\n";
      e << "(1, 1, 1); // L" << i << (i == 4 ? ", irradiance\n" : ", irradiance, pre-scaled base\n");
    }
  }
  const fs::path out = scratch("bad_out");
  const std::vector<Case> cases = {
      {{"import-light", negative.string(), "--format", "threejs", "--json", out.string()}, "intensity -2 is negative"},
      {{"import-light", two_rows.string(), "--format", "filament", "--json", out.string()},
       "one ( r, g, b) row a line"},
      {{"import-light", radiance_rows.string(), "--format", "filament", "--json", out.string()},
       "row 0 is marked ' L0, radiance'"},
      {{"import-light", irradiance_rows.string(), "--format", "filament", "--json", out.string()},
       "row 4 is marked ' L4, irradiance'"},
      {{"import-light", irradiance_rows.string(), "--format", "filament-radiance", "--json", out.string()},
       "row 0 is marked"},
      {{"export-light", in.string(), "--format", "threejs", "--frame", "x,y,z,", "--out", out.string()}, "--frame"},
      {{"export-light", in.string(), "--format", "threejs", "--cs", "off", "--out", out.string()}, "--format raw only"},
      {{"export-light", in.string(), "--format", "unity", "--norm", "4pi", "--out", out.string()}, "--format raw only"},
      {{"import-light", in.string(), "--format", "raw", "--cs", "off", "--json", out.string()}, "takes no --cs"},
      {{"import-light", raw.string(), "--format", "raw", "--json", out.string()}, "\"index\" must be \"acn\""},
      {{"import-light", raw_frame.string(), "--format", "raw", "--json", out.string()},
       "bad_raw_frame.json: \"frame\""},
      {{"import-light", turned.string(), "--format", "gltf", "--json", out.string()}, "rotation is not the identity"},
      {{"export-light", in.string(), "--format", "unreal", "--out", out.string()}, "--format"},
      {{"export-light", in.string(), "--format", "threejs", "--frame", "x,x,y", "--out", out.string()}, "--frame"},
      {{"export-light", in.string(), "--format", "threejs", "--frame", "x,z", "--out", out.string()}, "--frame"},
      {{"export-light", in.string(), "--format", "threejs", "--frame", "x,y,z,x", "--out", out.string()}, "--frame"},
      {{"import-light", long_line.string(), "--format", "filament", "--json", out.string()}, "not a finite number"},
      {{"export-light", in.string(), "--format", "threejs", "--intensity", "-1", "--out", out.string()}, "--intensity"},
      {{"export-light", scratch("missing.json").string(), "--format", "threejs", "--out", out.string()},
       "missing.json"},
      {{"import-light", bad_probe.string(), "--format", "threejs", "--json", out.string()}, "27 numbers"},
      {{"import-light", bad_txt.string(), "--format", "filament", "--json", out.string()},
       "'nan' is not a finite number"},
      {{"import-light", short_txt.string(), "--format", "filament", "--json", out.string()}, "expected 9"},
      {{"import-light", in.string(), "--format", "gltf", "--json", out.string()}, "EXT_lights_image_based"},
  };
  for (const Case& c : cases) {
    fs::remove(out);
    const auto r = run_shtool(c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args[0] << " " << c.message << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace
}  // namespace shtool
