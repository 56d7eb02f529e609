// shtool export-web: the folder's page, opened in headless Chromium (three.js on WebGL2,
// SwiftShader) and served alone on 127.0.0.1, draws what `shtool render` draws for the same
// mesh, fit, light, camera, size and exposure (mean difference at most 2/255 per channel
// over the pixels render covers), unrotated and with the light turned by the URL's
// quaternion against render under the light `shtool rotate` turned the same way; the page
// loads nothing from outside the folder; dragging turns the light (to the rotation its
// status line names), a finger's drag (pointer events of type touch) as the mouse's; the
// light rotated once per frame and colour channel (one gl.POINTS draw of 3 points a frame)
// draws the same pixels as the light rotated per vertex (?rotate-light=per-vertex, the
// page's fallback) and as the pass split over more points when WebGL passes fewer varyings,
// at order 3 and at order 8; bad inputs are refused with nothing written.
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
  int max_both = 0;  // over the pixels both cover
  std::size_t over_8 = 0;  // pixels both cover with a channel more than 8 apart
  int max_x = 0, max_y = 0;
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
    bool far = false;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int(page.pixels[p * 4 + c]) - int(reference.pixels[p * 4 + c]));
      d.mean[c] += diff;
      if (page.pixels[p * 4 + 3] != 255) continue;
      far = far || diff > 8;
      if (diff > d.max_both) {
        d.max_both = diff;
        d.max_x = int(p % reference.width);
        d.max_y = int(p / reference.width);
      }
    }
    d.over_8 += far;
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

// The pages the browser opens and the renders it is compared with, once per program: the
// sky unrotated and turned two ways, a bent pose, the probe-lit scene and order 8.
// Not square: the aspect ratio enters render's framing and the page's projection.
const std::vector<std::string> kViewOptions = {"--width", "160", "--height", "120", "--exposure", "0.5"};

std::vector<std::string> with_view(std::vector<std::string> args) {
  args.insert(args.end(), kViewOptions.begin(), kViewOptions.end());
  return args;
}

// Two turns of the light: about an oblique axis, and half a turn about x.
const std::vector<std::string> kQuats = {"0.8,0.2,-0.4,0.4", "0,1,0,0"};

struct Pages {
  fs::path sky_dir = scratch("page"), pose_dir = scratch("pose"), probe_dir = scratch("probes"),
           order8_dir = scratch("page8"), bent = scratch("bent.obj"), probes = scratch("probes.shtb"),
           fit8 = scratch("spot8.shtb"), sky8 = scratch("sky8.json"), white8 = scratch("white8.json"),
           posed_png = scratch("render-pose.png");
  std::vector<fs::path> turned_renders;  // under the sky unrotated, then turned by kQuats

  Pages() {
    for (const fs::path& d : {sky_dir, pose_dir, probe_dir, order8_dir}) fs::remove_all(d);
    must(run_shtool(with_view({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                               bakes().sky.string(), "--out", sky_dir.string()})));
    must(run_checked({SHTOOL_PYTHON, kSourceDir + "/scripts/pose_mesh.py", kSpotObj, bent.string(), "--bend", "0.8"}));
    must(run_shtool(with_view({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--pose", bent.string(),
                               "--light", bakes().sky.string(), "--out", pose_dir.string()})));
    must(run_shtool({"bake-probes", kSpotObj, "--grid", "4,4,3", "--env", bakes().sky.string(), "--samples", "64",
                     "--bounces", "1", "--out", probes.string()}));
    must(run_shtool(with_view({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                               bakes().sky.string(), "--probes", probes.string(), "--out", probe_dir.string()})));
    // Order 8, the largest: 16 texels per channel, one point of 16 varying vectors
    // (SwiftShader has 31), or two where WebGL2 passes only its guaranteed 15.
    must(run_shtool({"fit-zh", kSpotObj, "--order", "8", "--lobes", "2", "--rays", "64", "--mode", "shadowed", "--out",
                     fit8.string()}));
    make_white_and_sky_lights(8, white8, sky8);
    must(run_shtool(with_view({"export-web", kSpotObj, "--fit", fit8.string(), "--light", sky8.string(), "--out",
                               order8_dir.string()})));
    for (std::size_t k = 0; k <= kQuats.size(); ++k) {
      const fs::path light =
          k == 0 ? bakes().sky : rotated_light(bakes().sky, kQuats[k - 1], "sky-" + std::to_string(k) + ".json");
      turned_renders.push_back(scratch("render-" + std::to_string(k) + ".png"));
      must(run_shtool(with_view({"render", kSpotObj, "--fit", bakes().fit.string(), "--light", light.string(),
                                 "--out", turned_renders.back().string()})));
    }
    must(run_shtool(with_view({"render", kSpotObj, "--fit", bakes().fit.string(), "--pose", bent.string(), "--light",
                               bakes().sky.string(), "--out", posed_png.string()})));
  }
};

