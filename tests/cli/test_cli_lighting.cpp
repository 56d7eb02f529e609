// shtool project-env and shtool light end to end: every image format and layout on
// uniform radiance (c_00 = sqrt(4 pi) exactly), layouts and presets against each other
// (the other tools' mappings written out here from their sources), the render-back
// round trip, the automatic window, thread-count independence, and bad input (an error,
// a non-zero exit, no output).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <half.h>
#include <nlohmann/json.hpp>
#include <stb_image_write.h>

#include "lighting/image_io.h"
#include "cli_test.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool {
namespace {

using namespace test;
constexpr double kPi = std::numbers::pi;

const Scratch scratch("lighting");

using Texels = std::vector<float>;  // RGB, rows top first

void write_exr(const fs::path& p, int w, int h, const Texels& rgb, bool half_float,
               Imf::Compression compression = Imf::ZIP_COMPRESSION, int data_offset = 0) {
  Imf::Header header(Imath::Box2i({0, 0}, {w - 1, h - 1}),
                     Imath::Box2i({data_offset, 0}, {data_offset + w - 1, h - 1}));
  header.compression() = compression;
  const char* names[3] = {"R", "G", "B"};
  std::vector<half> halves;
  if (half_float) halves.assign(rgb.begin(), rgb.end());
  for (const char* n : names) header.channels().insert(n, Imf::Channel(half_float ? Imf::HALF : Imf::FLOAT));
  Imf::OutputFile file(p.c_str(), header);
  Imf::FrameBuffer fb;
  const Imath::Box2i dw = header.dataWindow();
  for (int c = 0; c < 3; ++c) {
    if (half_float)
      fb.insert(names[c], Imf::Slice::Make(Imf::HALF, halves.data() + c, dw, 3 * sizeof(half), w * 3 * sizeof(half)));
    else
      fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb.data() + c, dw, 3 * sizeof(float), w * 3 * sizeof(float)));
  }
  file.setFrameBuffer(fb);
  file.writePixels(h);
}

// Radiance RGBE without run-length encoding (stb writes the run-length form).
void write_flat_hdr(const fs::path& p, int w, int h, const Texels& rgb) {
  std::string out = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " + std::to_string(h) + " +X " + std::to_string(w) + "\n";
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    const float m = std::max({rgb[i], rgb[i + 1], rgb[i + 2]});
    int e = 0;
    const float scale = std::frexp(m, &e) * 256.0f / m;
    for (int c = 0; c < 3; ++c) out += static_cast<char>(static_cast<unsigned char>(rgb[i + c] * scale));
    out += static_cast<char>(e + 128);
  }
  write_file(p, out);
}

void write_stb(const fs::path& p, int w, int h, const Texels& rgb) {
  const std::string ext = p.extension().string();
  if (ext == ".hdr") {
    ASSERT_TRUE(stbi_write_hdr(p.c_str(), w, h, 3, rgb.data()));
    return;
  }
  std::vector<unsigned char> bytes(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i)
    bytes[i] = static_cast<unsigned char>(std::lround(255 * lighting::linear_to_srgb(rgb[i])));
  if (ext == ".png") ASSERT_TRUE(stbi_write_png(p.c_str(), w, h, 3, bytes.data(), w * 3));
  else ASSERT_TRUE(stbi_write_jpg(p.c_str(), w, h, 3, bytes.data(), 100));
}

nlohmann::json project(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"project-env"};
  argv.insert(argv.end(), args.begin(), args.end());
  const fs::path json = scratch("projection.json");
  fs::remove(json);
  argv.insert(argv.end(), {"--json", json.string()});
  const test::CommandResult r = run_shtool(argv);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(read_file(json));
}

void expect_uniform(const nlohmann::json& j, double value, const std::string& what) {
  const auto& c = j["coefficients"];
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[0][ch].get<double>(), value, 1e-14) << what;
  for (std::size_t i = 1; i < c.size(); ++i)
    for (int ch = 0; ch < 3; ++ch) ASSERT_LT(std::abs(c[i][ch].get<double>()), 1e-14) << what << " row " << i;
}

// The six faces (+X -X +Y -Y +Z -Z) of a cube as separate files and as both crosses.
struct Cube {
  int size;
  std::array<Texels, 6> faces;
};

