// shtool export-web: the folder's page, opened in headless Chromium (three.js on WebGL2,
// SwiftShader) and served alone on 127.0.0.1, draws what `shtool render` draws for the same
// mesh, fit, light, camera, size and exposure (mean difference at most 2/255 per channel
// over the pixels render covers), unrotated and with the light turned by the URL's
// quaternion against render under the light `shtool rotate` turned the same way; the page
// loads nothing from outside the folder; bad inputs are refused with nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <stb_image.h>

#include "cli_test.h"
#include "node_consumers.h"

namespace {

namespace fs = std::filesystem;
using namespace shtool::test;

const Scratch scratch("export_web");

// A fit of data/spot.obj (order 3, 2 lobes, shadowed) and the sky's light, once per program.
struct Bakes {
  fs::path fit = scratch("spot.shtb"), sky = scratch("sky.json"), white = scratch("white.json");
  Bakes() {
    must(run_shtool({"fit-zh", kSpotObj, "--order", "3", "--lobes", "2", "--rays", "64", "--mode", "shadowed", "--out",
                     fit.string()}));
    make_white_and_sky_lights(3, white, sky);
  }
};

const Bakes& bakes() {
  static const Bakes b;
  return b;
}

struct Rgba {
  int width = 0, height = 0;
  std::vector<unsigned char> pixels;
};

Rgba read_png(const fs::path& path) {
  const std::string bytes = read_file(path);
  Rgba image;
  int channels = 0;
  unsigned char* p = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                                           static_cast<int>(bytes.size()), &image.width, &image.height, &channels, 4);
  if (!p) {
    ADD_FAILURE() << path << ": not a PNG";
    return image;
  }
  image.pixels.assign(p, p + std::size_t(image.width) * image.height * 4);
  stbi_image_free(p);
  return image;
}

struct Difference {
  std::size_t covered = 0, uncovered_on_page = 0;
  double mean[3] = {0, 0, 0};
  int max = 0;
};

// Over the pixels the reference covers (alpha 255): the page's coverage there, and the mean
// and largest absolute difference per channel, in 8-bit steps.
Difference compare(const Rgba& page, const Rgba& reference) {
  Difference d;
  EXPECT_EQ(page.width, reference.width);
  EXPECT_EQ(page.height, reference.height);
  if (page.pixels.size() != reference.pixels.size()) return d;
  for (std::size_t p = 0; p < reference.pixels.size() / 4; ++p) {
    if (reference.pixels[p * 4 + 3] != 255) continue;
    ++d.covered;
    if (page.pixels[p * 4 + 3] != 255) ++d.uncovered_on_page;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int(page.pixels[p * 4 + c]) - int(reference.pixels[p * 4 + c]));
      d.mean[c] += diff;
      d.max = std::max(d.max, diff);
    }
  }
  for (double& m : d.mean) m /= std::max<std::size_t>(d.covered, 1);
  return d;
}

// The lighting JSON turned by a quaternion with `shtool rotate`, channel by channel.
fs::path rotated_light(const fs::path& light, const std::string& quat, const std::string& name) {
  nlohmann::json doc = nlohmann::json::parse(read_file(light));
  const int order = doc["order"].get<int>();
  for (int c = 0; c < 3; ++c) {
    std::string coeffs;
    for (const auto& row : doc["coefficients"]) coeffs += (coeffs.empty() ? "" : ",") + std::to_string(row[c].get<double>());
    const CommandResult r = run_shtool({"rotate", "--order", std::to_string(order), "--quat", quat, "--method",
                                        "reference", "--coeffs", coeffs});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json out = nlohmann::json::parse(r.out);
    for (std::size_t i = 0; i < doc["coefficients"].size(); ++i) doc["coefficients"][i][c] = out["coefficients"][i];
  }
  const fs::path path = scratch(name);
  write_file(path, doc.dump());
  return path;
}

// Chromium present, or the test ends: failed under CI (setup.sh installs it), skipped elsewhere.
#define REQUIRE_CHROMIUM()                                                                      \
  do {                                                                                          \
    if (run_command({"chromium", "--version"}).exit_code != 0) {                                \
      if (std::getenv("CI")) FAIL() << "chromium is not installed (scripts/setup.sh installs it)"; \
      GTEST_SKIP() << "chromium is not installed (set CI to make this a failure)";              \
    }                                                                                           \
  } while (false)

