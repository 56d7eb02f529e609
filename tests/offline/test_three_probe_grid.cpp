// The three.js LightProbeGridWebGL files (interop/three_probe_grid.h): the shtool -> three
// coefficient map against three's basis written out, the atlas byte by byte, bad grids
// refused with nothing written, and three@0.187.0 itself loading the files through
// web/shtool-three.js in node and evaluating every probe with getIrradianceAt.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/input_error.h"
#include "interop/engine_light.h"
#include "interop/three_probe_grid.h"
#include "node_consumers.h"
#include "run_command.h"
#include "scratch_files.h"
#include "shtool/irradiance.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

namespace fs = std::filesystem;
using interop::ThreeProbeGridInput;

fs::path scratch_dir(const std::string& name) {
  const fs::path p = test::scratch_path("three_probe_grid", name);
  fs::create_directories(p);
  return p;
}

// three's SphericalHarmonics3 basis (src/math/SphericalHarmonics3.js, getAt), with exact
// constants, in three's own coordinates.
std::array<double, 9> three_basis(const Eigen::Vector3d& d) {
  const double x = d.x(), y = d.y(), z = d.z();
  const double k0 = 0.28209479177387814, k1 = 0.4886025119029199, k2 = 1.0925484305920792, k20 = 0.31539156525252005,
               k22 = 0.5462742152960396;
  return {k0, k1 * y, k1 * z, k1 * x, k2 * x * y, k2 * y * z, k20 * (3 * z * z - 1), k2 * x * z, k22 * (x * x - y * y)};
}

// shtool's direction of three's (X, Y, Z): (X, -Z, Y).
Eigen::Vector3d shtool_of_three(const Eigen::Vector3d& t) { return {t.x(), -t.z(), t.y()}; }

std::vector<double> random_coefficients(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> c(count);
  for (double& x : c) x = u(rng);
  return c;
}

// The consumers' folder with the module under test copied beside their scripts, which
// import it as ./shtool-three.js.
fs::path consumers_with_module() {
  const fs::path consumers = test::node_consumers_dir();
  fs::copy_file(fs::path(SHTOOL_SOURCE_DIR) / "web/shtool-three.js", consumers / "shtool-three.js",
                fs::copy_options::overwrite_existing);
  return consumers;
}

TEST(ThreeProbeGrid, CoefficientMapIsThreesBasisInThreesFrame) {
  // f_three(d) = f_shtool(w) at w = (X, -Z, Y) for 200 random directions: the frame and the
  // dropped Condon-Shortley sign together. Exact up to rounding (a signed permutation and
  // a 2x2 rotation of (c6, c8)).
  const std::vector<double> c = random_coefficients(27, 1);
  std::array<double, 27> in{};
  std::copy(c.begin(), c.end(), in.begin());
  const std::array<double, 27> t = interop::threejs_sh3(in);
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d d = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    const std::array<double, 9> b = three_basis(d);
    std::vector<double> y(9);
    eval_sh<double>(3, shtool_of_three(d), y);
    for (int ch = 0; ch < 3; ++ch) {
      double f3 = 0, fs = 0;
      for (int i = 0; i < 9; ++i) f3 += t[3 * i + ch] * b[i], fs += c[3 * i + ch] * y[i];
      ASSERT_NEAR(f3, fs, 1e-14) << d.transpose();
    }
  }
  // The closed form: t1 = c2, t2 = c1, t3 = -c3, t4 = -c7, t5 = c5, t7 = -c4,
  // t6 = -c6 / 2 - (sqrt3 / 2) c8, t8 = -(sqrt3 / 2) c6 + c8 / 2.
  const double h = std::sqrt(3.0) / 2;
  auto C = [&](int i) { return c[3 * i]; };
  const double expect[9] = {C(0), C(2), C(1), -C(3), -C(7), C(5), -C(6) / 2 - h * C(8), -C(4), -h * C(6) + C(8) / 2};
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(t[3 * i], expect[i], 1e-15) << "three coefficient " << i;
}

float float_at(const std::string& bytes, std::size_t index) {
  std::uint32_t u = 0;
  for (int b = 0; b < 4; ++b) u |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[4 * index + b])) << (8 * b);
  return std::bit_cast<float>(u);
}