const Pages& pages() {
  static const Pages p;
  return p;
}

// Every page folder holds the page, its scene, mesh, shaders and three.js; the probe-lit one
// its grid; the renders the browser is compared with are pictures of the size asked. This
// case runs every shtool process of the comparison below, so the instrumented tree, which
// leaves the browser's part (three.js's shaders on SwiftShader) to the Release tree, still
// runs them under its sanitizers.
TEST(ExportWeb, WritesEveryPageAndTheRendersItIsComparedWith) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();  // three@0.187.0, which export-web copies
  const Pages& p = pages();
  for (const fs::path& dir : {p.sky_dir, p.pose_dir, p.probe_dir, p.order8_dir}) {
    for (const char* f : {"index.html", "scene.json", "mesh.glb", "shtool-three.js", "shtool-rotate.glsl",
                          "shtool-zh-shade.glsl", "three/build/three.module.js", "three/build/three.core.js"})
      EXPECT_TRUE(fs::is_regular_file(dir / f)) << dir / f;
  }
  EXPECT_TRUE(fs::is_regular_file(p.probe_dir / "probes/probes.bin"));
  EXPECT_FALSE(fs::exists(p.sky_dir / "probes"));
  EXPECT_EQ(read_json(p.order8_dir / "scene.json")["order"], 8);
  EXPECT_EQ(read_json(p.sky_dir / "scene.json")["order"], 3);
  std::vector<fs::path> renders = p.turned_renders;
  renders.push_back(p.posed_png);
  for (const fs::path& png : renders) {
    const Rgba image = read_png(png);
    EXPECT_EQ(image.width, 160) << png;
    EXPECT_EQ(image.height, 120) << png;
  }
}