TEST(ExportWeb, PageDrawsWhatRenderDrawsUnrotatedAndRotated) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();  // three@0.187.0, which export-web copies
  REQUIRE_CHROMIUM();
  const fs::path dir = scratch("page"), views = scratch("views");
  fs::remove_all(dir);
  fs::remove_all(views);
  fs::create_directories(views);
  // Not square: the aspect ratio enters render's framing and the page's projection.
  const std::vector<std::string> view_options = {"--width", "160", "--height", "120", "--exposure", "0.5"};
  std::vector<std::string> args = {"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                                   bakes().sky.string(), "--out", dir.string()};
  args.insert(args.end(), view_options.begin(), view_options.end());
  must(run_shtool(args));
  for (const char* f : {"index.html", "scene.json", "mesh.glb", "shtool-three.js", "shtool-rotate.glsl",
                        "shtool-zh-shade.glsl", "three/build/three.module.js", "three/build/three.core.js"})
    EXPECT_TRUE(fs::is_regular_file(dir / f)) << f;

  // Two turns of the light: about an oblique axis, and half a turn about x.
  const std::vector<std::string> quats = {"0.8,0.2,-0.4,0.4", "0,1,0,0"};
  std::vector<fs::path> references;
  std::vector<std::string> queries = {""};
  for (std::size_t k = 0; k <= quats.size(); ++k) {
    const fs::path light = k == 0 ? bakes().sky : rotated_light(bakes().sky, quats[k - 1], "sky-" + std::to_string(k) + ".json");
    const fs::path png = scratch("render-" + std::to_string(k) + ".png");
    std::vector<std::string> render = {"render", kSpotObj, "--fit", bakes().fit.string(), "--light", light.string(),
                                       "--out", png.string()};
    render.insert(render.end(), view_options.begin(), view_options.end());
    must(run_shtool(render));
    references.push_back(png);
    if (k > 0) queries.push_back("light-rotation=" + quats[k - 1]);
  }

  std::vector<std::string> node = {"node", (node_consumers_dir() / "export_web_browser.mjs").string(), "chromium",
                                   dir.string(), views.string()};
  node.insert(node.end(), queries.begin(), queries.end());
  const CommandResult r = run_checked(node);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json result = nlohmann::json::parse(r.out);
  ASSERT_FALSE(result.contains("error")) << result.dump(1);
  EXPECT_TRUE(result["outside"].empty()) << "requests outside the folder: " << result["outside"].dump();
  EXPECT_TRUE(result["missing"].empty()) << "requests for files the folder lacks: " << result["missing"].dump();
  EXPECT_GT(result["requests"].size(), 5u);
  ASSERT_EQ(result["views"].size(), references.size()) << result.dump(1);

  const Rgba unrotated = read_png(references[0]);
  for (std::size_t k = 0; k < references.size(); ++k) {
    const Rgba page = read_png(result["views"][k].get<std::string>());
    const Rgba reference = read_png(references[k]);
    const Difference d = compare(page, reference);
    std::cout << "view " << k << " (" << (k ? queries[k] : "unrotated") << "): " << d.covered
              << " pixels covered by render, " << d.uncovered_on_page << " of them not by the page; mean |page - render| "
              << d.mean[0] << ", " << d.mean[1] << ", " << d.mean[2] << " (R, G, B, of 255), max " << d.max << "\n";
    ASSERT_GT(d.covered, 2000u);
    EXPECT_LE(d.uncovered_on_page, d.covered / 100) << "view " << k;
    for (int c = 0; c < 3; ++c) EXPECT_LE(d.mean[c], 2.0) << "view " << k << ", channel " << c;
    if (k > 0) {  // the turn shows: a page that ignored it would fail the bound above
      const Difference turned = compare(reference, unrotated);
      EXPECT_GT(std::max({turned.mean[0], turned.mean[1], turned.mean[2]}), 6.0) << "view " << k;
    }
  }
}

TEST(ExportWeb, RefusesBadInputsAndWritesNothing) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();  // with three.js present, only the input is at fault
  const fs::path tetra = scratch("tetra.obj"), tetra_fit = scratch("tetra.shtb"), light9 = scratch("light9.json");
  write_file(tetra, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  must(run_shtool({"fit-zh", tetra.string(), "--order", "3", "--lobes", "1", "--rays", "16", "--mode", "unshadowed",
                   "--out", tetra_fit.string()}));
  must(run_shtool({"light", "--type", "constant", "--color", "1,1,1", "--order", "9", "--json", light9.string()}));
  const fs::path dir = scratch("refused");
  expect_all_refused("export-web", {kSpotObj},
                     {{{"--fit", tetra_fit.string(), "--light", bakes().sky.string()}, "--fit"},
                      {{"--fit", bakes().fit.string(), "--light", light9.string()}, "order 9"},
                      {{"--fit", bakes().sky.string(), "--light", bakes().sky.string()}, "--fit"}},
                     dir);
  // An existing folder is left as it was.
  fs::create_directories(dir);
  const CommandResult r = run_shtool({"export-web", kSpotObj, "--fit", tetra_fit.string(), "--light",
                                      bakes().sky.string(), "--out", dir.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(fs::is_empty(dir));
  // A folder that cannot be made: its parent is a file.
  const fs::path blocker = scratch("blocker");
  write_file(blocker, "x");
  expect_refused("export-web", {kSpotObj, "--fit", bakes().fit.string(), "--light", bakes().sky.string()},
                 "is not a folder", blocker / "page");
}

}  // namespace
