// shtool transform-splats end to end: a splat seen along d before looks the same along
// R d after, by the 3D Gaussian Splatting colour formula written here from the
// reference implementation (utils/sh_utils.py, eval_sh: its constants, its signs);
// positions, orientations and log-scales follow the similarity; every PLY encoding;
// identity keeps the bytes; bad files are errors with no output.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstdlib>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include <nlohmann/json.hpp>

#include "node_consumers.h"
#include "cli_test.h"
#include "eval_3dgs.h"

namespace {

using namespace shtool::test;

const Scratch scratch("splats");

struct Splat {
  std::array<float, 3> p, n, scale;
  std::array<float, 4> rot;
  float opacity;
  std::array<std::vector<float>, 3> sh;  // per channel, (deg+1)^2
  std::int32_t tag;                      // an extra integer property, kept as is
};

std::vector<Splat> random_splats(int count, int deg, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g;
  std::vector<Splat> s(count);
  for (Splat& x : s) {
    for (float& v : x.p) v = 3 * g(rng);
    for (float& v : x.n) v = g(rng);
    for (float& v : x.scale) v = g(rng) - 3;
    for (float& v : x.rot) v = g(rng);
    x.opacity = g(rng);
    for (auto& c : x.sh) {
      c.resize((deg + 1) * (deg + 1));
      for (float& v : c) v = 0.5f * g(rng);
    }
    x.tag = static_cast<std::int32_t>(rng() % 1000);
  }
  return s;
}

// The reference implementation's layout: x y z nx ny nz f_dc_0..2 f_rest_* (channel
// major) opacity scale_0..2 rot_0..3, plus one extra int property at the end.
std::string write_ply(const std::vector<Splat>& splats, int deg, const std::string& format) {
  std::ostringstream h;
  h << "ply\nformat " << format << " 1.0\ncomment made by the test\nelement vertex " << splats.size() << "\n"
    << ply_3dgs_properties(deg) << "property int tag\nend_header\n";
  std::string out = h.str();
  for (const Splat& s : splats) {
    std::vector<float> v(s.p.begin(), s.p.end());
    v.insert(v.end(), s.n.begin(), s.n.end());
    for (int c = 0; c < 3; ++c) v.push_back(s.sh[c][0]);
    for (int c = 0; c < 3; ++c) v.insert(v.end(), s.sh[c].begin() + 1, s.sh[c].end());
    v.push_back(s.opacity);
    v.insert(v.end(), s.scale.begin(), s.scale.end());
    v.insert(v.end(), s.rot.begin(), s.rot.end());
    if (format == "ascii") {
      std::ostringstream line;
      line.precision(9);
      for (float f : v) line << f << ' ';
      line << s.tag << '\n';
      out += line.str();
    } else {
      const bool swap = format == "binary_big_endian";
      auto put = [&](const void* p) {
        char b[4];
        std::memcpy(b, p, 4);
        if (swap) std::swap(b[0], b[3]), std::swap(b[1], b[2]);
        out.append(b, 4);
      };
      for (float f : v) put(&f);
      put(&s.tag);
    }
  }
  return out;
}

// Reads back what write_ply wrote, through the same layout.
std::vector<Splat> read_ply(const std::string& bytes, int deg, const std::string& format, std::size_t count) {
  const int rest = (deg + 1) * (deg + 1) - 1;
  const std::size_t body = bytes.find("end_header\n") + 11;
  const std::size_t floats = 9 + 3 * rest + 8;
  std::vector<Splat> out(count);
  std::istringstream text(bytes.substr(body));
  for (std::size_t i = 0; i < count; ++i) {
    std::vector<float> v(floats);
    Splat& s = out[i];
    if (format == "ascii") {
      for (float& f : v) text >> f;
      text >> s.tag;
    } else {
      const bool swap = format == "binary_big_endian";
      auto get = [&](std::size_t k, void* p) {
        char b[4];
        std::memcpy(b, bytes.data() + body + (i * (floats + 1) + k) * 4, 4);
        if (swap) std::swap(b[0], b[3]), std::swap(b[1], b[2]);
        std::memcpy(p, b, 4);
      };
      for (std::size_t k = 0; k < floats; ++k) get(k, &v[k]);
      get(floats, &s.tag);
    }
    std::size_t k = 0;
    for (float& f : s.p) f = v[k++];
    for (float& f : s.n) f = v[k++];
    for (auto& c : s.sh) c.resize(rest + 1);
    for (int c = 0; c < 3; ++c) s.sh[c][0] = v[k++];
    for (int c = 0; c < 3; ++c)
      for (int j = 0; j < rest; ++j) s.sh[c][1 + j] = v[k++];
    s.opacity = v[k++];
    for (float& f : s.scale) f = v[k++];
    for (float& f : s.rot) f = v[k++];
  }
  return out;
}

Eigen::Matrix3d quat_matrix(const std::array<float, 4>& q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

TEST(CliTransformSplats, ColoursPositionsOrientationsAndScales) {
  const Eigen::Quaterniond qr = Eigen::Quaterniond(0.8, -0.3, 0.4, 0.33).normalized();
  const Eigen::Matrix3d R = qr.toRotationMatrix();
  const double scale = 2.5;
  const Eigen::Vector3d t(1, -2, 0.5);
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (const std::string format : {"binary_little_endian", "binary_big_endian", "ascii"}) {
    for (int deg = 0; deg <= 3; ++deg) {
      const std::vector<Splat> before = random_splats(300, deg, 11 + deg);
      const fs::path in = scratch("in.ply"), out = scratch("out.ply");
      std::ofstream(in, std::ios::binary) << write_ply(before, deg, format);
      std::ostringstream quat;
      quat.precision(17);
      quat << qr.w() << "," << qr.x() << "," << qr.y() << "," << qr.z();
      const auto r = run_shtool({"transform-splats", in.string(), "--quat", quat.str(), "--scale", "2.5",
                                  "--translate", "1,-2,0.5", "--out", out.string()});
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const std::string bytes = read_file(out);
      // The header is kept byte for byte.
      const std::string in_bytes = read_file(in);
      ASSERT_EQ(bytes.substr(0, bytes.find("end_header")), in_bytes.substr(0, in_bytes.find("end_header")));
      const std::vector<Splat> after = read_ply(bytes, deg, format, before.size());
      for (std::size_t i = 0; i < before.size(); ++i) {
        const Splat &a = before[i], &b = after[i];
        const Eigen::Vector3d p(a.p[0], a.p[1], a.p[2]), q(b.p[0], b.p[1], b.p[2]);
        ASSERT_LT((scale * (R * p) + t - q).norm(), 1e-5 * (1 + q.norm())) << format << " " << i;
        const Eigen::Vector3d n(a.n[0], a.n[1], a.n[2]), m(b.n[0], b.n[1], b.n[2]);
        ASSERT_LT((R * n - m).norm(), 1e-5 * (1 + n.norm()));
        ASSERT_LT((R * quat_matrix(a.rot) - quat_matrix(b.rot)).norm(), 1e-5);
        for (int k = 0; k < 3; ++k) ASSERT_NEAR(b.scale[k], a.scale[k] + std::log(scale), 1e-5);
        EXPECT_EQ(b.opacity, a.opacity);
        EXPECT_EQ(b.tag, a.tag);
        // The colour along d before is the colour along R d after.
        for (int k = 0; k < 5; ++k) {
          const Eigen::Vector3d d = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
          for (int c = 0; c < 3; ++c) {
            const std::vector<double> fa(a.sh[c].begin(), a.sh[c].end()), fb(b.sh[c].begin(), b.sh[c].end());
            ASSERT_NEAR(eval_3dgs(deg, fb.data(), R * d), eval_3dgs(deg, fa.data(), d), 2e-6) << format << " degree " << deg;
          }
        }
      }
    }
  }
}

// @playcanvas/splat-transform, a 3DGS tool with its own SH rotation, rotates the same
// splats' colours by the same quaternion to the same numbers.
TEST(CliTransformSplats, SplatTransformAgrees) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const std::vector<Splat> before = random_splats(40, 3, 31);
  const fs::path in = scratch("pc_in.ply"), out = scratch("pc_out.ply"), json = scratch("pc_in.json");
  std::ofstream(in, std::ios::binary) << write_ply(before, 3, "binary_little_endian");
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.3, 0.5, -0.7, 0.2).normalized();
  std::ostringstream quat;
  quat.precision(17);
  quat << q.w() << "," << q.x() << "," << q.y() << "," << q.z();
  const auto r = run_shtool({"transform-splats", in.string(), "--quat", quat.str(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<Splat> after = read_ply(read_file(out), 3, "binary_little_endian", before.size());
  nlohmann::json doc = {{"quat", {q.w(), q.x(), q.y(), q.z()}}, {"rest", nlohmann::json::array()}};
  for (const Splat& s : before) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 3; ++c)
      for (int k = 1; k < 16; ++k) row.push_back(s.sh[c][k]);
    doc["rest"].push_back(row);
  }
  std::ofstream(json) << doc.dump();
  const auto node = run_command({"node", (shtool::test::node_consumers_dir() / "rotate_splat_sh.mjs").string(), json.string()});
  ASSERT_EQ(node.exit_code, 0) << node.err;
  const nlohmann::json theirs = nlohmann::json::parse(node.out);
  ASSERT_EQ(theirs.size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i)
    for (int c = 0; c < 3; ++c)
      for (int k = 1; k < 16; ++k)
        ASSERT_NEAR(after[i].sh[c][k], theirs[i][15 * c + k - 1].get<double>(), 2e-6) << "splat " << i << " channel " << c;
}

TEST(CliTransformSplats, IdentityKeepsTheBytes) {
  for (const std::string format : {"binary_little_endian", "binary_big_endian", "ascii"}) {
    const std::vector<Splat> s = random_splats(100, 3, 5);
    const fs::path in = scratch("id.ply"), out = scratch("id_out.ply");
    std::ofstream(in, std::ios::binary) << write_ply(s, 3, format);
    for (const std::vector<std::string> how : {std::vector<std::string>{"--quat", "1,0,0,0"},
                                               std::vector<std::string>{"--matrix", "1,0,0,0,1,0,0,0,1"}}) {
      std::vector<std::string> argv = {"transform-splats", in.string(), "--out", out.string()};
      argv.insert(argv.end(), how.begin(), how.end());
      const auto r = run_shtool(argv);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_TRUE(read_file(out) == read_file(in)) << format << " " << how[0];
    }
  }
}

TEST(CliTransformSplats, SameBytesWhateverTheThreadCount) {
  const std::vector<Splat> s = random_splats(20000, 3, 9);
  const fs::path in = scratch("threads.ply");
  std::ofstream(in, std::ios::binary) << write_ply(s, 3, "binary_little_endian");
  std::string bytes[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path out = scratch("threads_" + std::to_string(k) + ".ply");
    const auto r = run_shtool({"transform-splats", in.string(), "--quat", "0.5,0.5,-0.5,0.5", "--threads",
                                k ? "3" : "1", "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    bytes[k] = read_file(out);
  }
  EXPECT_EQ(bytes[0], bytes[1]);
}

// The common file (binary in the machine's order, float32) is streamed in pieces of
// records with the SH of several splats at once; big-endian files take the general
// path, one value at a time. Both give the same bits, reflections included.
TEST(CliTransformSplats, StreamedAndGeneralPathsGiveTheSameBits) {
  const std::vector<Splat> s = random_splats(5000, 3, 21);
  const fs::path le = scratch("paths_le.ply"), be = scratch("paths_be.ply");
  std::ofstream(le, std::ios::binary) << write_ply(s, 3, "binary_little_endian");
  std::ofstream(be, std::ios::binary) << write_ply(s, 3, "binary_big_endian");
  for (const std::vector<std::string> how :
       {std::vector<std::string>{"--quat", "0.8,-0.3,0.4,0.33", "--scale", "2", "--translate", "1,2,3"},
        std::vector<std::string>{"--matrix", "0,1,0,1,0,0,0,0,1", "--translate", "-1,0.5,0"}}) {
    std::string bytes[2];
    for (int k = 0; k < 2; ++k) {
      const fs::path out = scratch(k ? "paths_be_out.ply" : "paths_le_out.ply");
      std::vector<std::string> argv = {"transform-splats", (k ? be : le).string(), "--out", out.string()};
      argv.insert(argv.end(), how.begin(), how.end());
      const auto r = run_shtool(argv);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      bytes[k] = read_file(out);
    }
    const std::size_t body[2] = {bytes[0].find("end_header\n") + 11, bytes[1].find("end_header\n") + 11};
    ASSERT_EQ(bytes[0].size() - body[0], bytes[1].size() - body[1]);
    std::string swapped = bytes[1].substr(body[1]);
    for (std::size_t i = 0; i + 4 <= swapped.size(); i += 4) std::swap(swapped[i], swapped[i + 3]), std::swap(swapped[i + 1], swapped[i + 2]);
    EXPECT_TRUE(swapped == bytes[0].substr(body[0])) << how[0];
    // And the values did change.
    EXPECT_FALSE(bytes[0] == read_file(le));
  }
}

// In the streamed path too a value that is not finite, or one the transform takes past
// float32, is refused, the first splat's problem named whatever the threads, nothing written.
TEST(CliTransformSplats, StreamedPathRefusesNonFiniteValues) {
  struct Case {
    std::vector<std::pair<std::size_t, float>> x;  // splat, its x
    std::string message;
  };
  const std::vector<Case> cases = {
      {{{4500, std::nanf("")}}, "splat 4500: 'x' is not finite"},
      {{{4500, INFINITY}, {100, 3e38f}}, "splat 100: 'x' overflows its type after the transform"},
      {{{4500, 3e38f}, {4600, std::nanf("")}}, "splat 4500: 'x' overflows its type after the transform"},
      {{{2100, std::nanf("")}, {4500, 3e38f}}, "splat 2100: 'x' is not finite"},
  };
  for (const Case& c : cases) {
    std::vector<Splat> s = random_splats(5000, 2, 23);
    for (const auto& [i, x] : c.x) s[i].p[0] = x;
    const fs::path in = scratch("nonfinite.ply"), out = scratch("nonfinite_out.ply");
    std::ofstream(in, std::ios::binary) << write_ply(s, 2, "binary_little_endian");
    for (const char* threads : {"1", "3"}) {
      fs::remove(out);
      const auto r = run_shtool({"transform-splats", in.string(), "--quat", "0.6,0.8,0,0", "--scale", "2",
                                  "--threads", threads, "--out", out.string()});
      EXPECT_EQ(r.exit_code, 1) << c.message << ": " << r.err;
      EXPECT_NE(r.err.find(c.message), std::string::npos) << threads << " threads: " << r.err;
      EXPECT_FALSE(fs::exists(out)) << c.message;
    }
  }
}

// Normals are not splat data: one that is not finite is carried (turned) into PLY, as it
// is dropped on the way into spz and glb, in every encoding; a splat value that is not
// finite is refused on every path.
TEST(CliTransformSplats, NonFiniteNormalsAreCarriedSplatValuesRefused) {
  for (const std::string format : {"binary_little_endian", "binary_big_endian", "ascii"}) {
    std::vector<Splat> s = random_splats(50, 1, 29);
    s[3].n[0] = std::nanf("");
    s[7].n[2] = INFINITY;
    const fs::path in = scratch("nan_normal.ply");
    std::ofstream(in, std::ios::binary) << write_ply(s, 1, format);
    for (const std::string ext : {".ply", ".spz", ".glb"}) {
      const fs::path out = scratch("nan_normal_out" + ext);
      fs::remove(out);
      const auto r = run_shtool({"transform-splats", in.string(), "--quat", "0.8,0.6,0,0", "--out", out.string()});
      EXPECT_EQ(r.exit_code, 0) << format << " -> " << ext << ": " << r.err;
      EXPECT_TRUE(fs::exists(out)) << format << " -> " << ext;
    }
    s[5].sh[1][2] = std::nanf("");  // f_rest_4 (G, coefficient 2)
    std::ofstream(in, std::ios::binary | std::ios::trunc) << write_ply(s, 1, format);
    for (const std::string ext : {".ply", ".spz", ".glb"}) {
      const fs::path out = scratch("nan_normal_out" + ext);
      fs::remove(out);
      const auto r = run_shtool({"transform-splats", in.string(), "--quat", "0.8,0.6,0,0", "--out", out.string()});
      EXPECT_EQ(r.exit_code, 1) << format << " -> " << ext << ": " << r.err;
      EXPECT_NE(r.err.find("splat 5"), std::string::npos) << format << " -> " << ext << ": " << r.err;
      EXPECT_FALSE(fs::exists(out)) << format << " -> " << ext;
    }
    // A finite normal that the turn takes past float is not carried as inf: refused into
    // PLY, dropped (as every normal) on the way into spz and glb.
    s = random_splats(50, 1, 29);
    s[6].n = {3e38f, 3e38f, 0};  // 45 degrees about z: ny = 4.2e38
    std::ofstream(in, std::ios::binary | std::ios::trunc) << write_ply(s, 1, format);
    for (const std::string ext : {".ply", ".spz", ".glb"}) {
      const fs::path out = scratch("big_normal_out" + ext);
      fs::remove(out);
      const auto r = run_shtool(
          {"transform-splats", in.string(), "--quat", "0.9238795,0,0,0.3826834", "--out", out.string()});
      if (ext == ".ply") {
        EXPECT_EQ(r.exit_code, 1) << format << ": " << r.err;
        EXPECT_NE(r.err.find("splat 6: 'ny'"), std::string::npos) << format << ": " << r.err;  // nx = 0 after
        EXPECT_NE(r.err.find("overflows its type after the transform"), std::string::npos) << format << ": " << r.err;
        EXPECT_FALSE(fs::exists(out)) << format;
      } else {
        EXPECT_EQ(r.exit_code, 0) << format << " -> " << ext << ": " << r.err;
      }
    }
  }
}

// The messages name the problem: a compressed PLY (SuperSplat's packed layout) is named
// as such; an ASCII value past float's range is the input's, and an overflow under a
// rotation alone does not blame --scale or --translate.
TEST(CliTransformSplats, MessagesNameTheProblem) {
  struct Case {
    std::string name, bytes;
    std::vector<std::string> args;
    std::string ext, message;
  };
  std::string packed = "ply\nformat binary_little_endian 1.0\nelement chunk 1\n";
  for (const char* p : {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"}) packed += std::string("property float ") + p + "\n";
  packed += "element vertex 1\n";
  for (const char* p : {"packed_position", "packed_rotation", "packed_scale", "packed_color"})
    packed += std::string("property uint ") + p + "\n";
  packed += "end_header\n" + std::string(6 * 4 + 4 * 4, '\x01');
  std::vector<Splat> s = random_splats(4, 0, 31);
  std::string ascii = write_ply(s, 0, "ascii");
  const std::size_t line = ascii.find("end_header\n") + 11;
  ascii.replace(line, ascii.find(' ', line) - line, "1e39");  // splat 0's x
  s[2].p = {3e38f, 3e38f, 0};
  const std::string far = write_ply(s, 0, "binary_little_endian");
  const std::string turn = "0.9238795,0,0,0.3826834";  // 45 degrees about z: y -> (x + y) / sqrt(2) = 4.2e38
  const std::vector<Case> cases = {
      {"compressed PLY", packed, {}, ".ply", "a compressed PLY (SuperSplat"},
      {"compressed PLY to spz", packed, {}, ".spz", "which shtool does not support"},
      {"ASCII past float", ascii, {"--quat", turn}, ".ply", "splat 0: 'x' = 1e+39 is past the range of its type, float"},
      {"rotation overflows (streamed)", far, {"--quat", turn}, ".ply", "too close to its type's limit to be rotated"},
      {"rotation overflows (glb)", far, {"--quat", turn}, ".glb", "too close to its type's limit to be rotated"},
      {"scale overflows (glb)", far, {"--scale", "2"}, ".glb", "(--scale or --translate too large"},
  };
  for (const Case& c : cases) {
    const fs::path in = scratch("msg.ply"), out = scratch("msg_out" + c.ext);
    std::ofstream(in, std::ios::binary) << c.bytes;
    fs::remove(out);
    std::vector<std::string> argv = {"transform-splats", in.string(), "--out", out.string()};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    const auto r = run_shtool(argv);
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << ": " << r.err;
    if (c.args.empty() || c.args[0] == "--quat")
      EXPECT_EQ(r.err.find("--scale"), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
}

// ASCII values are read as C's strtod reads them (PLY writers print with printf): a
// leading '+' is a sign, so "+1.5" is the scene "1.5" is; a second sign is no number.
TEST(CliTransformSplats, AsciiValuesMayCarryAPlusSign) {
  const std::string plain = write_ply(random_splats(3, 1, 37), 1, "ascii");
  const std::size_t body = plain.find("end_header\n") + 11;
  auto with_first_value = [&](const std::string& text) {
    std::string b = plain;
    b.replace(body, b.find(' ', body) - body, text);  // splat 0's x
    return b;
  };
  std::string outputs[2];
  for (int k = 0; k < 2; ++k) {
    const fs::path in = scratch("plus.ply"), out = scratch("plus_out.glb");
    std::ofstream(in, std::ios::binary) << with_first_value(k ? "+1.5" : "1.5");
    const auto r = run_shtool({"transform-splats", in.string(), "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    outputs[k] = read_file(out);
  }
  EXPECT_TRUE(outputs[0] == outputs[1]);
  for (const std::string bad : {"+-1.5", "++1.5", "+"}) {
    const fs::path in = scratch("plus.ply"), out = scratch("plus_out.glb");
    std::ofstream(in, std::ios::binary) << with_first_value(bad);
    fs::remove(out);
    const auto r = run_shtool({"transform-splats", in.string(), "--out", out.string()});
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_NE(r.err.find("'" + bad + "' in element 'vertex' is not a number"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << bad;
  }
}

TEST(CliTransformSplats, BadInputIsAnErrorWithNoOutput) {
  const std::string good = write_ply(random_splats(10, 1, 3), 1, "binary_little_endian");
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  struct Case {
    std::string name, bytes;
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"truncated body", good.substr(0, good.size() - 7), {}, "ends before"},
      {"extra bytes", good + "xyz", {}, "after the last element"},
      {"no x", replace("property float x\n", "property float u\n"), {}, "'x'"},
      {"wrong f_rest count", replace("property float f_rest_8\n", "property float other\n"), {}, "f_rest"},
      {"integer f_rest", replace("property float f_rest_0\n", "property int f_rest_0\n"), {}, "float"},
      {"list property", replace("end_header", "element face 0\nproperty list uchar int vertex_indices\nend_header"), {},
       "list"},
      {"not a PLY", "hello\n", {}, "not a PLY"},
      // A count whose product with the property count wraps around 2^64.
      {"huge ASCII count", "ply\nformat ascii 1.0\nelement vertex 4611686018427387904\nproperty float x\n"
                           "property float y\nproperty float z\nproperty float opacity\nend_header\n", {}, "more than the body"},
      {"end_header in a comment", "ply\nformat ascii 1.0\ncomment end_header\n", {}, "end_header"},
      {"not orthogonal", good, {"--matrix", "1,0,0,0,2,0,0,0,1"}, "orthogonal"},
      {"zero quaternion", good, {"--quat", "0,0,0,0"}, "non-zero"},
      {"both", good, {"--quat", "1,0,0,0", "--matrix", "1,0,0,0,1,0,0,0,1"}, "exactly one"},
      {"negative scale", good, {"--quat", "1,0,0,0", "--scale", "-1"}, "--scale"},
  };
  for (const Case& c : cases) {
    const fs::path in = scratch("bad.ply"), out = scratch("bad_out.ply");
    std::ofstream(in, std::ios::binary) << c.bytes;
    fs::remove(out);
    std::vector<std::string> argv = {"transform-splats", in.string(), "--out", out.string()};
    if (c.args.empty()) argv.insert(argv.end(), {"--quat", "1,0,0,0"});
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    const auto r = run_shtool(argv);
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
}

}  // namespace
