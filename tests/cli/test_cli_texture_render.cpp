// fit-zh --texture and render end to end: the maps sit beside the table, render finds
// them from the table's meta (its header valid against the schema), the white furnace is 1 on every covered pixel, the texture
// render matches the vertex render of the same bake settings, the bytes do not depend on
// the thread count, and bad requests are refused by name with nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "lighting/image_io.h"
#include "cli_test.h"

namespace {

using namespace shtool::test;

const Scratch scratch("texture_render");

shtool::lighting::ChannelImage read_rgba(const fs::path& p) {
  return shtool::lighting::decode_exr_channels(read_file(p), p);  // A, B, G, R
}

// Order 3, 2 lobes, shadowed, on spot: per texel of a 64 x 64 atlas and per vertex.
struct Bakes {
  fs::path texture = scratch("spot.tex.shtb"), vertex = scratch("spot.vtx.shtb");
  fs::path furnace = scratch("spot.furnace.shtb");
  fs::path white = scratch("white.json"), sky = scratch("sky.json");
  Bakes() {
    const std::vector<std::string> common = {"--order", "3", "--lobes", "2", "--rays", "64"};
    auto bake = [&](std::vector<std::string> args) {
      args.insert(args.begin(), {"fit-zh", kSpotObj});
      args.insert(args.end(), common.begin(), common.end());
      must(run_shtool(args));
    };
    bake({"--texture", "64", "--out", texture.string()});
    bake({"--out", vertex.string()});
    bake({"--texture", "64", "--mode", "unshadowed", "--direct", "--out", furnace.string()});
    make_white_and_sky_lights(3, white, sky);
  }
};

const Bakes& bakes() {
  static const Bakes b;
  return b;
}

TEST(TextureRender, MapsAreWrittenBesideTheTable) {
  (void)bakes();
  EXPECT_TRUE(fs::exists(scratch("spot.tex.dc_linear.exr")));
  EXPECT_TRUE(fs::exists(scratch("spot.tex.lobes.exr")));
  EXPECT_FALSE(fs::exists(scratch("spot.vtx.dc_linear.exr")));  // a vertex bake writes none
  expect_valid_against_schema("zh-fit.schema.json", {bakes().texture});
}

TEST(TextureRender, WhiteFurnaceIsOneOnEveryCoveredPixel) {
  const fs::path out = scratch("furnace.exr");
  must(run_shtool({"render", kSpotObj, "--fit", bakes().furnace.string(), "--light", bakes().white.string(), "--width",
                   "96", "--height", "80", "--out", out.string()}));
  const auto image = read_rgba(out);
  std::size_t covered = 0;
  double worst = 0;
  for (std::size_t p = 0; p < image.texels.size() / 4; ++p) {
    const float* px = &image.texels[p * 4];
    if (px[0] != 1.0f) continue;
    ++covered;
    for (int c = 1; c < 4; ++c) worst = std::max(worst, std::abs(px[c] - 1.0));
  }
  EXPECT_GT(covered, 1000u);
  // Unshadowed DC is exact per texel and stored directly; float maps round it.
  EXPECT_LT(worst, 1e-5);
  std::printf("white furnace: %zu covered pixels, worst |radiance - 1| %.3g\n", covered, worst);
}

TEST(TextureRender, MatchesTheVertexRender) {
  const fs::path tex = scratch("tex.exr"), vtx = scratch("vtx.exr");
  for (const auto& [fit, out] : {std::pair{bakes().texture, tex}, std::pair{bakes().vertex, vtx}})
    must(run_shtool({"render", kSpotObj, "--fit", fit.string(), "--light", bakes().sky.string(), "--width", "96",
                     "--height", "80", "--out", out.string()}));
  const auto a = read_rgba(tex), b = read_rgba(vtx);
  ASSERT_EQ(a.texels.size(), b.texels.size());
  std::size_t covered = 0;
  double diff = 0, level = 0;
  for (std::size_t p = 0; p < a.texels.size() / 4; ++p) {
    ASSERT_EQ(a.texels[p * 4], b.texels[p * 4]) << p;  // the same pixels are covered
    if (a.texels[p * 4] != 1.0f) continue;
    ++covered;
    for (int c = 1; c < 4; ++c) {
      diff += std::abs(a.texels[p * 4 + c] - b.texels[p * 4 + c]);
      level += std::abs(b.texels[p * 4 + c]);
    }
  }
  EXPECT_GT(covered, 1000u);
  // Texels and vertices sample the shadowing at different points (64 rays each) and
  // the lobes are point-sampled: a few percent apart on average.
  EXPECT_LT(diff / level, 0.06);
  std::printf("texture vs vertex render: mean |difference| / mean level %.4f over %zu pixels\n", diff / level, covered);
}

TEST(TextureRender, SameBytesOnAnyThreadCount) {
  std::string first;
  for (const char* threads : {"1", "2"}) {
    const fs::path out = scratch(std::string("threads") + threads + ".exr");
    must(run_shtool({"render", kSpotObj, "--fit", bakes().texture.string(), "--light", bakes().sky.string(), "--width",
                     "64", "--height", "48", "--threads", threads, "--out", out.string()}));
    if (first.empty()) first = read_file(out);
    else EXPECT_TRUE(first == read_file(out));
  }
}

TEST(TextureRender, BadRequestsAreRefusedByName) {
  const fs::path out = scratch("bad.exr");
  auto refused = [&](std::vector<std::string> args, const std::string& words) {
    const auto r = run_shtool(args);
    EXPECT_NE(r.exit_code, 0) << words;
    EXPECT_NE(r.err.find(words), std::string::npos) << words << ": " << r.err;
    EXPECT_FALSE(fs::exists(out));
  };
  // Lobes posed per vertex have no meaning for texels.
  refused({"render", kSpotObj, "--fit", bakes().texture.string(), "--pose", kSpotObj, "--light", bakes().sky.string(),
           "--out", out.string()},
          "is a texture-space bake");
  // Nor does deform carry a texel bake onto a pose.
  refused({"deform", bakes().texture.string(), "--rest", kSpotObj, "--pose", kSpotObj, "--out", out.string()},
          "texture-space bake");
  // The same mesh without texture coordinates cannot be sampled: spot with its vt lines
  // and face texcoord indices taken out.
  const fs::path bare = scratch("bare.obj");
  {
    std::istringstream in(read_file(kSpotObj));
    std::string line, kept;
    while (std::getline(in, line)) {
      if (line.rfind("vt ", 0) == 0) continue;
      if (line.rfind("f ", 0) == 0) {
        std::istringstream corners(line.substr(2));
        std::string corner;
        line = "f";
        while (corners >> corner) line += " " + corner.substr(0, corner.find('/'));
      }
      kept += line + "\n";
    }
    shtool::test::write_file(bare, kept);
  }
  refused({"render", bare.string(), "--fit", bakes().texture.string(), "--light", bakes().sky.string(), "--out",
           out.string()},
          "no texture coordinates");
  // Another UV layout: the maps would be sampled at the wrong texels.
  std::string text = read_file(kSpotObj);
  const std::size_t vt = text.find("\nvt ");
  ASSERT_NE(vt, std::string::npos);
  text.replace(vt + 1, text.find('\n', vt + 1) - (vt + 1), "vt 0.5 0.5");  // the first texcoord moved
  const fs::path moved = scratch("moved_uv.obj");
  shtool::test::write_file(moved, text);
  refused({"render", moved.string(), "--fit", bakes().texture.string(), "--light", bakes().sky.string(), "--out",
           out.string()},
          "UV layout");
  // A map gone: named.
  fs::create_directories(scratch("lonely"));
  const fs::path lonely = scratch("lonely") / "spot.tex.shtb";
  fs::copy_file(bakes().texture, lonely, fs::copy_options::overwrite_existing);
  refused({"render", kSpotObj, "--fit", lonely.string(), "--light", bakes().sky.string(), "--out", out.string()},
          "spot.tex.dc_linear.exr");
  // A map with a NaN, or without a channel the table needs: named.
  fs::create_directories(scratch("broken"));
  const fs::path broken = scratch("broken") / "spot.tex.shtb";
  fs::copy_file(bakes().texture, broken, fs::copy_options::overwrite_existing);
  const fs::path lobes_map = bakes().texture.parent_path() / "spot.tex.lobes.exr";
  fs::copy_file(lobes_map, scratch("broken") / "spot.tex.lobes.exr", fs::copy_options::overwrite_existing);
  const fs::path dc_map = bakes().texture.parent_path() / "spot.tex.dc_linear.exr";
  shtool::lighting::ChannelImage dc =
      shtool::lighting::decode_exr_channels(read_file(dc_map), dc_map);
  dc.texels[5] = NAN;
  shtool::test::write_file(scratch("broken") / "spot.tex.dc_linear.exr",
                           shtool::lighting::encode_exr_channels(dc, shtool::NonFinite::keep));
  refused({"render", kSpotObj, "--fit", broken.string(), "--light", bakes().sky.string(), "--out", out.string()},
          "is not finite");
  dc = shtool::lighting::decode_exr_channels(read_file(dc_map), dc_map);
  dc.names.back() = "sh9";  // one channel renamed
  shtool::test::write_file(scratch("broken") / "spot.tex.dc_linear.exr", shtool::lighting::encode_exr_channels(dc));
  refused({"render", kSpotObj, "--fit", broken.string(), "--light", bakes().sky.string(), "--out", out.string()},
          "no channel");
  refused({"fit-zh", kSpotObj, "--texture", "0", "--out", scratch("x.shtb").string()}, "--texture 0");
  EXPECT_FALSE(fs::exists(scratch("x.shtb")));
  refused({"fit-zh", bare.string(), "--texture", "16", "--out", scratch("x.shtb").string()},
          "bare.obj: no texture coordinates");
  EXPECT_FALSE(fs::exists(scratch("x.shtb")));
}

}  // namespace