Texels cross_texels(const Cube& cube, bool horizontal, int& w, int& h) {
  const int n = cube.size;
  w = horizontal ? 4 * n : 3 * n;
  h = horizontal ? 3 * n : 4 * n;
  Texels out(static_cast<std::size_t>(w) * h * 3, 0.0f);
  const int at[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {horizontal ? 3 : 1, horizontal ? 1 : 3}};
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        // The vertical cross holds -Z turned by 180 degrees (cmft, filament).
        const bool turned = !horizontal && f == 5;
        const int fx = turned ? n - 1 - x : x, fy = turned ? n - 1 - y : y;
        for (int c = 0; c < 3; ++c)
          out[((at[f][1] * n + y) * w + at[f][0] * n + x) * 3 + c] = cube.faces[f][(fy * n + fx) * 3 + c];
      }
  return out;
}

TEST(CliProjectEnv, UniformRadianceInEveryFormatAndLayout) {
  const double c00 = std::sqrt(4 * kPi);
  const int w = 64, h = 32;
  const Texels ones(static_cast<std::size_t>(w) * h * 3, 1.0f);
  struct File {
    std::string name;
    std::function<void(const fs::path&)> write;
  };
  const std::vector<File> files = {
      {"float.exr", [&](const fs::path& p) { write_exr(p, w, h, ones, false); }},
      {"half.exr", [&](const fs::path& p) { write_exr(p, w, h, ones, true); }},
      {"piz.exr", [&](const fs::path& p) { write_exr(p, w, h, ones, true, Imf::PIZ_COMPRESSION); }},
      {"plain.exr", [&](const fs::path& p) { write_exr(p, w, h, ones, false, Imf::NO_COMPRESSION); }},
      {"rle.hdr", [&](const fs::path& p) { write_stb(p, w, h, ones); }},
      {"flat.hdr", [&](const fs::path& p) { write_flat_hdr(p, w, h, ones); }},
      {"srgb.png", [&](const fs::path& p) { write_stb(p, w, h, ones); }},
      {"srgb.jpg", [&](const fs::path& p) { write_stb(p, w, h, ones); }},
  };
  for (const File& f : files) {
    const fs::path p = scratch(f.name);
    f.write(p);
    expect_uniform(project({p.string(), "--order", "5"}), c00, f.name);
    expect_uniform(project({p.string(), "--order", "3", "--quantity", "irradiance"}), kPi * c00, f.name);
  }
  // A grey (Y-only) EXR is grey RGB.
  {
    const fs::path p = scratch("grey.exr");
    Imf::Header header(w, h);
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    const std::vector<float> y(static_cast<std::size_t>(w) * h, 1.0f);
    Imf::OutputFile file(p.c_str(), header);
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice(Imf::FLOAT, (char*)y.data(), sizeof(float), w * sizeof(float)));
    file.setFrameBuffer(fb);
    file.writePixels(h);
  }
  expect_uniform(project({scratch("grey.exr").string(), "--order", "4"}), c00, "grey.exr");
  // Cubemaps: two crosses and six files, from the same faces.
  Cube cube{16, {}};
  for (Texels& t : cube.faces) t.assign(16 * 16 * 3, 1.0f);
  for (bool horizontal : {true, false}) {
    int cw = 0, ch = 0;
    const Texels cross = cross_texels(cube, horizontal, cw, ch);
    const fs::path p = scratch(horizontal ? "hcross.exr" : "vcross.exr");
    write_exr(p, cw, ch, cross, false);
    expect_uniform(project({p.string(), "--order", "6"}), c00, p.filename().string());
  }
  const char* suffix[6] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (int f = 0; f < 6; ++f) write_exr(scratch(std::string("face_") + suffix[f] + ".exr"), 16, 16, cube.faces[f], true);
  expect_uniform(project({scratch("face_%s.exr").string(), "--order", "6"}), c00, "faces");
}