// One Chromium for every view of the pages above.
TEST(ExportWeb, PageDrawsWhatRenderDraws) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();  // three@0.187.0, which export-web copies
  REQUIRE_CHROMIUM();
  const Pages& p = pages();
  const fs::path &sky_dir = p.sky_dir, &pose_dir = p.pose_dir, &probe_dir = p.probe_dir, &order8_dir = p.order8_dir,
                 &sky8 = p.sky8, &fit8 = p.fit8;
  const fs::path views = scratch("views");
  fs::remove_all(views);
  fs::create_directories(views);
  const std::vector<std::string>& quats = kQuats;
  std::vector<fs::path> references = p.turned_renders;
  std::vector<std::string> specs, labels;
  for (std::size_t k = 0; k <= quats.size(); ++k) {
    specs.push_back(sky_dir.string() + (k ? "?light-rotation=" + quats[k - 1] : ""));
    labels.push_back(k ? "light-rotation=" + quats[k - 1] : "unrotated");
  }
  references.push_back(p.posed_png);
  specs.push_back(pose_dir.string());
  labels.push_back("--pose, bent");
  const std::size_t probe_view = specs.size(), drag_view = probe_view + 1, touch_view = probe_view + 2,
                    vertex_view = probe_view + 3, fallback_view = probe_view + 4, split_view = probe_view + 5,
                    order8_view = probe_view + 6, order8_vertex_view = probe_view + 7,
                    order8_split_view = probe_view + 8, broken_view = probe_view + 9;
  specs.push_back(probe_dir.string());  // compared with the unrotated render below
  specs.push_back(sky_dir.string() + "#drag=80,-50");  // compared with render at the rotation the page shows
  specs.push_back(sky_dir.string() + "#touch-drag=80,-50");  // the same drag by a finger
  // The per-vertex path, asked for and as the fallback of a WebGL without float render
  // targets, compared with the per-frame page of the same rotation (view 1).
  specs.push_back(sky_dir.string() + "?light-rotation=" + quats[0] + "&rotate-light=per-vertex");
  specs.push_back(sky_dir.string() + "?light-rotation=" + quats[0] + "#no-float-targets");
  // Order 3 needs 3 texels per channel; with 2 varying vectors the pass takes 2 points per
  // channel, each rotating once and writing its share. Compared with view 1 as well.
  specs.push_back(sky_dir.string() + "?light-rotation=" + quats[0] + "#max-varying-vectors=2");
  // Order 8: per frame (against render), per vertex, and split by WebGL2's minimum of 15.
  specs.push_back(order8_dir.string() + "?light-rotation=" + quats[0]);
  specs.push_back(order8_dir.string() + "?light-rotation=" + quats[0] + "&rotate-light=per-vertex");
  specs.push_back(order8_dir.string() + "?light-rotation=" + quats[0] + "#max-varying-vectors=15");
  // The pass broken on purpose (each texel written with its neighbour's coefficients): the
  // checks above must see it.
  specs.push_back(sky_dir.string() + "?light-rotation=" + quats[0] + "#shifted-texels");

  std::vector<std::string> node = {"node", (node_consumers_dir() / "export_web_browser.mjs").string(), "chromium",
                                   views.string()};
  node.insert(node.end(), specs.begin(), specs.end());
  const CommandResult r = run_checked(node);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json result = nlohmann::json::parse(r.out);
  ASSERT_FALSE(result.contains("error")) << result.dump(1);
  EXPECT_TRUE(result["outside"].empty()) << "requests outside the folder: " << result["outside"].dump();
  EXPECT_TRUE(result["missing"].empty()) << "requests for files the folder lacks: " << result["missing"].dump();
  EXPECT_NE(result["requests"].dump().find("/probes/probes.bin"), std::string::npos) << result["requests"].dump();
  ASSERT_EQ(result["views"].size(), specs.size()) << result.dump(1);

  // SwiftShader renders to float textures, so every view but the two per-vertex ones takes
  // the per-frame pass; the status line says which path drew, and why. The pass is one
  // gl.POINTS draw a frame, a point per colour channel (two with 2 varying vectors), and the
  // rotation runs in the points' vertex shader: 3 rotations a frame (6 split). The
  // per-vertex paths draw no points.
  for (std::size_t k = 0; k < specs.size(); ++k) {
    const bool per_vertex = k == vertex_view || k == fallback_view || k == order8_vertex_view;
    const char* path =
        k == vertex_view || k == order8_vertex_view ? "(light rotated per vertex (rotate-light=per-vertex))"
        : k == fallback_view ? "(light rotated per vertex: this WebGL cannot render to float textures"
        : k == split_view    ? "(light rotated once per frame: 2 rotations per colour channel, this WebGL passing 2 of "
                               "the 3 texels per point (MAX_VARYING_VECTORS 2"
        : k == order8_split_view
            ? "(light rotated once per frame: 2 rotations per colour channel, this WebGL passing 15 of the 16 texels "
              "per point (MAX_VARYING_VECTORS 15"
            : "(light rotated once per frame: one rotation per colour channel)";
    EXPECT_NE(result["status"][k].get<std::string>().find(path), std::string::npos)
        << specs[k] << ": " << result["status"][k];
    const nlohmann::json& points = result["points"][k];
    if (per_vertex) {
      EXPECT_TRUE(points.empty()) << specs[k] << ": " << points;
      continue;
    }
    EXPECT_FALSE(points.empty()) << specs[k];
    const int per_frame_points = k == split_view || k == order8_split_view ? 6 : 3;
    for (const auto& count : points) EXPECT_EQ(count.get<int>(), per_frame_points) << specs[k] << ": " << points;
  }

  const Rgba unrotated = read_png(references[0]);
  for (std::size_t k = 0; k < references.size(); ++k) {
    const Rgba page = read_png(result["views"][k].get<std::string>());
    const Rgba reference = read_png(references[k]);
    const Difference d = compare(page, reference);
    std::cout << labels[k] << ": " << d.covered << " pixels covered by render, " << d.uncovered_on_page
              << " of them not by the page; mean |page - render| " << d.mean[0] << ", " << d.mean[1] << ", "
              << d.mean[2] << " (R, G, B, of 255); max " << d.max_both << " where both cover, at (" << d.max_x << ", "
              << d.max_y << "); " << d.over_8 << " pixels more than 8 apart\n";
    ASSERT_GT(d.covered, 2000u);
    EXPECT_LE(d.uncovered_on_page, d.covered / 100) << labels[k];
    for (int c = 0; c < 3; ++c) EXPECT_LE(d.mean[c], 2.0) << labels[k] << ", channel " << c;
    if (k > 0) {  // the turn (or the pose) shows: a page that ignored it would fail the bound above
      const Difference turned = compare(reference, unrotated);
      std::cout << "  render against render unrotated: mean " << turned.mean[0] << ", " << turned.mean[1] << ", "
                << turned.mean[2] << "\n";
      EXPECT_GT(std::max({turned.mean[0], turned.mean[1], turned.mean[2]}), 6.0) << labels[k];
    }
  }
  // The probe-lit scene: the ground and spheres cover pixels render's mesh does not.
  const Rgba probe_page = read_png(result["views"][probe_view].get<std::string>());
  std::size_t opaque = 0;
  for (std::size_t p = 0; p < probe_page.pixels.size() / 4; ++p) opaque += probe_page.pixels[p * 4 + 3] == 255;
  std::cout << "probe-lit scene: " << opaque << " opaque pixels\n";
  EXPECT_GT(opaque, compare(unrotated, unrotated).covered + 1000);

  // Dragging turned the light: the status line names the rotation drawn, and render under
  // the light turned by it is the same picture.
  const std::string status = result["status"][drag_view].get<std::string>();
  const std::string prefix = "light-rotation=";
  ASSERT_EQ(status.rfind(prefix, 0), 0u) << status;
  const std::string dragged_quat = status.substr(prefix.size(), status.find(' ') - prefix.size());
  EXPECT_NE(dragged_quat, "1.000000,0.000000,0.000000,0.000000");
  const fs::path dragged_png = scratch("render-dragged.png");
  must(run_shtool(with_view({"render", kSpotObj, "--fit", bakes().fit.string(), "--light",
                             rotated_light(bakes().sky, dragged_quat, "sky-dragged.json").string(), "--out",
                             dragged_png.string()})));
  const Difference dragged = compare(read_png(result["views"][drag_view].get<std::string>()), read_png(dragged_png));
  const Difference turned = compare(read_png(dragged_png), unrotated);
  std::cout << "dragged to " << dragged_quat << ": mean |page - render| " << dragged.mean[0] << ", "
            << dragged.mean[1] << ", " << dragged.mean[2] << "; render against render unrotated " << turned.mean[0]
            << ", " << turned.mean[1] << ", " << turned.mean[2] << "\n";
  for (int c = 0; c < 3; ++c) EXPECT_LE(dragged.mean[c], 2.0) << "dragged, channel " << c;
  EXPECT_GT(std::max({turned.mean[0], turned.mean[1], turned.mean[2]}), 6.0);
  // A finger's drag reaches the page as pointer events of type touch and turns the light as
  // the mouse's drag does: the same rotation, the same pixels.
  for (const auto& [view, type] : {std::pair{drag_view, "mouse"}, std::pair{touch_view, "touch"}}) {
    const nlohmann::json& types = result["pointerTypes"][view];
    EXPECT_FALSE(types.empty()) << specs[view] << ": no pointermove on the canvas";
    for (const auto& t : types) EXPECT_EQ(t.get<std::string>(), type) << specs[view] << ": " << types;
  }
  EXPECT_EQ(result["status"][touch_view], result["status"][drag_view]);
  const Difference touch_vs_mouse = compare(read_png(result["views"][touch_view].get<std::string>()),
                                            read_png(result["views"][drag_view].get<std::string>()));
  const Difference touch_vs_render = compare(read_png(result["views"][touch_view].get<std::string>()), read_png(dragged_png));
  std::cout << "touch drag: " << result["status"][touch_view] << "; against the mouse drag: max difference "
            << touch_vs_mouse.max_both << "; against render: mean " << touch_vs_render.mean[0] << ", "
            << touch_vs_render.mean[1] << ", " << touch_vs_render.mean[2] << "; max " << touch_vs_render.max_both
            << "\n";
  for (int c = 0; c < 3; ++c) EXPECT_LE(touch_vs_render.mean[c], 2.0) << "touch drag, channel " << c;
  EXPECT_EQ(touch_vs_mouse.uncovered_on_page, 0u);
  EXPECT_LE(touch_vs_mouse.max_both, 1);

  // Per frame against per vertex (and against the split pass), same rotation: the texture
  // holds the float32 numbers the vertex shader would compute with the same generated code,
  // passed as flat varyings, so the pixels agree; 1/255
  // leaves room for a driver that orders the arithmetic of the two shaders differently
  // (SwiftShader draws them byte-identical). A texture read at the wrong texel, channel or
  // component moves a coefficient to another band and misses this by far.
  const Rgba per_frame = read_png(result["views"][1].get<std::string>());
  for (const std::size_t k : {vertex_view, fallback_view, split_view}) {
    const Rgba per_vertex = read_png(result["views"][k].get<std::string>());
    const Difference paths = compare(per_vertex, per_frame);
    const Difference against_render = compare(per_vertex, read_png(references[1]));
    std::cout << specs[k] << " against per frame: " << paths.uncovered_on_page
              << " pixels not covered by both; max difference " << paths.max_both << "; mean " << paths.mean[0]
              << ", " << paths.mean[1] << ", " << paths.mean[2] << "; against render: " << against_render.covered
              << " pixels covered by render, " << against_render.uncovered_on_page << " of them not by the page; mean "
              << against_render.mean[0] << ", " << against_render.mean[1] << ", " << against_render.mean[2] << "; max "
              << against_render.max_both << " where both cover\n";
    EXPECT_EQ(paths.uncovered_on_page, 0u) << specs[k];
    EXPECT_LE(paths.max_both, 1) << specs[k];
    for (int c = 0; c < 3; ++c) EXPECT_LE(against_render.mean[c], 2.0) << specs[k] << ", channel " << c;
  }

  // A broken pass misses render by far, and the per-vertex page too.
  const Rgba broken = read_png(result["views"][broken_view].get<std::string>());
  const Difference broken_vs_render = compare(broken, read_png(references[1]));
  const Difference broken_vs_vertex = compare(broken, read_png(result["views"][vertex_view].get<std::string>()));
  std::cout << "pass broken on purpose (texels shifted): mean |page - render| " << broken_vs_render.mean[0] << ", "
            << broken_vs_render.mean[1] << ", " << broken_vs_render.mean[2] << "; max against per vertex "
            << broken_vs_vertex.max_both << "\n";
  EXPECT_GT(std::max({broken_vs_render.mean[0], broken_vs_render.mean[1], broken_vs_render.mean[2]}), 2.0);
  EXPECT_GT(broken_vs_vertex.max_both, 1);

  // Order 8: the one-point pass against render under the turned order-8 light, and against
  // the per-vertex path and the two-point split, as above.
  const fs::path render8 = scratch("render-8.png");
  must(run_shtool(with_view({"render", kSpotObj, "--fit", fit8.string(), "--light",
                             rotated_light(sky8, quats[0], "sky8-turned.json").string(), "--out", render8.string()})));
  const Rgba order8 = read_png(result["views"][order8_view].get<std::string>());
  const Difference d8 = compare(order8, read_png(render8));
  std::cout << "order 8, light-rotation=" << quats[0] << ": " << d8.covered << " pixels covered by render, "
            << d8.uncovered_on_page << " of them not by the page; mean |page - render| " << d8.mean[0] << ", "
            << d8.mean[1] << ", " << d8.mean[2] << "; max " << d8.max_both << " where both cover\n";
  ASSERT_GT(d8.covered, 2000u);
  EXPECT_LE(d8.uncovered_on_page, d8.covered / 100);
  for (int c = 0; c < 3; ++c) EXPECT_LE(d8.mean[c], 2.0) << "order 8, channel " << c;
  for (const std::size_t k : {order8_vertex_view, order8_split_view}) {
    const Difference paths = compare(read_png(result["views"][k].get<std::string>()), order8);
    std::cout << specs[k] << " against per frame: " << paths.uncovered_on_page
              << " pixels not covered by both; max difference " << paths.max_both << "\n";
    EXPECT_EQ(paths.uncovered_on_page, 0u) << specs[k];
    EXPECT_LE(paths.max_both, 1) << specs[k];
  }
}

