// export-light --format l1 | zh3: the files' layout, their numbers against the runtime's
// encoders (shtool/probe_encoding.h), the frame option, the intensity, and bad requests.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "lighting/lighting_output.h"
#include "shtool/irradiance.h"
#include "shtool/probe_encoding.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

using namespace test;
using lighting::Lighting;
using lighting::Quantity;

const Scratch scratch("probe_encoding_cli");

// A light mostly positive, unequal in its channels.
Lighting light_of_order(int order, unsigned seed) { return random_radiance(order, seed, 0.3, {3, 2, 1}); }

nlohmann::json export_file(const Lighting& l, const std::vector<std::string>& extra, std::string* err = nullptr) {
  const fs::path in = scratch("light.json"), out = scratch("probe.json");
  std::ofstream(in) << lighting::lighting_json(l);
  std::vector<std::string> args = {"export-light", in.string(), "--out", out.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_shtool(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (err) *err = r.err;
  return nlohmann::json::parse(read_file(out));
}

TEST(ExportProbeEncoding, L1HoldsBands0And1InShtoolsBasis) {
  const Lighting l = light_of_order(4, 1);
  std::string err;
  const nlohmann::json j = export_file(l, {"--format", "l1"}, &err);
  EXPECT_EQ(j["encoding"], "l1");
  EXPECT_EQ(j["quantity"], "radiance");
  EXPECT_EQ(j["frame"], "x,y,z");
  ASSERT_EQ(j["coefficients"].size(), 4u);
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(j["coefficients"][i][c].get<double>(), l.coefficients[3 * i + c]) << i;
  EXPECT_NE(err.find("dropped"), std::string::npos) << err;  // band 3 (and 2, not stored) noted
}

TEST(ExportProbeEncoding, Zh3HoldsL1AndTheZonalCoefficientsOfBothFits) {
  const Lighting l = light_of_order(3, 2);
  for (const char* axis : {"luminance", "per-channel"}) {
    const Zh3Axis mode = std::string(axis) == "luminance" ? Zh3Axis::luminance : Zh3Axis::per_channel;
    const nlohmann::json j = export_file(l, {"--format", "zh3", "--axis", axis});
    EXPECT_EQ(j["encoding"], "zh3");
    EXPECT_EQ(j["axis"], axis);
    EXPECT_EQ(j.contains("luminance_weights"), mode == Zh3Axis::luminance);
    const Zh3Probe<double> fit = encode_zh3<double>(l.coefficients, mode, Zh3Fit::explicit_fit);
    const Zh3Probe<double> guess = encode_zh3<double>(l.coefficients, mode, Zh3Fit::hallucinated);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(j["zonal"][c].get<double>(), fit.zonal[c]) << axis;
      EXPECT_EQ(j["zonal_hallucinated"][c].get<double>(), guess.zonal[c]) << axis;
      const Vec3<double> a = zh3_axis(fit.l1, mode, c);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(j["axes"][c][k].get<double>(), a[k]);
    }
    // The zonal coefficient is not 0 (a random band 2): a file of zeros would pass the
    // comparison only if the encoder also returned zeros.
    EXPECT_GT(std::abs(j["zonal"][0].get<double>()), 1e-3);
  }
}

TEST(ExportProbeEncoding, TheDefaultAxisIsLuminance) {
  const nlohmann::json j = export_file(light_of_order(3, 3), {"--format", "zh3"});
  EXPECT_EQ(j["axis"], "luminance");
  EXPECT_EQ(j["luminance_weights"], nlohmann::json({0.2126, 0.7152, 0.0722}));
}

TEST(ExportProbeEncoding, FrameAndIntensityCarryTheLight) {
  // In the y-up frame x,z,-y the file's probe evaluated at the engine's normal Q n equals
  // the shtool probe at n; the intensity scales every number.
  const Lighting l = light_of_order(3, 4);
  const nlohmann::json j = export_file(l, {"--format", "zh3", "--frame", "x,z,-y", "--intensity", "2"});
  EXPECT_EQ(j["frame"], "x,z,-y");
  Zh3Probe<double> file;
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) file.l1.coefficients[3 * i + c] = j["coefficients"][i][c];
  for (int c = 0; c < 3; ++c) file.zonal[c] = j["zonal"][c];
  const Zh3Probe<double> here = encode_zh3<double>(l.coefficients, Zh3Axis::luminance, Zh3Fit::explicit_fit);
  for (const Vec3<double>& n : {Vec3<double>(0.6, 0, 0.8), Vec3<double>(0, -1, 0), Vec3<double>(0.48, 0.6, 0.64)}) {
    const Vec3<double> engine_n(n.x(), n.z(), -n.y());
    const Vec3<double> a = zh3_irradiance(file, Zh3Axis::luminance, engine_n), b = zh3_irradiance(here, Zh3Axis::luminance, n);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], 2 * b[c], 1e-12) << n.transpose();
  }
}

TEST(ExportProbeEncoding, IrradianceInputIsConvertedToRadiance) {
  Lighting l = light_of_order(3, 5);
  const nlohmann::json radiance = export_file(l, {"--format", "zh3"});
  for (int i = 0; i < 9; ++i)
    for (int c = 0; c < 3; ++c) l.coefficients[3 * i + c] *= clamped_cosine_band(sh_band(i));
  l.quantity = Quantity::irradiance;
  const nlohmann::json irradiance = export_file(l, {"--format", "zh3"});
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(irradiance["zonal"][c].get<double>(), radiance["zonal"][c].get<double>(), 1e-14);
}

TEST(ExportProbeEncoding, BadRequests) {
  const fs::path in = scratch("bad_light.json");
  std::ofstream(in) << lighting::lighting_json(light_of_order(3, 6));
  const fs::path out = scratch("bad_out.json");
  expect_refused("export-light", {in.string(), "--format", "l1", "--axis", "luminance"}, "--axis applies to --format zh3 only", out);
  expect_refused("export-light", {in.string(), "--format", "zh3", "--axis", "red"}, "--axis", out);
  expect_refused("export-light", {in.string(), "--format", "zh4"}, "--format", out);
  // Nothing to import: an encoding keeps less than the light.
  expect_refused("import-light", {in.string(), "--format", "zh3"}, "--format", out, "--json");
}

}  // namespace
}  // namespace shtool