TEST(CliProjectEnv, CrossesAndFaceFilesAgree) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 3);
  Cube cube{8, {}};
  for (Texels& t : cube.faces) {
    t.resize(8 * 8 * 3);
    for (float& v : t) v = u(rng);
  }
  const char* suffix[6] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (int f = 0; f < 6; ++f) write_exr(scratch(std::string("rface_") + suffix[f] + ".exr"), 8, 8, cube.faces[f], false);
  const nlohmann::json faces = project({scratch("rface_%s.exr").string(), "--order", "5"});
  for (bool horizontal : {true, false}) {
    int cw = 0, ch = 0;
    const Texels cross = cross_texels(cube, horizontal, cw, ch);
    const fs::path p = scratch(horizontal ? "rhcross.exr" : "rvcross.exr");
    write_exr(p, cw, ch, cross, false);
    EXPECT_EQ(project({p.string(), "--order", "5"})["coefficients"], faces["coefficients"]) << p;
  }
  // --mirror-x: the mirror image of the environment, whose coefficients change sign
  // with x -> -x: (-1)^m for m >= 0, (-1)^(m+1) for m < 0.
  const nlohmann::json mirrored = project({scratch("rface_%s.exr").string(), "--order", "5", "--mirror-x"});
  for (int l = 0; l < 5; ++l)
    for (int m = -l; m <= l; ++m) {
      const double sign = m >= 0 ? (m % 2 ? -1 : 1) : ((m + 1) % 2 ? -1 : 1);
      for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(mirrored["coefficients"][sh_index(l, m)][ch].get<double>(),
                    sign * faces["coefficients"][sh_index(l, m)][ch].get<double>(), 1e-13);
    }
}

// A smooth scene, and equirect images of it in the other tools' mappings, each written
// out from the tool's source (docs/lighting.md cites them).
double scene(const Eigen::Vector3d& w, int c) {
  return 1.0 + (c + 1) * 0.7 * std::exp(3 * (w.dot(Eigen::Vector3d(0.36, -0.48, 0.8)) - 1)) + 0.2 * w.y();
}