// An encoded grid reaches three.js as bake-probes --threejs writes it: zh3 as the order-3
// SH it stands for (explicit and hallucinated fits), the same bytes; l1, which three.js
// cannot reconstruct, refused with nothing written.
TEST(ExportWeb, EncodedProbeGridsAsBakeProbesWritesThemForThree) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const std::vector<std::string> bake = {"bake-probes", kSpotObj,  "--grid",    "3,2,2", "--env", bakes().sky.string(),
                                         "--samples",   "32",      "--bounces", "1",     "--order", "3"};
  for (const char* fit : {"explicit", "hallucinated"}) {
    const fs::path table = scratch(std::string("zh3-") + fit + ".shtb"), three = scratch(std::string("three-") + fit),
                   page = scratch(std::string("page-zh3-") + fit);
    fs::remove_all(three);
    fs::remove_all(page);
    fs::create_directories(three);
    std::vector<std::string> args = bake;
    args.insert(args.end(), {"--encoding", "zh3", "--zh3-fit", fit, "--out", table.string(), "--threejs", three.string()});
    must(run_shtool(args));
    must(run_shtool({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light", bakes().sky.string(),
                     "--probes", table.string(), "--out", page.string()}));
    EXPECT_EQ(read_file(page / "probes/probes.bin"), read_file(three / "probes.bin")) << fit;
    EXPECT_EQ(read_json(page / "probes/probes.json"), read_json(three / "probes.json")) << fit;
  }
  const fs::path l1 = scratch("l1.shtb"), page = scratch("page-l1");
  fs::remove_all(page);
  std::vector<std::string> args = bake;
  args.insert(args.end(), {"--encoding", "l1", "--out", l1.string()});
  must(run_shtool(args));
  const CommandResult r = run_shtool({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                                      bakes().sky.string(), "--probes", l1.string(), "--out", page.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("non-linear L1"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(page));
}

// three samples a probe grid half a cell along the normal and leaves a point unlit where
// that falls outside the box: a box ending at the ground (bake-probes' default bounds, the
// mesh's own) blackens the spheres' undersides, and export-web says so; a box reaching a
// cell below does not. scene.json names its inputs and the mesh's up axis.
TEST(ExportWeb, WarnsWhenTheProbeBoxEndsAtTheGround) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const fs::path tight = scratch("tight.shtb"), deep = scratch("deep.shtb");
  must(run_shtool({"bake-probes", kSpotObj, "--grid", "2,2,2", "--env", bakes().sky.string(), "--samples", "8",
                   "--bounces", "0", "--out", tight.string()}));
  // spot's lowest point is at z = -0.7368 (file y); a cell of this box is 1.2 high.
  must(run_shtool({"bake-probes", kSpotObj, "--grid", "2,2,2", "--bounds=-1.5,-1.5,-1.94,1.5,1.5,0.46", "--env",
                   bakes().sky.string(), "--samples", "8", "--bounces", "0", "--out", deep.string()}));
  for (const bool ends_at_ground : {true, false}) {
    const fs::path page = scratch(ends_at_ground ? "tight_page" : "deep_page");
    fs::remove_all(page);
    const CommandResult r = run_shtool({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                                        bakes().sky.string(), "--probes", (ends_at_ground ? tight : deep).string(),
                                        "--out", page.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("below the ground, less than half a cell") != std::string::npos, ends_at_ground) << r.err;
    const nlohmann::json scene = read_json(page / "scene.json");
    EXPECT_EQ(scene["source"]["mesh"], fs::path(kSpotObj).filename().string());
    EXPECT_EQ(scene["source"]["up"], "y");
    EXPECT_EQ(scene["source"]["probes"], (ends_at_ground ? tight : deep).filename().string());
    if (ends_at_ground) continue;
    // Every sphere half a cell (0.75, 0.75, 0.6) inside each face of the deep box, or three
    // leaves its outer parts black. The page's frame is three's: shtool (x, y, z) = (X, -Z, Y).
    ASSERT_EQ(scene["spheres"].size(), 3u);
    const double lo[3] = {-1.5, -1.5, -1.94}, hi[3] = {1.5, 1.5, 0.46}, half[3] = {0.75, 0.75, 0.6};
    for (const nlohmann::json& sphere : scene["spheres"]) {
      const double r = sphere["radius"].get<double>(), X = sphere["centre"][0].get<double>(),
                   Y = sphere["centre"][1].get<double>(), Z = sphere["centre"][2].get<double>();
      const double p[3] = {X, -Z, Y};
      EXPECT_GT(r, 0.1);
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(p[a] - r - half[a], lo[a] - 1e-9) << sphere.dump();
        EXPECT_LE(p[a] + r + half[a], hi[a] + 1e-9) << sphere.dump();
      }
    }
  }
  // A box that starts above the mesh's lowest point puts the page's ground at its bottom,
  // and says so; an atlas side past WebGL2's 256 names the grid axis that makes it.
  const fs::path high = scratch("high.shtb"), wide = scratch("wide.shtb");
  must(run_shtool({"bake-probes", kSpotObj, "--grid", "2,2,2", "--bounds=-1.5,-1.5,-0.5,1.5,1.5,1", "--env",
                   bakes().sky.string(), "--samples", "8", "--bounces", "0", "--out", high.string()}));
  must(run_shtool({"bake-probes", kSpotObj, "--grid", "300,2,2", "--env", bakes().sky.string(), "--samples", "4",
                   "--bounces", "0", "--out", wide.string()}));
  for (const bool is_high : {true, false}) {
    const fs::path page = scratch(is_high ? "high_page" : "wide_page");
    fs::remove_all(page);
    const CommandResult r =
        run_shtool({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light", bakes().sky.string(), "--probes",
                    (is_high ? high : wide).string(), "--out", page.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    if (is_high) {
      EXPECT_NE(r.err.find("box starts 0.236784 above the mesh's lowest point"), std::string::npos) << r.err;
      EXPECT_EQ(r.err.find("below the ground"), std::string::npos) << r.err;
    } else {
      EXPECT_NE(r.err.find("300 x 2 x 28 texels, and its side for the grid's x (300 texels)"), std::string::npos)
          << r.err;
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
  // A light the page's float32 cannot hold.
  const fs::path huge = scratch("huge.json");
  write_file(huge, R"({"order": 1, "quantity": "radiance", "channels": ["r", "g", "b"], "window": {"type": "none"},
                       "coefficients": [[1e39, 1, 1]]})");
  expect_refused("export-web", {kSpotObj, "--fit", bakes().fit.string(), "--light", huge.string()},
                 "beyond float32's range", dir);
  // An existing folder is left as it was.
  fs::create_directories(dir);
  const CommandResult r = run_shtool({"export-web", kSpotObj, "--fit", tetra_fit.string(), "--light",
                                      bakes().sky.string(), "--out", dir.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(fs::is_empty(dir));
  // three.js not where it was said to be: refused, the folder not made.
  const fs::path no_three = scratch("no-three");
  const CommandResult missing = run_checked({"env", "SHTOOL_THREE_DIR=" + scratch("nowhere").string(), kShtoolExe,
                                             "export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                                             bakes().sky.string(), "--out", no_three.string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("three.js was not found"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(no_three));
  // A folder that cannot be made: an ancestor is a file (missing parents are made).
  const fs::path blocker = scratch("blocker");
  write_file(blocker, "x");
  const CommandResult blocked = run_shtool({"export-web", kSpotObj, "--fit", bakes().fit.string(), "--light",
                                            bakes().sky.string(), "--out", (blocker / "site" / "page").string()});
  EXPECT_EQ(blocked.exit_code, 1);
  EXPECT_NE(blocked.err.find("cannot be made: " + blocker.string() + " is not a folder"), std::string::npos)
      << blocked.err;
  EXPECT_EQ(read_file(blocker), "x");
}

}  // namespace
