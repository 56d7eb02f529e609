// render --shading wrinkle end to end, on the cylinder of scripts/make_wrinkled_cylinder.py
// ([4] Fig. 6ab's setup): it covers the mesh and shows the grooves, the flat groove
// renders as the unshadowed surface (the thin membrane with alpha 0, the clamped cosine
// lobe along the normal), the same bytes on 1 and 2 threads, bad requests refused by name
// with nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lighting/image_io.h"
#include "cli_test.h"

namespace {

using namespace shtool::test;

const Scratch scratch("render_wrinkle");

// Once per program: a small wrinkle map (order 4, 2 lobes, 6 x 6 nodes, depths 0..1),
// the cylinder (6 grooves, 48 columns: 8 vertices per groove) with its coordinates, the
// same coordinates with every depth 0, and a side light of order 4.
struct Inputs {
  fs::path map = scratch("wrinkles.shtb"), obj = scratch("cylinder.obj"), xd = scratch("cylinder.json");
  fs::path flat = scratch("flat.json"), light = scratch("light.json");
  std::size_t vertices = 0;
  nlohmann::json coords;
  Inputs() {
    must(run_shtool({"fit-wrinkles", "--order", "4", "--lobes", "2", "--grid", "6", "--samples", "1", "--rays", "1024",
                     "--max-evaluations", "200", "--out", map.string()}));
    must(run_command({SHTOOL_PYTHON, std::string(SHTOOL_SOURCE_DIR) + "/scripts/make_wrinkled_cylinder.py",
                      obj.string(), xd.string(), "--grooves", "6", "--rows", "12", "--cols", "48", "--depth", "0,1"}));
    coords = nlohmann::json::parse(read_file(xd));
    vertices = coords["x"].size();
    nlohmann::json f = coords;
    for (auto& d : f["d"]) d = 0.0;
    shtool::test::write_file(flat, f.dump());
    must(run_shtool({"light", "--type", "cone", "--dir", "1,1,0.3", "--half-angle", "30", "--color", "2,1.5,1",
                     "--order", "4", "--json", light.string()}));
  }
};

const Inputs& inputs() {
  static const Inputs s;
  return s;
}

const std::vector<std::string> kView = {"--width", "64", "--height", "64", "--camera", "4,0,0,0,0,0,0,0,1"};

std::vector<std::string> wrinkle_args(const fs::path& xd, const fs::path& out, int threads) {
  // The cylinder is written in shtool's frame, its axis z: --up z.
  std::vector<std::string> a = {"render", inputs().obj.string(), "--up", "z", "--shading", "wrinkle", "--wrinkle",
                                inputs().map.string(), "--wrinkle-map", xd.string(), "--light",
                                inputs().light.string(), "--threads", std::to_string(threads), "--out", out.string()};
  a.insert(a.end(), kView.begin(), kView.end());
  return a;
}

TEST(RenderWrinkle, CylinderCoversPixelsShowsGroovesAndIsThreadIndependent) {
  const fs::path one = scratch("one.exr"), two = scratch("two.exr");
  must(run_shtool(wrinkle_args(inputs().xd, one, 1)));
  must(run_shtool(wrinkle_args(inputs().xd, two, 2)));
  EXPECT_EQ(read_file(one), read_file(two));
  const fs::path png1 = scratch("one.png"), png2 = scratch("two.png");
  must(run_shtool(wrinkle_args(inputs().xd, png1, 1)));
  must(run_shtool(wrinkle_args(inputs().xd, png2, 2)));
  EXPECT_EQ(read_file(png1), read_file(png2));
  // The cylinder (diameter 1, length 2) seen from 4 away with a 40-degree view fills
  // about 0.35 x 0.7 of the frame: ~15 % of the pixels; 5 % catches a camera or mesh slip.
  const auto r = run_shtool(wrinkle_args(inputs().xd, one, 2));
  const std::size_t at = r.err.find("64 x 64, ");
  ASSERT_NE(at, std::string::npos) << r.err;
  const std::size_t covered = std::stoul(r.err.substr(at + 9));
  EXPECT_GT(covered, 64u * 64u / 20) << r.err;
  // The grooves: along a row of the deep top (d near 1) the radiance falls and rises
  // again across each groove; on the smooth cylinder (every d = 0) the same row, over
  // the pixels it lights, is one rise and fall at most.
  const fs::path flat_out = scratch("flat_row.exr");
  must(run_shtool(wrinkle_args(inputs().flat, flat_out, 1)));
  const auto image = read_image(one), flat = read_image(flat_out);
  const int row = 64 / 2 - 64 * 7 / 20;  // near the top of the cylinder: deep grooves
  auto turns = [&](const shtool::lighting::Image& im) {
    std::vector<double> v;
    for (int x = 0; x < im.width; ++x) {
      const std::size_t p = (std::size_t(row) * im.width + x) * 3;
      if (flat.texels[p] > 1e-3f) v.push_back(im.texels[p]);
    }
    int n = 0;
    for (std::size_t i = 2; i < v.size(); ++i) n += (v[i] - v[i - 1]) * (v[i - 1] - v[i - 2]) < 0;
    return std::pair<int, std::size_t>(n, v.size());
  };
  const auto [grooved, lit] = turns(image);
  EXPECT_GT(lit, 10u) << "the light must reach the row";
  EXPECT_GE(grooved, 4) << "grooves missing along row " << row;
  EXPECT_LE(turns(flat).first, 1) << "a smooth cylinder has at most one brightest line";
}

// d = 0 is an open plane: its transfer is the clamped cosine lobe A_l / pi along the normal,
// exactly what --shading membrane with alpha 0 shades. The map's flat row is a fit of a
// simulated plane (1024 rays): within 3 % of the lit radiance.
TEST(RenderWrinkle, FlatGrooveRendersAsTheUnshadowedSurface) {
  const fs::path wr = scratch("flat.exr"), mem = scratch("membrane.exr");
  must(run_shtool(wrinkle_args(inputs().flat, wr, 2)));
  std::vector<std::string> m = {"render", inputs().obj.string(), "--up", "z", "--shading", "membrane", "--alpha", "0",
                                "--light", inputs().light.string(), "--out", mem.string()};
  m.insert(m.end(), kView.begin(), kView.end());
  must(run_shtool(m));
  const auto a = read_image(wr), b = read_image(mem);
  ASSERT_EQ(a.texels.size(), b.texels.size());
  double peak = 0, worst = 0;
  for (std::size_t i = 0; i < a.texels.size(); ++i) peak = std::max(peak, double(b.texels[i]));
  for (std::size_t i = 0; i < a.texels.size(); ++i) worst = std::max(worst, std::abs(double(a.texels[i]) - b.texels[i]));
  EXPECT_GT(peak, 0.1);
  EXPECT_LT(worst, 0.03 * peak) << "peak " << peak;
}

TEST(RenderWrinkle, BadRequestsAreRefusedByName) {
  const Inputs& s = inputs();
  const std::size_t v = s.vertices;
  auto variant = [&](const std::string& name, const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json j = s.coords;
    change(j);
    const fs::path p = scratch(name);
    shtool::test::write_file(p, j.dump());
    return p.string();
  };
  const std::string short_x = variant("short.json", [](nlohmann::json& j) { j["x"].erase(j["x"].begin()); });
  const std::string deep = variant("deep.json", [](nlohmann::json& j) { j["d"][5] = 1.5; });
  // Just past the deepest depth: the message must show the digits that differ.
  const std::string barely = variant("barely.json", [](nlohmann::json& j) { j["d"][5] = 1.0000001; });
  const std::string negative = variant("negative.json", [](nlohmann::json& j) { j["d"][3] = -0.1; });
  const std::string text = variant("text.json", [](nlohmann::json& j) { j["x"][2] = "a"; });
  const std::string no_d = variant("no_d.json", [](nlohmann::json& j) { j.erase("d"); });
  const std::string constant = variant("constant.json", [](nlohmann::json& j) {
    for (auto& x : j["x"]) x = 0.25;
  });
  const fs::path zh_fit = scratch("not_a_map.shtb");
  shtool::test::write_file(zh_fit, read_file(s.map).substr(0, 100));
  const std::string obj = s.obj.string(), map = s.map.string(), xd = s.xd.string(), light = s.light.string();
  struct Bad {
    std::vector<std::string> args;
    std::string message;
  } bad[] = {
      {{obj, "--shading", "wrinkle", "--wrinkle-map", xd, "--light", light}, "--wrinkle"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--light", light}, "--wrinkle-map"},
      {{obj, "--shading", "membrane", "--wrinkle", map, "--wrinkle-map", xd, "--light", light},
       "--shading wrinkle only"},
      {{obj, "--shading", "wrinkle", "--wrinkle", zh_fit.string(), "--wrinkle-map", xd, "--light", light}, "--wrinkle"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", short_x, "--light", light},
       std::to_string(v) + " numbers each, one per mesh vertex; 'x' has " + std::to_string(v - 1)},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", no_d, "--light", light},
       "'d' is missing or not an array"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", deep, "--light", light},
       "d[5] = 1.5 is outside the map's depths [0, 1]"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", barely, "--light", light},
       "d[5] = 1.0000001 is outside the map's depths [0, 1]"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", negative, "--light", light}, "d[3]"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", text, "--light", light},
       "x[2] is not a number"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", constant, "--light", light},
       "x does not change across the surface at mesh vertex 0"},
      {{obj, "--shading", "wrinkle", "--wrinkle", map, "--wrinkle-map", xd}, "--light"},
  };
  for (const Bad& b : bad) expect_refused("render", b.args, b.message, scratch("bad.png"));
}

}  // namespace