Texels equirect_image(int w, int h, const std::function<Eigen::Vector3d(double u, double v)>& direction) {
  Texels t(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        t[(y * w + x) * 3 + c] = static_cast<float>(scene(direction((x + 0.5) / w, (y + 0.5) / h), c));
  return t;
}

TEST(CliProjectEnv, EquirectPresetsMatchTheirTools) {
  const int w = 128, h = 64;
  // y-up engine direction (x, y, z) -> shtool (x, -z, y).
  auto from_y_up = [](double x, double y, double z) { return Eigen::Vector3d(x, -z, y); };
  const std::map<std::string, std::function<Eigen::Vector3d(double, double)>> presets = {
      {"shtool",
       [](double u, double v) { return direction_from_angles<double>(kPi * v, kPi - 2 * kPi * u); }},
      // three.js equirectUv: u = atan(d.z, d.x) / 2pi + 1/2, v = asin(d.y) / pi + 1/2 (v up;
      // the loaders put the file's first row at the top).
      {"three",
       [&](double u, double v) {
         const double phi = 2 * kPi * (u - 0.5), theta = kPi * v;
         return from_y_up(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
       }},
      // filament CubemapUtils::equirectangularToCubemap: (sin t sin l, cos t, sin t cos l),
      // l = 2 pi u - pi; then cmgen's default mirrorCubemap negates x.
      {"filament",
       [&](double u, double v) {
         const double l = 2 * kPi * u - kPi, t = kPi * v;
         return from_y_up(-std::sin(t) * std::sin(l), std::cos(t), std::sin(t) * std::cos(l));
       }},
      // google/spherical-harmonics ImageXToPhi / ImageYToTheta + ToVector, z up.
      {"google",
       [](double u, double v) {
         const double phi = 2 * kPi * u, t = kPi * v;
         return Eigen::Vector3d(std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t));
       }},
  };
  const fs::path own = scratch("preset_shtool.exr");
  write_exr(own, w, h, equirect_image(w, h, presets.at("shtool")), false);
  const nlohmann::json reference = project({own.string(), "--order", "6"});
  for (const auto& [name, direction] : presets) {
    const fs::path p = scratch("preset_" + name + ".exr");
    write_exr(p, w, h, equirect_image(w, h, direction), false);
    const nlohmann::json got = project({p.string(), "--order", "6", "--equirect-preset", name});
    // Each mapping is a rotation or mirror that carries texels onto texels, so the
    // projections agree to rounding, not just to the discretisation error.
    for (int i = 0; i < 36; ++i)
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(got["coefficients"][i][c].get<double>(), reference["coefficients"][i][c].get<double>(), 1e-12)
            << name << " coefficient " << i;
    if (name != "shtool" && name != "three") {
      // ... and the preset matters: read as shtool's mapping, the image is another scene.
      const nlohmann::json wrong = project({p.string(), "--order", "6"});
      EXPECT_GT(std::abs(wrong["coefficients"][1][0].get<double>() - reference["coefficients"][1][0].get<double>()) +
                    std::abs(wrong["coefficients"][3][0].get<double>() - reference["coefficients"][3][0].get<double>()),
                1e-3)
          << name;
    }
  }
}

TEST(CliProjectEnv, RenderBackRoundTripAndOutputs) {
  const fs::path sky = fs::path(kSourceDir) / "data" / "sky.hdr";
  const fs::path back = scratch("back.exr"), table = scratch("sky.shtb");
  const nlohmann::json first =
      project({sky.string(), "--order", "4", "--render-back", back.string(), "--out", table.string()});
  // The render-back is band-limited: projected again it returns its coefficients, to the
  // midpoint sampling error of a 512 x 256 image.
  const nlohmann::json again = project({back.string(), "--order", "4"});
  const double scale = first["coefficients"][0][0].get<double>();
  for (int i = 0; i < 16; ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(again["coefficients"][i][c].get<double>(), first["coefficients"][i][c].get<double>(), 1e-4 * scale)
          << i;
  // The table holds the JSON's numbers, and its header follows the schema.
  const Result<Table> t = read_table(table, {"env-sh", 1, 0});
  ASSERT_TRUE(t) << t.error().message;
  const std::vector<double> c = t.value().get<double>("coefficients").value();
  EXPECT_EQ(c[3 * 5 + 2], first["coefficients"][5][2].get<double>());
  expect_valid_against_schema("env-sh.schema.json", {table});
  EXPECT_EQ(first["order"], 4);
  EXPECT_EQ(first["quantity"], "radiance");
  EXPECT_EQ(first["channels"], nlohmann::json({"r", "g", "b"}));
  EXPECT_EQ(first["window"]["type"], "none");
}

// --render-source: the source through the render-back's equirect. An equirect of the
// render-back's size comes back texel for texel; six constant faces come back as the face
// each texel centre's direction hits (the cube frame's major axis, docs/lighting.md).
TEST(CliProjectEnv, RenderSourceIsTheSourceInTheRenderBacksMapping) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 4);
  Texels image(512 * 256 * 3);
  for (float& v : image) v = u(rng);
  const fs::path in = scratch("source_in.exr"), out = scratch("source_out.exr"), back = scratch("source_back.exr");
  write_exr(in, 512, 256, image, false);
  project({in.string(), "--order", "2", "--render-source", out.string(), "--render-back", back.string()});
  const lighting::Image same = read_image(out);
  ASSERT_EQ(same.width, 512);
  ASSERT_EQ(same.height, 256);
  EXPECT_EQ(same.texels, image);
  EXPECT_EQ(read_image(back).width, 512);

  Cube cube{4, {}};
  for (int f = 0; f < 6; ++f) cube.faces[f].assign(4 * 4 * 3, float(f + 1));
  const char* suffix[6] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (int f = 0; f < 6; ++f) write_exr(scratch(std::string("cface_") + suffix[f] + ".exr"), 4, 4, cube.faces[f], false);
  const fs::path faces_out = scratch("faces_source.exr");
  project({scratch("cface_%s.exr").string(), "--order", "2", "--render-source", faces_out.string()});
  const lighting::Image seen = read_image(faces_out);
  ASSERT_EQ(seen.width, 512);  // 2 x 4 texels, raised to the smallest render-back of 256 rows
  ASSERT_EQ(seen.height, 256);
  int wrong = 0;
  for (int y = 0; y < seen.height; ++y)
    for (int x = 0; x < seen.width; ++x) {
      const double t = kPi * (y + 0.5) / seen.height, p = kPi - 2 * kPi * (x + 0.5) / seen.width;
      const Eigen::Vector3d w(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
      const Eigen::Vector3d cube_dir(w.x(), w.z(), -w.y());  // the y-up cube frame
      int axis = 0;
      cube_dir.cwiseAbs().maxCoeff(&axis);
      const int face = 2 * axis + (cube_dir[axis] < 0);
      // Directions within a hair of a cube edge may land on either face.
      Eigen::Vector3d a = cube_dir.cwiseAbs();
      std::sort(a.data(), a.data() + 3);
      if (a[2] - a[1] < 1e-9) continue;
      wrong += seen.texels[(std::size_t(y) * seen.width + x) * 3] != float(face + 1);
    }
  EXPECT_EQ(wrong, 0);
}

TEST(CliProjectEnv, SameBytesWhateverTheThreadCount) {
  const fs::path sky = fs::path(kSourceDir) / "data" / "sky.hdr";
  std::string bytes[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path json = scratch("t" + std::to_string(k) + ".json"), table = scratch("t" + std::to_string(k) + ".shtb");
    const test::CommandResult r = run_shtool({"project-env", sky.string(), "--order", "9", "--window", "auto",
                                               "--threads", k == 0 ? "1" : "3", "--json", json.string(), "--out",
                                               table.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    bytes[k] = read_file(json) + read_file(table);
  }
  EXPECT_EQ(bytes[0], bytes[1]);
}

TEST(CliProjectEnv, ExrCrossSameBytesWhateverTheThreadCountAndItsCrc) {
  // A float ZIP OpenEXR cross of 40^2 faces: the decoder's pool and the cube blocks both
  // follow --threads, and the generator record holds the CRC-32 of the file's bytes
  // (hashed while OpenEXR reads them).
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 3);
  const int w = 160, h = 120;
  Texels cross(static_cast<std::size_t>(w) * h * 3);
  for (float& v : cross) v = u(rng);
  const fs::path image = scratch("threads_cross.exr");
  write_exr(image, w, h, cross, false);
  std::string bytes[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path json = scratch("x" + std::to_string(k) + ".json"), table = scratch("x" + std::to_string(k) + ".shtb");
    const test::CommandResult r = run_shtool({"project-env", image.string(), "--order", "7", "--threads",
                                               k == 0 ? "1" : "3", "--json", json.string(), "--out", table.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    bytes[k] = read_file(json) + read_file(table);
    const Result<Table> t = read_table(table, {"env-sh", 1, 0});
    ASSERT_TRUE(t) << t.error().message;
    const std::string file = read_file(image);
    EXPECT_EQ(nlohmann::json::parse(t.value().generator)["parameters"]["input_crc32"].get<std::uint32_t>(),
              table_crc32(std::span<const std::byte>(reinterpret_cast<const std::byte*>(file.data()), file.size())));
  }
  EXPECT_EQ(bytes[0], bytes[1]);
}

TEST(CliProjectEnv, AutoWindowMakesASunNonNegative) {
  // A sun of 1e4 (3 degrees across) over a dim sky, order 8: without a window the
  // reconstruction rings below zero; with --window auto it does not.
  const int w = 512, h = 256;
  const Eigen::Vector3d sun = Eigen::Vector3d(0.3, 0.2, 0.9).normalized();
  const Texels img = [&] {
    Texels t(static_cast<std::size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Eigen::Vector3d d = direction_from_angles<double>(kPi * (y + 0.5) / h, kPi - 2 * kPi * (x + 0.5) / w);
        for (int c = 0; c < 3; ++c)
          t[(y * w + x) * 3 + c] = d.dot(sun) > std::cos(1.5 * kPi / 180) ? 1e4f : 0.1f + 0.1f * c;
      }
    return t;
  }();
  const fs::path p = scratch("sun.exr");
  write_exr(p, w, h, img, false);
  auto lowest = [](const nlohmann::json& j) {
    std::vector<double> c;
    for (const auto& row : j["coefficients"]) c.push_back(row[0].get<double>());
    double m = 1e300;
    for (int k = 0; k < 20000; ++k) {
      const double z = 1 - (2 * k + 1.0) / 20000, r = std::sqrt(1 - z * z), a = k * kPi * (3 - std::sqrt(5.0));
      m = std::min(m, reconstruct<double>(c, Eigen::Vector3d(r * std::cos(a), r * std::sin(a), z)));
    }
    return m;
  };
  EXPECT_LT(lowest(project({p.string(), "--order", "8"})), 0.0);
  const nlohmann::json windowed = project({p.string(), "--order", "8", "--window", "auto"});
  EXPECT_EQ(windowed["window"]["type"], "auto");
  EXPECT_TRUE(windowed["window"]["cutoff"].is_number());
  EXPECT_EQ(windowed["window"]["factors"].size(), 8u);
  EXPECT_GE(lowest(windowed), 0.0);
}

struct BadCase {
  std::string name;
  std::vector<std::string> args;
  std::string message;
};

TEST(CliProjectEnv, BadInputIsAnErrorWithNoOutput) {
  const fs::path text = scratch("not_an_image.exr");
  write_file(text, "hello, I am text\n");
  const fs::path wide = scratch("wide.exr");
  write_exr(wide, 48, 16, Texels(48 * 16 * 3, 1.0f), false);
  const fs::path odd = scratch("odd.exr");
  write_exr(odd, 40, 32, Texels(40 * 32 * 3, 1.0f), false);
  Texels nan(16 * 8 * 3, 1.0f);
  nan[(3 * 16 + 5) * 3 + 2] = std::numeric_limits<float>::quiet_NaN();
  const fs::path with_nan = scratch("nan.exr");
  write_exr(with_nan, 16, 8, nan, false);
  const fs::path windowed = scratch("window.exr");
  write_exr(windowed, 16, 8, Texels(16 * 8 * 3, 1.0f), false, Imf::ZIP_COMPRESSION, 4);
  const char* suffix[6] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (int f = 0; f < 6; ++f) {
    const int n = f == 3 ? 8 : 16;  // -Y smaller than the others
    write_exr(scratch(std::string("bad_") + suffix[f] + ".exr"), n, n, Texels(static_cast<std::size_t>(n) * n * 3, 1.0f),
              false);
  }
  const fs::path png_named_exr = scratch("png.exr");
  write_stb(scratch("real.png"), 8, 4, Texels(8 * 4 * 3, 0.5f));
  fs::copy_file(scratch("real.png"), png_named_exr, fs::copy_options::overwrite_existing);
  // Truncated files: stb_image would read zeros (HDR) or grey (JPEG) past the end.
  const Texels grey(16 * 8 * 3, 0.5f);
  write_stb(scratch("full_rle.hdr"), 16, 8, grey);
  write_flat_hdr(scratch("full_flat.hdr"), 16, 8, grey);
  write_stb(scratch("full.jpg"), 16, 8, grey);
  for (const char* name : {"full_rle.hdr", "full_flat.hdr", "full.jpg"}) {
    const std::string bytes = read_file(scratch(name));
    write_file(scratch(std::string("cut_") + name), bytes.substr(0, bytes.size() - 20));
  }
  // A PNG cut between chunks (after its IHDR, or before its IEND): stb_image gives no reason.
  write_stb(scratch("full.png"), 16, 8, grey);
  const std::string png = read_file(scratch("full.png"));
  write_file(scratch("cut_ihdr.png"), png.substr(0, 33));
  write_file(scratch("cut_iend.png"), png.substr(0, png.size() - 12));
  const fs::path cross43 = scratch("cross43.exr"), windowed_ok = scratch("ok.exr");
  write_exr(cross43, 64, 48, Texels(64 * 48 * 3, 1.0f), false);
  write_exr(windowed_ok, 16, 8, Texels(16 * 8 * 3, 1.0f), false);
  // Run-length rows, then a flat row: stb reads the whole image flat from there.
  {
    const std::string rle = read_file(scratch("full_rle.hdr"));
    const std::size_t body = rle.find("+X 16\n") + 6;
    std::string mixed = rle.substr(0, body);
    // First scanline as the file has it (run-length), then 4 bytes that are not a
    // run-length start, then a little data.
    std::size_t at = body + 4;
    for (int component = 0; component < 4; ++component)
      for (int x = 0; x < 16;) {
        const int count = static_cast<unsigned char>(rle[at]);
        const int run = count > 128 ? count - 128 : count;
        at += 1 + (count > 128 ? 1 : count);
        x += run;
      }
    mixed += rle.substr(body, at - body) + std::string("\x10\x10\x10\x80", 4) + std::string(64, '\x20');
    std::ofstream(scratch("mixed.hdr"), std::ios::binary) << mixed;
  }
  const std::vector<BadCase> cases = {
      {"run-length rows, then a short flat tail", {scratch("mixed.hdr").string()}, "data ends before"},
      {"preset on a cross", {cross43.string(), "--equirect-preset", "three"}, "--equirect-preset"},
      {"mirror on an equirect", {windowed_ok.string(), "--mirror-x"}, "--mirror-x"},
      {"truncated run-length HDR", {scratch("cut_full_rle.hdr").string()}, "data ends before"},
      {"truncated flat HDR", {scratch("cut_full_flat.hdr").string()}, "data ends before"},
      {"truncated JPEG", {scratch("cut_full.jpg").string()}, "truncated"},
      {"PNG cut after its IHDR", {scratch("cut_ihdr.png").string()}, "PNG: the file ends without its IEND chunk"},
      {"PNG cut before its IEND", {scratch("cut_iend.png").string()}, "PNG: the file ends without its IEND chunk"},
      {"missing file", {scratch("nope.exr").string()}, "nope.exr"},
      {"text named .exr", {text.string()}, "not a OpenEXR file"},
      {"png named .exr", {png_named_exr.string()}, "content is PNG"},
      {"3:1 image", {wide.string()}, "neither an equirect"},
      {"3:1 as equirect", {wide.string(), "--layout", "equirect"}, "must be 2:1"},
      {"cross of the wrong aspect", {odd.string(), "--layout", "cross"}, "4:3"},
      {"NaN texel", {with_nan.string()}, "texel (5, 3) channel 2 is NaN"},
      {"data window", {windowed.string()}, "data window"},
      {"faces of different sizes", {scratch("bad_%s.exr").string()}, "one size"},
      {"order 0", {wide.string(), "--order", "0"}, "--order"},
      {"order 33", {wide.string(), "--order", "33"}, "--order"},
      {"cutoff without window", {wide.string(), "--cutoff", "2"}, "--cutoff"},
      {"unknown window", {wide.string(), "--window", "gauss"}, "--window"},
      {"render-back .jpg", {wide.string(), "--render-back", scratch("x.jpg").string()}, ".exr"},
  };
  for (const BadCase& c : cases) {
    const fs::path json = scratch("bad.json"), table = scratch("bad.shtb");
    fs::remove(json);
    fs::remove(table);
    std::vector<std::string> argv = {"project-env"};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    argv.insert(argv.end(), {"--json", json.string(), "--out", table.string()});
    const test::CommandResult r = run_shtool(argv);
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(json)) << c.name;
    EXPECT_FALSE(fs::exists(table)) << c.name;
  }
}

// ---------------------------------------------------------------------------
// shtool light

nlohmann::json light(const std::vector<std::string>& args, int expect = 0, std::string* err = nullptr) {
  const fs::path json = scratch("light.json");
  fs::remove(json);
  std::vector<std::string> argv = {"light"};
  argv.insert(argv.end(), args.begin(), args.end());
  argv.insert(argv.end(), {"--json", json.string()});
  const test::CommandResult r = run_shtool(argv);
  EXPECT_EQ(r.exit_code, expect) << r.err;
  if (err) *err = r.err;
  if (expect != 0) {
    EXPECT_FALSE(fs::exists(json));
    return {};
  }
  return nlohmann::json::parse(read_file(json));
}

TEST(CliLight, ClosedFormsAndSums) {
  const Eigen::Vector3d d = Eigen::Vector3d(1, -2, 2).normalized();
  std::vector<double> y(25);
  eval_sh<double>(5, d, y);
  const nlohmann::json dir = light({"--type", "directional", "--dir", "1,-2,2", "--color", "2,3,4", "--order", "5"});
  for (int i = 0; i < 25; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(dir["coefficients"][i][c].get<double>(), (2 + c) * y[i], 1e-15);
  // A cone of radiance 1 and half-angle 60 degrees around +z: c_00 = 2 pi (1 - cos a) / sqrt(4 pi).
  const nlohmann::json cone = light({"--type", "cone", "--dir", "0,0,1", "--half-angle", "60", "--order", "3"});
  EXPECT_NEAR(cone["coefficients"][0][1].get<double>(), 2 * kPi * 0.5 / std::sqrt(4 * kPi), 1e-15);
  // The sphere light is the cone seen from its centre.
  EXPECT_EQ(light({"--type", "sphere", "--dir", "0,0,1", "--half-angle", "60", "--order", "3"})["coefficients"],
            cone["coefficients"]);
  const nlohmann::json constant = light({"--type", "constant", "--color", "1,1,1", "--order", "2",
                                         "--quantity", "irradiance"});
  EXPECT_NEAR(constant["coefficients"][0][0].get<double>() / std::sqrt(4 * kPi), kPi, 1e-15);
  EXPECT_EQ(constant["quantity"], "irradiance");
  // A list sums its lights.
  const fs::path list = scratch("lights.json");
  write_file(list, R"([{"type": "directional", "dir": [1, -2, 2], "color": [2, 3, 4]},
                        {"type": "cone", "dir": [0, 0, 1], "half_angle": 60}])");
  const nlohmann::json sum = light({"--lights", list.string(), "--order", "3"});
  for (int i = 0; i < 9; ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(sum["coefficients"][i][c].get<double>(),
                  dir["coefficients"][i][c].get<double>() + cone["coefficients"][i][c].get<double>(), 1e-15);
}

TEST(CliLight, BadInput) {
  const fs::path list = scratch("bad_lights.json");
  write_file(list, R"([{"type": "cone", "dir": [0, 0, 1]}])");
  const fs::path grounded = scratch("grounded_lights.json");
  write_file(grounded, R"([{"type": "directional", "dir": [0, 0, 1], "ground": [5, 5, 5]}])");
  const fs::path aimed = scratch("aimed_lights.json");
  write_file(aimed, R"([{"type": "constant", "dir": [0, 0, 1]}])");
  const std::vector<BadCase> cases = {
      {"no light", {"--order", "3"}, "no light"},
      {"zero direction", {"--type", "directional", "--dir", "0,0,0"}, "not zero"},
      {"missing direction", {"--type", "cone", "--half-angle", "5"}, "direction"},
      {"cone without angle", {"--type", "cone", "--dir", "0,0,1"}, "--half-angle"},
      {"angle out of range", {"--type", "cone", "--dir", "0,0,1", "--half-angle", "190"}, "(0, 180]"},
      {"two numbers", {"--type", "directional", "--dir", "0,1"}, "three numbers"},
      {"ground on a cone", {"--type", "cone", "--dir", "0,0,1", "--half-angle", "5", "--ground", "1,1,1"}, "--ground"},
      {"list without angle", {"--lights", list.string()}, "light 0"},
      {"order 40", {"--type", "constant", "--order", "40"}, "--order"},
      {"ground in a list", {"--lights", grounded.string()}, "\"ground\" is a hemisphere light's"},
      {"constant with a direction", {"--type", "constant", "--dir", "0,0,1"}, "takes no direction"},
      {"constant with a direction in a list", {"--lights", aimed.string()}, "takes no direction"},
  };
  for (const BadCase& c : cases) {
    std::string err;
    light(c.args, 1, &err);
    EXPECT_NE(err.find(c.message), std::string::npos) << c.name << ": " << err;
  }
}

// A direction is a direction at any length a double holds: (1e200, 1e200, 1e200) and
// (1e-200, ...) are (1, 1, 1), though their norms leave a double's range.
TEST(CliLight, DirectionsOfAnyLength) {
  const fs::path unit = scratch("dir_unit.json");
  ASSERT_EQ(run_shtool({"light", "--type", "cone", "--half-angle", "20", "--dir", "1,1,1", "--json", unit.string()})
                .exit_code,
            0);
  for (const char* dir : {"1e200,1e200,1e200", "1e-200,1e-200,1e-200", "3,3,3"}) {
    const fs::path out = scratch("dir_scaled.json");
    const auto r = run_shtool({"light", "--type", "cone", "--half-angle", "20", "--dir", dir, "--json", out.string()});
    ASSERT_EQ(r.exit_code, 0) << dir << ": " << r.err;
    EXPECT_EQ(read_file(out), read_file(unit)) << dir;
  }
}

}  // namespace
}  // namespace shtool