TEST(ThreeProbeGrid, AtlasLayoutAndBoundsAsThreeSeesThem) {
  ThreeProbeGridInput g;
  g.resolution = {3, 2, 4};
  g.min = Eigen::Vector3d(-1, -2, 0.5);
  g.max = Eigen::Vector3d(2, 3, 4.5);
  g.order = 4;  // band 3 is dropped
  const std::size_t per = 16 * 3;
  g.coefficients = random_coefficients(3 * 2 * 4 * per, 3);
  const interop::ThreeProbeGridFiles f = interop::three_probe_grid_files(g);
  const nlohmann::json doc = nlohmann::json::parse(f.json);
  EXPECT_EQ(doc["three"], "0.187.0");
  EXPECT_EQ(doc["atlas"], "probes.bin");
  EXPECT_EQ(doc["resolution"], nlohmann::json({3, 4, 2}));  // (NX, NZ, NY)
  EXPECT_EQ(doc["boundingBox"]["min"], nlohmann::json({-1.0, 0.5, -3.0}));
  EXPECT_EQ(doc["boundingBox"]["max"], nlohmann::json({2.0, 4.5, 2.0}));
  const int tx = 3, ty = 4, tz = 2;
  ASSERT_EQ(f.atlas.size(), static_cast<std::size_t>(tx * ty * 7 * (tz + 2) * 4 * 4));
  for (int iz = 0; iz < 4; ++iz)
    for (int iy = 0; iy < 2; ++iy)
      for (int ix = 0; ix < 3; ++ix) {
        const std::size_t probe = (static_cast<std::size_t>(iz) * 2 + iy) * 3 + ix;
        std::array<double, 27> c{};
        for (int k = 0; k < 27; ++k) c[k] = g.coefficients[probe * per + k];
        const std::array<double, 27> t = interop::threejs_sh3(c);
        const int x = ix, y = iz, z = 1 - iy;  // three's probe of shtool's (ix, iy, iz)
        for (int slot = 0; slot < 7; ++slot) {
          std::vector<int> slices = {slot * (tz + 2) + 1 + z};
          if (z == 0) slices.push_back(slot * (tz + 2));
          if (z == tz - 1) slices.push_back(slot * (tz + 2) + tz + 1);
          for (int s : slices)
            for (int k = 0; k < 4; ++k) {
              const std::size_t at = ((static_cast<std::size_t>(s) * ty + y) * tx + x) * 4 + k;
              const float want = 4 * slot + k < 27 ? static_cast<float>(t[4 * slot + k]) : 0.0f;
              ASSERT_EQ(float_at(f.atlas, at), want) << "probe " << ix << "," << iy << "," << iz << " slot " << slot
                                                     << " slice " << s << " channel " << k;
            }
        }
      }
}

TEST(ThreeProbeGrid, BadGridsAreRefusedAndNothingIsWritten) {
  const fs::path dir = scratch_dir("bad");
  ThreeProbeGridInput ok;
  ok.resolution = {2, 2, 2};
  ok.min = Eigen::Vector3d(0, 0, 0);
  ok.max = Eigen::Vector3d(1, 1, 1);
  ok.coefficients = random_coefficients(8 * 27, 4);
  struct Case {
    ThreeProbeGridInput grid;
    std::string message;
  };
  std::vector<Case> cases;
  cases.push_back({ok, "coefficients for 8 probes"});
  cases.back().grid.coefficients.pop_back();
  cases.push_back({ok, "resolution 0"});
  cases.back().grid.resolution[1] = 0;
  cases.push_back({ok, "min < max"});
  cases.back().grid.max.z() = 0;
  cases.push_back({ok, "min < max"});
  cases.back().grid.min.x() = NAN;
  cases.push_back({ok, "not finite as float32"});
  cases.back().grid.coefficients[5 * 27] = 1e300;
  for (const Case& c : cases) {
    try {
      interop::write_three_probe_grid(dir, c.grid);
      ADD_FAILURE() << "accepted: " << c.message;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "probes.json"));
    EXPECT_FALSE(fs::exists(dir / "probes.bin"));
  }
  EXPECT_THROW(interop::write_three_probe_grid(dir / "missing", ok), InputError);
}

// The probes' irradiance as three.js computes it from the loaded files, against shtool's
// E = sum A_l L_lm y_lm at the same normal (mapped to shtool's frame). three's constants
// have 6 digits (relative differences up to 1.6e-6) and the atlas is float32 (6e-8):
// 1e-5 of the sum of the terms' sizes covers both and fails on any wrong sign or slot.
TEST(ThreeProbeGrid, ThreeLoadsTheFilesAndEvaluatesShtoolsIrradiance) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const fs::path consumers = consumers_with_module();
  ThreeProbeGridInput g;
  g.resolution = {3, 2, 2};
  g.min = Eigen::Vector3d(-2, -1, 0);
  g.max = Eigen::Vector3d(4, 1, 3);
  g.order = 3;
  g.coefficients = random_coefficients(12 * 27, 5);
  const fs::path dir = scratch_dir("grid");
  interop::write_three_probe_grid(dir, g);
  // 64 normals: the 6 axes and 58 random ones (three's frame).
  std::mt19937_64 rng(6);
  std::normal_distribution<double> gauss;
  std::vector<Eigen::Vector3d> normals = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (normals.size() < 64) normals.push_back(Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized());
  nlohmann::json nj = nlohmann::json::array();
  for (const auto& n : normals) nj.push_back({n.x(), n.y(), n.z()});
  test::write_file(dir / "normals.json", nj.dump());
  const test::CommandResult r = test::run_command(
      {"node", (consumers / "probe_grid_three.mjs").string(), (dir / "probes.json").string(), (dir / "normals.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json out = nlohmann::json::parse(r.out);
  ASSERT_FALSE(out.contains("error")) << out["error"];
  EXPECT_EQ(out["resolution"], nlohmann::json({3, 2, 2}));
  EXPECT_EQ(out["boundingBox"]["min"], nlohmann::json({-2.0, 0.0, -1.0}));
  EXPECT_EQ(out["boundingBox"]["max"], nlohmann::json({4.0, 3.0, 1.0}));
  EXPECT_EQ(out["padding_mismatches"], 0);
  EXPECT_EQ(out["disposed"], true) << "grid.dispose() left the atlas texture on the GPU";
  // three's constants: RGBAFormat 1023, FloatType 1015, LinearFilter 1006.
  EXPECT_EQ(out["textureType"]["format"], 1023);
  EXPECT_EQ(out["textureType"]["type"], 1015);
  EXPECT_EQ(out["textureType"]["minFilter"], 1006);
  EXPECT_EQ(out["textureType"]["magFilter"], 1006);
  EXPECT_EQ(out["textureType"]["generateMipmaps"], false);
  ASSERT_EQ(out["probes"].size(), 12u);
  double worst = 0;
  for (const nlohmann::json& p : out["probes"]) {
    const int i = p["index"][0], j = p["index"][1], k = p["index"][2];
    const int ix = i, iy = 2 - 1 - k, iz = j;
    // three's probe centre is shtool's, mapped.
    const Eigen::Vector3d centre(g.min.x() + (ix + 0.5) * 6 / 3, g.min.y() + (iy + 0.5) * 2 / 2,
                                 g.min.z() + (iz + 0.5) * 3 / 2);
    const Eigen::Vector3d three_position(p["position"][0], p["position"][1], p["position"][2]);
    EXPECT_LT((shtool_of_three(three_position) - centre).norm(), 1e-12) << i << "," << j << "," << k;
    const std::size_t probe = (static_cast<std::size_t>(iz) * 2 + iy) * 3 + ix;
    std::vector<double> e(g.coefficients.begin() + probe * 27, g.coefficients.begin() + (probe + 1) * 27);
    radiance_to_irradiance(3, e);
    std::vector<double> y(9);
    for (std::size_t q = 0; q < normals.size(); ++q) {
      eval_sh<double>(3, shtool_of_three(normals[q]), y);
      for (int c = 0; c < 3; ++c) {
        double want = 0, scale = 0;
        for (int n = 0; n < 9; ++n) want += e[3 * n + c] * y[n], scale += std::abs(e[3 * n + c] * y[n]);
        const double got = p["irradiance"][q][c];
        worst = std::max(worst, std::abs(got - want) / scale);
        ASSERT_NEAR(got, want, 1e-5 * scale) << "probe " << i << "," << j << "," << k << " normal " << q << " channel " << c;
      }
    }
  }
  std::printf("three.js getIrradianceAt vs shtool: worst error %.3g of the sum of term sizes\n", worst);
}

TEST(ThreeProbeGrid, TheModuleRefusesATruncatedAtlasByName) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const fs::path consumers = consumers_with_module();
  ThreeProbeGridInput g;
  g.resolution = {2, 1, 1};
  g.min = Eigen::Vector3d(0, 0, 0);
  g.max = Eigen::Vector3d(1, 1, 1);
  g.coefficients = random_coefficients(2 * 27, 8);
  const fs::path dir = scratch_dir("truncated");
  interop::write_three_probe_grid(dir, g);
  const std::string atlas = test::read_file(dir / "probes.bin");
  test::write_file(dir / "probes.bin", atlas.substr(0, atlas.size() - 16));
  test::write_file(dir / "normals.json", "[[0, 1, 0]]");
  const test::CommandResult r = test::run_command(
      {"node", (consumers / "probe_grid_three.mjs").string(), (dir / "probes.json").string(), (dir / "normals.json").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json out = nlohmann::json::parse(r.out);
  ASSERT_TRUE(out.contains("error")) << r.out;
  EXPECT_NE(out["error"].get<std::string>().find("the atlas holds 656 bytes"), std::string::npos) << out["error"];
}

// three's own shader reading the atlas on a GPU (SwiftShader's WebGL2 in headless
// Chromium): a white MeshLambertMaterial sphere of radius 1 at the origin, lit only by a
// loaded 4 x 4 x 4 grid over [-8, 8]^3, rendered into a float target, has exit radiance
// E(n) / pi at each pixel's normal n (read back from a second pass with
// MeshNormalMaterial), E being the irradiance of the coefficients three interpolates at its
// sample point P + n spacing / 2 = 3 n (P = n on the unit sphere, spacing 4). Two grids:
// every probe the same light (filtering returns it exactly; every pixel reads all seven
// slots), and coefficients affine in the probe position, c(p) = c + G p, which trilinear
// filtering reproduces exactly between probe centres (3 n stays inside [-6, 6]^3), so each
// pixel checks where three finds each probe. Tolerance 1e-3 absolute for pixels near 1:
// float rendering, the normal's round trip, the sphere's facets (|P - n| < 2e-4, times
// |G| = 0.02) and 8-bit filter weights (1/512 of a neighbour difference of 0.08) stay
// below it; a wrong slot, sign, axis or probe order moves pixels by 0.01 and more.
TEST(ThreeProbeGrid, ChromiumRendersALambertSphereWithEOverPi) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  if (test::run_command({"sh", "-c", "command -v chromium"}).exit_code != 0) {
    if (std::getenv("CI")) FAIL() << "chromium is not installed (Debian package chromium)";
    GTEST_SKIP() << "chromium is not installed (set CI to make this a failure)";
  }
  const fs::path consumers = test::node_consumers_dir();
  for (const fs::path& f : {fs::path(SHTOOL_SOURCE_DIR) / "web/shtool-three.js",
                            fs::path(SHTOOL_SOURCE_DIR) / "tests/consumer/node/probe_grid_page.html"})
    fs::copy_file(f, consumers / f.filename(), fs::copy_options::overwrite_existing);
  // Ambient 0.6 (E = 0.6 pi) plus directional lights: positive order-3 irradiance everywhere.
  std::array<double, 27> light{};
  std::vector<double> y(9);
  const std::array<double, 3> ambient = {0.6, 0.5, 0.7};
  for (int c = 0; c < 3; ++c) light[c] = ambient[c] * std::sqrt(4 * std::numbers::pi);
  const std::vector<std::pair<Eigen::Vector3d, std::array<double, 3>>> suns = {
      {Eigen::Vector3d(0.3, -0.5, 0.8).normalized(), {1.2, 0.9, 0.4}}, {Eigen::Vector3d(-1, 0.2, -0.1).normalized(), {0.2, 0.5, 0.9}}};
  for (const auto& sun : suns) {
    eval_sh<double>(3, sun.first, y);
    for (int i = 0; i < 9; ++i)
      for (int c = 0; c < 3; ++c) light[3 * i + c] += sun.second[c] * y[i];
  }
  // G: one gradient (shtool's frame) per coefficient and channel, |G| = 0.02.
  std::vector<Eigen::Vector3d> gradient(27);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> gauss;
  for (auto& v : gradient) v = 0.02 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
  for (const bool affine : {false, true}) {
    SCOPED_TRACE(affine ? "affine grid" : "uniform grid");
    auto coefficients_at = [&](const Eigen::Vector3d& p) {
      std::vector<double> c(light.begin(), light.end());
      if (affine)
        for (int k = 0; k < 27; ++k) c[k] += gradient[k].dot(p);
      return c;
    };
    ThreeProbeGridInput g;
    g.resolution = {4, 4, 4};
    g.min = Eigen::Vector3d(-8, -8, -8);
    g.max = Eigen::Vector3d(8, 8, 8);
    for (int iz = 0; iz < 4; ++iz)
      for (int iy = 0; iy < 4; ++iy)
        for (int ix = 0; ix < 4; ++ix) {
          const std::vector<double> c = coefficients_at(Eigen::Vector3d(-6 + 4 * ix, -6 + 4 * iy, -6 + 4 * iz));
          g.coefficients.insert(g.coefficients.end(), c.begin(), c.end());
        }
    const fs::path dir = scratch_dir(affine ? "browser_affine" : "browser_uniform");
    interop::write_three_probe_grid(dir, g);
    test::CommandOptions o;
    o.timeout_seconds = 300;
    const test::CommandResult r = test::run_command(
        {"node", (consumers / "probe_grid_browser.mjs").string(), "chromium", dir.string()}, o);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json out = nlohmann::json::parse(r.out);
    ASSERT_FALSE(out.contains("error")) << out["error"].get<std::string>();
    ASSERT_GT(out["pixels"].size(), 2000u);  // the sphere covers about 70% of 64 x 64
    double worst = 0;
    for (const nlohmann::json& px : out["pixels"]) {
      Eigen::Vector3d n3(px[0], px[1], px[2]);
      n3.normalize();
      const Eigen::Vector3d n = shtool_of_three(n3);
      std::vector<double> e = coefficients_at(3 * n);
      radiance_to_irradiance(3, e);
      eval_sh<double>(3, n, y);
      for (int c = 0; c < 3; ++c) {
        double want = 0;
        for (int i = 0; i < 9; ++i) want += e[3 * i + c] * y[i];
        want /= std::numbers::pi;
        const double got = px[3 + c];
        worst = std::max(worst, std::abs(got - want));
        ASSERT_NEAR(got, want, 1e-3) << "normal " << n3.transpose() << " channel " << c;
      }
    }
    std::printf("%s grid, %s: %zu pixels, worst |pixel - E/pi| %.3g\n", affine ? "affine" : "uniform",
                out["renderer"].get<std::string>().c_str(), out["pixels"].size(), worst);
  }
  // A grid whose atlas no WebGL holds (4096 probes along shtool's y: 28,686 slices, past
  // every GPU's MAX_3D_TEXTURE_SIZE, SwiftShader's 2048 included) is refused by the loader
  // given the renderer, instead of lighting the sphere with the zeros of a failed upload.
  ThreeProbeGridInput tall;
  tall.resolution = {1, 4096, 1};
  tall.min = Eigen::Vector3d(-8, -8, -8);
  tall.max = Eigen::Vector3d(8, 8, 8);
  for (int p = 0; p < 4096; ++p) tall.coefficients.insert(tall.coefficients.end(), light.begin(), light.end());
  const fs::path dir = scratch_dir("browser_tall");
  interop::write_three_probe_grid(dir, tall);
  test::CommandOptions o;
  o.timeout_seconds = 300;
  const test::CommandResult r =
      test::run_command({"node", (consumers / "probe_grid_browser.mjs").string(), "chromium", dir.string()}, o);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json out = nlohmann::json::parse(r.out);
  ASSERT_TRUE(out.contains("error")) << r.out.substr(0, 200);
  EXPECT_NE(out["error"].get<std::string>().find("MAX_3D_TEXTURE_SIZE"), std::string::npos) << out["error"];
  EXPECT_NE(out["error"].get<std::string>().find("1 x 1 x 28686"), std::string::npos) << out["error"];
}

}  // namespace
}  // namespace shtool
