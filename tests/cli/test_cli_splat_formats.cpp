// transform-splats between formats (.ply, .spz v3/v4, .glb, .gltf): round trips keep
// every splat within its format's quantisation; colours seen along d before are the
// colours along M d after, for rotations and for a reflecting frame change (3DGS's
// eval_sh, written here from the reference implementation); spz files written by hand
// decode to the values the specification gives; @playcanvas/splat-transform reads what
// shtool writes and shtool reads what it writes; the glTF outputs pass the Khronos
// validator; bad files are refused with nothing written.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Dense>

#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "eval_3dgs.h"
#include "node_consumers.h"

namespace {

using namespace shtool::test;

const Scratch scratch("splat_formats");

constexpr double kPi = 3.14159265358979323846;
constexpr double C0 = 0.28209479177387814;  // y_0^0, the DC colour scale of 3DGS

// A splat as the reference PLY holds it; sh[c][k], k = 0 the DC.
struct Splat {
  Eigen::Vector3d p, log_scale;
  Eigen::Vector4d rot;  // w x y z
  double opacity = 0;
  std::array<std::vector<double>, 3> sh;

  Eigen::Matrix3d rotation() const {
    return Eigen::Quaterniond(rot[0], rot[1], rot[2], rot[3]).normalized().toRotationMatrix();
  }
  Eigen::Matrix3d covariance() const {
    const Eigen::Vector3d s = log_scale.array().exp();
    const Eigen::Matrix3d r = rotation();
    return r * s.cwiseAbs2().asDiagonal() * r.transpose();
  }
  int degree() const { return static_cast<int>(std::lround(std::sqrt(double(sh[0].size())))) - 1; }
  double colour(int c, const Eigen::Vector3d& d) const { return eval_3dgs(degree(), sh[c].data(), d); }
};

struct Scene {
  int degree = 0;
  std::vector<Splat> splats;
};

// Values inside every format's range: positions within spz's fixed point, log-scales
// within [-10, 5.9], SH within spz's [-1, 1] under any rotation (a rotated coefficient
// is at most its band's norm, sqrt(7) 0.34 < 0.9 at degree 3; spz clips beyond 1).
Scene random_scene(std::size_t count, int degree, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-1, 1);
  Scene s;
  s.degree = degree;
  s.splats.resize(count);
  for (Splat& x : s.splats) {
    x.p = Eigen::Vector3d(3 * g(rng), 3 * g(rng), 3 * g(rng));
    x.log_scale = Eigen::Vector3d(u(rng) * 3 - 4, u(rng) * 3 - 4, u(rng) * 3 - 4);
    x.rot = Eigen::Vector4d(g(rng), g(rng), g(rng), g(rng));
    x.opacity = 2 * g(rng);
    for (auto& c : x.sh) {
      c.resize((degree + 1) * (degree + 1));
      c[0] = u(rng) * 2;
      for (std::size_t k = 1; k < c.size(); ++k) c[k] = 0.34 * u(rng);
    }
  }
  return s;
}

std::string ply_bytes(const Scene& s) {
  const int rest = (s.degree + 1) * (s.degree + 1) - 1;
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\nelement vertex " << s.splats.size() << "\n"
    << ply_3dgs_properties(s.degree) << "end_header\n";
  std::string out = h.str();
  auto put = [&](double v) {
    const float f = static_cast<float>(v);
    out.append(reinterpret_cast<const char*>(&f), 4);
  };
  for (const Splat& x : s.splats) {
    for (int k = 0; k < 3; ++k) put(x.p[k]);
    for (int k = 0; k < 3; ++k) put(0);
    for (int c = 0; c < 3; ++c) put(x.sh[c][0]);
    for (int c = 0; c < 3; ++c)
      for (int k = 1; k <= rest; ++k) put(x.sh[c][k]);
    put(x.opacity);
    for (int k = 0; k < 3; ++k) put(x.log_scale[k]);
    for (int k = 0; k < 4; ++k) put(x.rot[k]);
  }
  return out;
}

// Any 3DGS PLY with float properties, binary little endian (what shtool and
// splat-transform write), properties found by name.
Scene read_ply(const fs::path& path) {
  const std::string bytes = read_file(path);
  const std::size_t body = bytes.find("end_header\n") + 11;
  std::istringstream header(bytes.substr(0, body));
  std::string line;
  std::vector<std::string> names;
  std::size_t count = 0;
  while (std::getline(header, line)) {
    std::istringstream w(line);
    std::string a, b, c;
    w >> a >> b >> c;
    if (a == "element" && b == "vertex") count = std::stoul(c);
    if (a == "property") {
      EXPECT_EQ(b, "float") << line;
      names.push_back(c);
    }
  }
  auto index = [&](const std::string& n) -> int {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return static_cast<int>(i);
    return -1;
  };
  int rest = 0;
  while (index("f_rest_" + std::to_string(rest)) >= 0) ++rest;
  Scene s;
  s.degree = rest == 0 ? 0 : rest == 9 ? 1 : rest == 24 ? 2 : 3;
  const int k_rest = rest / 3;
  s.splats.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    auto get = [&](const std::string& n) {
      float f;
      std::memcpy(&f, bytes.data() + body + (i * names.size() + index(n)) * 4, 4);
      return static_cast<double>(f);
    };
    Splat& x = s.splats[i];
    for (int k = 0; k < 3; ++k) {
      x.p[k] = get(std::string(1, "xyz"[k]));
      x.log_scale[k] = get("scale_" + std::to_string(k));
    }
    for (int k = 0; k < 4; ++k) x.rot[k] = get("rot_" + std::to_string(k));
    x.opacity = get("opacity");
    for (int c = 0; c < 3; ++c) {
      x.sh[c].resize(k_rest + 1);
      x.sh[c][0] = get("f_dc_" + std::to_string(c));
      for (int k = 0; k < k_rest; ++k) x.sh[c][k + 1] = get("f_rest_" + std::to_string(c * k_rest + k));
    }
  }
  return s;
}

void write_bytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

CommandResult convert(const fs::path& in, const fs::path& out, std::vector<std::string> more = {}) {
  std::vector<std::string> argv = {"transform-splats", in.string(), "--out", out.string()};
  argv.insert(argv.end(), more.begin(), more.end());
  return run_shtool(argv);
}

// A refused conversion: exit 1, `message` in the error, and no output (`out` is removed
// first, so a file left by an earlier case does not count).
void expect_refused(const fs::path& in, const fs::path& out, const std::string& message,
                    std::vector<std::string> more = {}) {
  fs::remove(out);
  const auto r = convert(in, out, std::move(more));
  EXPECT_EQ(r.exit_code, 1) << message << ": " << r.err;
  EXPECT_NE(r.err.find(message), std::string::npos) << message << " not in: " << r.err;
  EXPECT_FALSE(fs::exists(out)) << message;
}

// A file's values as stored (no frame change on the way to PLY).
Scene raw_values(const fs::path& file) {
  const fs::path ply = scratch("raw_" + file.filename().string() + ".ply");
  const auto r = convert(file, ply, {"--frame", "RUB", "--spz-frame", "RUB"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return read_ply(ply);
}

std::vector<Eigen::Vector3d> directions(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Eigen::Vector3d> d(64);
  for (auto& v : d) v = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  return d;
}

double sigmoid(double x) { return 1 / (1 + std::exp(-x)); }

// Quantisation of a format (0: float): the largest errors of one value.
struct Tolerance {
  double position = 1e-5, log_scale = 1e-5, alpha = 1e-6, covariance = 1e-5, colour = 1e-5;
};
// spz at the default bits: positions half of 2^-12; log-scales half of 1/16; alpha half
// of 1/255; the smallest-three rotation's components within 0.7071/511/2; the colour
// bound of docs/splats.md: DC 0.5/(0.15*255)*C0 plus sum_l e_l (2l+1)/sqrt(4 pi).
Tolerance spz_tolerance(int degree) {
  Tolerance t;
  t.position = std::ldexp(1.0, -13) + 1e-5;
  t.log_scale = 1.0 / 32 + 1e-5;
  t.alpha = 0.5 / 255 + 1e-6;
  t.covariance = 0.01;
  t.colour = 0.5 / (0.15 * 255) * C0 + 1e-6;
  for (int l = 1; l <= degree; ++l) t.colour += ((l == 1 ? 4 : 8) + 0.5) / 128 * (2 * l + 1) / std::sqrt(4 * kPi);
  return t;
}
Tolerance combine(const Tolerance& a, const Tolerance& b) {
  return {a.position + b.position, a.log_scale + b.log_scale, a.alpha + b.alpha, a.covariance + b.covariance,
          a.colour + b.colour};
}

// after = s M before + u (positions p -> s M p + u, log-scales + log s, orientations and
// SH by M, orthogonal), within t. Covariances are compared with the scales of `after` on
// both sides so that the rotation's own error is measured, relative to the largest
// variance.
void expect_moved(const Scene& before, const Scene& after, const Eigen::Matrix3d& m, double scale,
                  const Eigen::Vector3d& u, const Tolerance& t, const std::string& what) {
  ASSERT_EQ(before.splats.size(), after.splats.size()) << what;
  ASSERT_EQ(before.degree, after.degree) << what;
  const std::vector<Eigen::Vector3d> dirs = directions(5);
  double worst_colour = 0;
  for (std::size_t i = 0; i < before.splats.size(); ++i) {
    const Splat &a = before.splats[i], &b = after.splats[i];
    ASSERT_LT((scale * (m * a.p) + u - b.p).cwiseAbs().maxCoeff(), t.position) << what << " splat " << i;
    ASSERT_LT((a.log_scale.array() + std::log(scale) - b.log_scale.array()).abs().maxCoeff(), t.log_scale)
        << what << " splat " << i;
    ASSERT_LT(std::abs(sigmoid(a.opacity) - sigmoid(b.opacity)), t.alpha) << what << " splat " << i;
    Splat a_scaled = a;
    a_scaled.log_scale = b.log_scale;
    const Eigen::Matrix3d ca = m * a_scaled.covariance() * m.transpose(), cb = b.covariance();
    const double biggest = b.log_scale.array().exp().square().maxCoeff();
    ASSERT_LT((ca - cb).cwiseAbs().maxCoeff(), t.covariance * biggest) << what << " splat " << i;
    for (const Eigen::Vector3d& d : dirs)
      for (int c = 0; c < 3; ++c) {
        const double e = std::abs(a.colour(c, d) - b.colour(c, m * d));
        worst_colour = std::max(worst_colour, e);
        ASSERT_LT(e, t.colour) << what << " splat " << i << " channel " << c;
      }
  }
  std::cout << what << ": largest colour change " << worst_colour << " (allowed " << t.colour << ")\n";
}
void expect_mapped(const Scene& before, const Scene& after, const Eigen::Matrix3d& m, const Tolerance& t,
                   const std::string& what) {
  expect_moved(before, after, m, 1, Eigen::Vector3d::Zero(), t, what);
}

// The frames of the formats, as matrices from the file's axes to shtool's (RFU): PLY
// RDF by default, spz RUB, glTF RUB.
const Eigen::Matrix3d kRdf = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished();
const Eigen::Matrix3d kRub = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, -1, 0, 1, 0).finished();

struct Format {
  std::string name, ext;
  std::vector<std::string> args;  // when writing it
  Eigen::Matrix3d frame;
  bool quantised;

  // transform-splats from `in` to `out` in this format, with `more` options.
  CommandResult write(const fs::path& in, const fs::path& out, std::vector<std::string> more = {}) const {
    more.insert(more.end(), args.begin(), args.end());
    return convert(in, out, more);
  }
  // What `out`, written by write(), holds: a PLY as read, anything else as stored.
  Scene stored(const fs::path& out) const { return name == "ply" ? read_ply(out) : raw_values(out); }
};
const std::vector<Format>& formats() {
  static const std::vector<Format> f = {
      {"ply", ".ply", {}, kRdf, false},
      {"spz4", ".spz", {}, kRub, true},
      {"spz3", ".spz", {"--spz-version", "3"}, kRub, true},
      {"glb", ".glb", {}, kRub, false},
      {"gltf", ".gltf", {}, kRub, false},
  };
  return f;
}

}  // namespace

// PLY -> A -> B -> PLY for every pair: every value within the quantisation of the spz
// steps, and the frames undone exactly (the identity overall).
TEST(CliSplatFormats, RoundTripsEveryPair) {
  const Scene scene = random_scene(1000, 3, 17);
  const fs::path in = scratch("pairs_in.ply");
  write_bytes(in, ply_bytes(scene));
  for (const Format& a : formats())
    for (const Format& b : formats()) {
      if (a.name == "ply" && b.name == "ply") continue;
      const fs::path fa = scratch("pair_a_" + a.name + a.ext), fb = scratch("pair_b_" + b.name + b.ext),
                     back = scratch("pair_back.ply");
      auto r = convert(in, fa, a.args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      r = convert(fa, fb, b.args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      r = convert(fb, back);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      Tolerance t;
      if (a.quantised) t = combine(t, spz_tolerance(3));
      if (b.quantised) t = combine(t, spz_tolerance(3));
      expect_mapped(scene, read_ply(back), Eigen::Matrix3d::Identity(), t, a.name + " -> " + b.name);
    }
}

// What each format stores is the scene in that format's frame: PLY (RDF) to spz or glTF
// (RUB) turns it by Q = RUB^-1 RDF = diag(1, -1, -1), a half turn about x.
TEST(CliSplatFormats, EachFormatStoresItsFrame) {
  const Scene scene = random_scene(300, 3, 23);
  const fs::path in = scratch("frame_in.ply");
  write_bytes(in, ply_bytes(scene));
  for (const Format& f : formats()) {
    if (f.name == "ply") continue;
    const fs::path out = scratch("frame_out" + f.ext);
    const auto r = f.write(in, out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Eigen::Matrix3d q = f.frame.transpose() * kRdf;
    EXPECT_TRUE(q.isApprox(Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix()));
    Tolerance t = f.quantised ? spz_tolerance(3) : Tolerance{};
    expect_mapped(scene, raw_values(out), q, t, "ply -> " + f.name + " (raw)");
  }
}

// A rotation given in the input's coordinates, with scale and translation, into each
// format; and a frame change that reflects (a left-handed PLY, Unity's RUF, into glTF's
// RUB): colours along d before are colours along M d after (64 directions, 1000 splats).
TEST(CliSplatFormats, ColoursFollowRotationsAndReflections) {
  const Scene scene = random_scene(1000, 3, 29);
  const fs::path in = scratch("rot_in.ply");
  write_bytes(in, ply_bytes(scene));
  const Eigen::Quaterniond qr = Eigen::Quaterniond(0.8, -0.3, 0.4, 0.33).normalized();
  std::ostringstream quat;
  quat.precision(17);
  quat << qr.w() << "," << qr.x() << "," << qr.y() << "," << qr.z();
  for (const Format& f : formats()) {
    const fs::path out = scratch("rot_out" + f.ext);
    const auto r = f.write(in, out, {"--quat", quat.str()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Eigen::Matrix3d m = f.frame.transpose() * kRdf * qr.toRotationMatrix();
    expect_mapped(scene, f.stored(out), m, f.quantised ? spz_tolerance(3) : Tolerance{}, "rotated into " + f.name);
  }
  // Reflection: the PLY's axes are RUF (left-handed); glTF's RUB: z flips.
  for (const std::string ext : {".glb", ".spz"}) {
    const fs::path out = scratch("mirror_out" + ext);
    const auto r = convert(in, out, {"--frame", "RUF", "--quat", quat.str()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("reflects"), std::string::npos) << r.err;
    const Eigen::Matrix3d ruf = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, 1, 0).finished();
    const Eigen::Matrix3d m = kRub.transpose() * ruf * qr.toRotationMatrix();
    EXPECT_NEAR(m.determinant(), -1, 1e-12);
    expect_mapped(scene, raw_values(out), m, ext == ".spz" ? spz_tolerance(3) : Tolerance{}, "reflected into " + ext);
  }
}

// A reflecting --matrix (det -1: a rotation times a mirror through a generic plane), in
// the input's coordinates, into every format: PLY in place, spz, glTF. Colours along d
// before are colours along M d after (64 directions, 1000 splats), covariances are
// M Sigma M^T with the orientation a proper rotation.
TEST(CliSplatFormats, ReflectingMatrix) {
  const Scene scene = random_scene(1000, 3, 31);
  const fs::path in = scratch("mirror_matrix_in.ply");
  write_bytes(in, ply_bytes(scene));
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity() - 2 * n * n.transpose();
  const Eigen::Matrix3d m = Eigen::Quaterniond(0.8, -0.3, 0.4, 0.33).normalized().toRotationMatrix() * mirror;
  ASSERT_NEAR(m.determinant(), -1, 1e-12);
  std::ostringstream text;
  text.precision(17);
  for (int k = 0; k < 9; ++k) text << (k ? "," : "") << m(k / 3, k % 3);
  for (const Format& f : formats()) {
    const fs::path out = scratch("mirror_matrix_out" + f.ext);
    const auto r = f.write(in, out, {"--matrix", text.str()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("reflects"), std::string::npos) << r.err;
    const Eigen::Matrix3d frame = f.frame.transpose() * kRdf;
    const Scene after = f.stored(out);
    expect_mapped(scene, after, frame * m, f.quantised ? spz_tolerance(3) : Tolerance{}, "mirrored into " + f.name);
    for (const Splat& x : after.splats) ASSERT_NEAR(x.rotation().determinant(), 1, 1e-6);
  }
  // PLY to PLY through the scene (--sh-degree) rather than in place: the same values.
  const fs::path out = scratch("mirror_matrix_scene.ply");
  const auto r = convert(in, out, {"--matrix", text.str(), "--sh-degree", "3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_mapped(scene, read_ply(out), m, Tolerance{}, "mirrored through the scene");
}

// glTF node transforms over the splat mesh, composed down the hierarchy: a parent with a
// rotation and a translation, the mesh's node with a rotation and a uniform scale; then a
// reflecting matrix node. The splats read are the scene moved by the composed similarity
// (colours along d before = along R d after, covariances s^2 R Sigma R^T); a
// non-uniform scale is refused.
TEST(CliSplatFormats, GltfNodeTransformsAreApplied) {
  const Scene scene = random_scene(1000, 3, 37);
  const fs::path in = scratch("node_in.ply"), gltf = scratch("node_plain.gltf");
  write_bytes(in, ply_bytes(scene));
  // No frame change anywhere: the file's values are the PLY's.
  ASSERT_EQ(convert(in, gltf, {"--frame", "RUB"}).exit_code, 0);
  const nlohmann::json plain = nlohmann::json::parse(read_file(gltf));
  ASSERT_EQ(plain["nodes"].size(), 1u);
  const Eigen::Quaterniond q1 = Eigen::Quaterniond(0.9, 0.2, -0.3, 0.1).normalized(),
                          q2 = Eigen::Quaterniond(0.4, -0.6, 0.5, 0.3).normalized();
  const double s = 1.75;
  const Eigen::Vector3d t1(0.5, -2, 3.25), t2(1, 0.25, -0.5);
  auto with_nodes = [&](const nlohmann::json& nodes, const std::string& name) {
    nlohmann::json g = plain;
    g["nodes"] = nodes;
    g["scenes"][0]["nodes"] = {0};
    const fs::path p = scratch(name);
    write_bytes(p, g.dump());
    return p;
  };
  {
    const nlohmann::json nodes = {
        {{"children", {1}}, {"rotation", {q1.x(), q1.y(), q1.z(), q1.w()}}, {"translation", {t1[0], t1[1], t1[2]}}},
        {{"mesh", 0}, {"rotation", {q2.x(), q2.y(), q2.z(), q2.w()}}, {"scale", {s, s, s}}, {"translation", {t2[0], t2[1], t2[2]}}}};
    const fs::path moved = with_nodes(nodes, "node_trs.gltf"), back = scratch("node_trs_back.ply");
    const auto r = convert(moved, back, {"--frame", "RUB"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Eigen::Matrix3d r1 = q1.toRotationMatrix(), r2 = q2.toRotationMatrix();
    Tolerance t;
    t.position = 1e-4;  // float positions of magnitude ~20
    expect_moved(scene, read_ply(back), r1 * r2, s, r1 * t2 + t1, t, "glTF node TRS");
  }
  {
    // A matrix node (column-major) that reflects: mirror z, rotate, scale 0.5, translate.
    Eigen::Matrix4d w = Eigen::Matrix4d::Identity();
    const Eigen::Matrix3d m = q1.toRotationMatrix() * Eigen::Vector3d(1, 1, -1).asDiagonal();
    w.topLeftCorner<3, 3>() = 0.5 * m;
    w.topRightCorner<3, 1>() = t1;
    nlohmann::json matrix = nlohmann::json::array();
    for (int k = 0; k < 16; ++k) matrix.push_back(w(k % 4, k / 4));
    const fs::path moved = with_nodes({{{"mesh", 0}, {"matrix", matrix}}}, "node_matrix.gltf"),
                   back = scratch("node_matrix_back.ply");
    const auto r = convert(moved, back, {"--frame", "RUB"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_moved(scene, read_ply(back), m, 0.5, t1, Tolerance{}, "glTF node matrix, reflecting");
  }
  {
    const fs::path moved = with_nodes({{{"mesh", 0}, {"scale", {1, 2, 1}}}}, "node_stretch.gltf"),
                   back = scratch("node_stretch_back.ply");
    fs::remove(back);
    const auto r = convert(moved, back);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("non-uniform scale"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(back));
  }
}

// --sh-degree keeps the bands up to D as they are (the L2-nearest function of that
// degree) and pads missing bands with zeros.
TEST(CliSplatFormats, ShDegree) {
  const Scene scene = random_scene(200, 3, 31);
  const fs::path in = scratch("deg_in.ply"), out = scratch("deg_out.ply"), up = scratch("deg_up.ply");
  write_bytes(in, ply_bytes(scene));
  auto r = convert(in, out, {"--sh-degree", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Scene low = read_ply(out);
  ASSERT_EQ(low.degree, 1);
  for (std::size_t i = 0; i < scene.splats.size(); ++i)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 4; ++k) ASSERT_EQ(low.splats[i].sh[c][k], static_cast<float>(scene.splats[i].sh[c][k]));
  r = convert(out, up, {"--sh-degree", "3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Scene high = read_ply(up);
  ASSERT_EQ(high.degree, 3);
  for (std::size_t i = 0; i < scene.splats.size(); ++i)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 16; ++k) ASSERT_EQ(high.splats[i].sh[c][k], k < 4 ? low.splats[i].sh[c][k] : 0.0);
}

namespace {

void put24(std::string& s, std::int32_t v) {
  for (int b = 0; b < 3; ++b) s.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
}
void put32(std::string& s, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) s.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
}
void put64(std::string& s, std::uint64_t v) {
  put32(s, static_cast<std::uint32_t>(v));
  put32(s, static_cast<std::uint32_t>(v >> 32));
}

// Two splats of degree 1 by the specification's encodings, block by block: positions,
// alphas, colours, scales, rotations (v2: 3 bytes, v3+: 4), SH.
std::array<std::string, 6> hand_blocks(int version) {
  std::array<std::string, 6> b;
  put24(b[0], 4096), put24(b[0], -2048), put24(b[0], 1);  // (1, -0.5, 2^-12) at 12 bits
  put24(b[0], -1), put24(b[0], 0), put24(b[0], 8388607);  // (-2^-12, 0, 2048 - 2^-12)
  b[1] = std::string("\xbf\x00", 2);                       // alpha 191/255, then 0 (bucket edge 0.5/255)
  b[2] = std::string("\xa6\x80\x00\xff\x7f\x80", 6);       // colour bytes
  b[3] = std::string("\x80\x90\x00\xff\xa0\x70", 6);       // log-scales byte/16 - 10
  if (version == 2) {
    b[4] = std::string("\x80\x80\x80\xff\x80\x80", 6);  // (0,0,0)+w -> identity; x = 1 -> (1,0,0,0)
  } else {
    put32(b[4], 3u << 30);  // largest w, others 0: identity
    // largest x (index 0); y = +mag 511 (0.7071), z = 0, w = -0 ... : comp = 0, then y, z, w
    put32(b[4], (((0u << 10 | 511u) << 10 | 0u) << 10) | 0u);
  }
  // SH: per splat, coefficient-major, RGB inner: 3 coefficients x 3 channels.
  b[5] = std::string("\x80\xc0\x40\x00\xff\x80\x80\x80\x80", 9);
  b[5] += std::string("\x88\x80\x80\x80\x78\x80\x80\x80\x90", 9);
  return b;
}

std::string legacy_payload(int version) {
  std::string s;
  put32(s, 0x5053474e), put32(s, static_cast<std::uint32_t>(version)), put32(s, 2);
  s += std::string("\x01\x0c\x00\x00", 4);  // degree 1, 12 fractional bits, flags, reserved
  for (const std::string& b : hand_blocks(version)) s += b;
  return s;
}

std::string compress_with(const std::string& tool, const std::string& plain) {
  const fs::path p = scratch("plain.bin");
  write_bytes(p, plain);
  fs::remove(scratch(tool == "gzip" ? "plain.bin.gz" : "plain.bin.zst"));
  const auto r = run_command({tool, "-q", "-k", "-f", p.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return read_file(scratch(tool == "gzip" ? "plain.bin.gz" : "plain.bin.zst"));
}

std::string hand_v4() {
  const std::array<std::string, 6> b = hand_blocks(4);
  std::vector<std::string> z;
  for (const std::string& x : b) z.push_back(compress_with("zstd", x));
  std::string s;
  put32(s, 0x5053474e), put32(s, 4), put32(s, 2);
  s += std::string("\x01\x0c\x00\x06", 4);  // degree 1, 12 bits, flags, 6 streams
  put32(s, 32);
  s.append(12, '\0');
  for (int k = 0; k < 6; ++k) put64(s, z[k].size()), put64(s, b[k].size());
  for (const std::string& x : z) s += x;
  return s;
}

}  // namespace

// spz files built here from the specification's encodings (gzip and zstd by their own
// command-line tools) decode to the values it gives.
TEST(CliSplatFormats, HandWrittenSpzDecodes) {
  const std::vector<std::pair<int, std::string>> files = {{2, compress_with("gzip", legacy_payload(2))},
                                                          {3, compress_with("gzip", legacy_payload(3))},
                                                          {4, hand_v4()}};
  for (const auto& [version, bytes] : files) {
    const fs::path spz = scratch("hand.spz"), ply = scratch("hand.ply");
    write_bytes(spz, bytes);
    const auto r = convert(spz, ply, {"--spz-frame", "RDF"});  // PLY's frame: values as stored
    ASSERT_EQ(r.exit_code, 0) << "version " << version << ": " << r.err;
    const Scene s = read_ply(ply);
    ASSERT_EQ(s.splats.size(), 2u);
    ASSERT_EQ(s.degree, 1);
    const Splat &a = s.splats[0], &b = s.splats[1];
    EXPECT_EQ(a.p, Eigen::Vector3d(1, -0.5, 1.0 / 4096));
    EXPECT_EQ(b.p, Eigen::Vector3d(-1.0 / 4096, 0, 2048 - 1.0 / 4096));
    EXPECT_NEAR(a.opacity, std::log(191.0 / 64), 1e-6);
    EXPECT_NEAR(b.opacity, std::log(0.5 / 254.5), 1e-5);
    const double colour[6] = {0xa6, 0x80, 0x00, 0xff, 0x7f, 0x80};
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(a.sh[c][0], (colour[c] / 255 - 0.5) / 0.15, 1e-6);
      EXPECT_NEAR(b.sh[c][0], (colour[3 + c] / 255 - 0.5) / 0.15, 1e-6);
    }
    EXPECT_EQ(a.log_scale, Eigen::Vector3d(-2, -1, -10));
    EXPECT_EQ(b.log_scale, Eigen::Vector3d(255.0 / 16 - 10, 0, -3));
    if (version == 2) {
      // Bytes 0x80 decode to 128/127.5 - 1 (v2 cannot store 0); w = sqrt(1 - |xyz|^2).
      const double e = 128.0 / 127.5 - 1;
      EXPECT_NEAR(a.rot[0], std::sqrt(1 - 3 * e * e), 1e-6);
      for (int k = 1; k < 4; ++k) EXPECT_NEAR(a.rot[k], e, 1e-6);
      EXPECT_EQ(b.rot[0], 0);
      EXPECT_EQ(b.rot[1], 1);
      EXPECT_NEAR(b.rot[2], e, 1e-6);
    } else {
      EXPECT_EQ(a.rot, Eigen::Vector4d(1, 0, 0, 0)) << "version " << version;
      // x the largest (recovered as sqrt(1 - y^2)), y = 0.7071.
      EXPECT_NEAR(b.rot[2], std::sqrt(0.5), 1e-6);
      EXPECT_NEAR(b.rot[1], std::sqrt(0.5), 1e-6);
      EXPECT_EQ(b.rot[0], 0);
      EXPECT_EQ(b.rot[3], 0);
    }
    // SH bytes (x - 128) / 128, coefficient k, channel c at byte 3k + c.
    const unsigned char sh0[9] = {0x80, 0xc0, 0x40, 0x00, 0xff, 0x80, 0x80, 0x80, 0x80};
    const unsigned char sh1[9] = {0x88, 0x80, 0x80, 0x80, 0x78, 0x80, 0x80, 0x80, 0x90};
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(a.sh[c][1 + k], (sh0[3 * k + c] - 128.0) / 128);
        EXPECT_EQ(b.sh[c][1 + k], (sh1[3 * k + c] - 128.0) / 128);
      }
  }
}

// The bytes shtool writes for a known splat (v4, then v3 inflated): the header and every
// block as the specification encodes them.
TEST(CliSplatFormats, SpzWriterBytes) {
  Scene s = random_scene(1, 1, 3);
  Splat& x = s.splats[0];
  // In RUB, the spz's frame, from a PLY read as RUB too (no frame change).
  x.p = Eigen::Vector3d(1, -0.5, 0.25);
  x.log_scale = Eigen::Vector3d(-2, -1, 0.03);
  x.rot = Eigen::Vector4d(2, 0, 0, 0);  // w = 2: normalised to the identity
  x.opacity = 0;
  for (int c = 0; c < 3; ++c) x.sh[c] = {0.2, 0.5, -0.5, 0.01};
  const fs::path in = scratch("bytes_in.ply"), out = scratch("bytes_out.spz");
  write_bytes(in, ply_bytes(s));
  const auto r = convert(in, out, {"--frame", "RUB", "--spz-version", "3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string gz = read_file(out);
  ASSERT_GE(gz.size(), 2u);
  EXPECT_EQ(static_cast<unsigned char>(gz[0]), 0x1f);
  write_bytes(scratch("bytes_out.gz"), gz);
  fs::remove(scratch("bytes_out"));
  ASSERT_EQ(run_command({"gzip", "-d", "-k", "-f", scratch("bytes_out.gz").string()}).exit_code, 0);
  const std::string p = read_file(scratch("bytes_out"));
  std::string want;
  put32(want, 0x5053474e), put32(want, 3), put32(want, 1);
  want += std::string("\x01\x0c\x00\x00", 4);
  put24(want, 4096), put24(want, -2048), put24(want, 1024);
  want.push_back('\x80');  // sigmoid(0) * 255 = 127.5 -> 128
  // round(0.2 * 0.15 * 255 + 127.5) = round(135.15) = 135
  want += std::string("\x87\x87\x87", 3);
  // round((s + 10) * 16): 128, 144, round(160.48) = 160
  want += std::string("\x80\x90\xa0", 3);
  put32(want, 3u << 30);
  // SH band 1 at 5 bits (bucket 8): 0.5 -> 192; -0.5 -> 64; 0.01 -> round(1.28) = 1 + 128 = 129 -> 128.
  for (int c = 0; c < 3; ++c) want.push_back('\xc0');
  for (int c = 0; c < 3; ++c) want.push_back('\x40');
  for (int c = 0; c < 3; ++c) want.push_back('\x80');
  EXPECT_EQ(p, want);
  EXPECT_NE(r.err.find("spz quantisation"), std::string::npos) << r.err;
}

// SH coefficients far past spz's [-1, 127/128] saturate at the end bytes, whatever their
// size (128 x would overflow an int past 2^24).
TEST(CliSplatFormats, SpzShSaturates) {
  Scene s = random_scene(1, 1, 5);
  for (int c = 0; c < 3; ++c) s.splats[0].sh[c] = {0.2, 3e9, -3e9, 2.0};
  const fs::path in = scratch("sat_in.ply");
  write_bytes(in, ply_bytes(s));
  for (const std::string version : {"4", "3"}) {
    const fs::path out = scratch("sat_out.spz");
    const auto r = convert(in, out, {"--frame", "RUB", "--spz-version", version});  // no frame change
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Scene back = raw_values(out);
    ASSERT_EQ(back.splats.size(), 1u);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(back.splats[0].sh[c][1], 127.0 / 128) << "3e9, channel " << c << ", v" << version;
      EXPECT_EQ(back.splats[0].sh[c][2], -1.0) << "-3e9, channel " << c << ", v" << version;
      EXPECT_EQ(back.splats[0].sh[c][3], 127.0 / 128) << "2, channel " << c << ", v" << version;
    }
  }
}

namespace {

// An spz extension record: [u32 type][u32 byteLength][payload].
std::string spz_record(std::uint32_t type, const std::string& payload) {
  std::string s;
  put32(s, type), put32(s, static_cast<std::uint32_t>(payload.size()));
  return s + payload;
}
std::string u32_bytes(std::uint32_t v) {
  std::string s;
  put32(s, v);
  return s;
}
// A gzip stream (a v3 spz file) inflated by gzip itself, through scratch file `name`;
// empty when gzip refuses it.
std::string gunzip(const std::string& gz, const std::string& name) {
  write_bytes(scratch(name + ".gz"), gz);
  fs::remove(scratch(name));
  if (run_command({"gzip", "-d", "-k", "-f", scratch(name + ".gz").string()}).exit_code != 0) return {};
  return read_file(scratch(name));
}
// A v4 file with `records` between its header and its table of contents (flag 0x2).
std::string with_records_v4(std::string v4, const std::string& records) {
  v4[14] = static_cast<char>(v4[14] | 2);
  std::string toc;
  put32(toc, static_cast<std::uint32_t>(32 + records.size()));
  v4.replace(16, 4, toc);
  return v4.insert(32, records);
}
// A v2/v3 payload with `records` after the SH (flag 0x2).
std::string with_records_legacy(std::string plain, const std::string& records) {
  plain[14] = static_cast<char>(plain[14] | 2);
  return plain + records;
}

}  // namespace

// spz extension records (flag 0x2: v4 between the header and the table of contents, v3
// after the SH): SPZ_ADOBE_coordinate_system (0xADBE0003, a u32, RDF = 6) names the
// frame the values are in, and the file is read in it whatever --spz-frame says; other
// types are skipped with a warning naming them; spz written in a frame other than RUB
// records it, and reads back without --spz-frame.
TEST(CliSplatFormats, SpzExtensionRecords) {
  const std::string rdf = spz_record(0xADBE0003, u32_bytes(6)), other = spz_record(0x12340001, "abc");
  const std::string plain3 = legacy_payload(3), v4 = hand_v4();
  // The reference: the files without records, read with --spz-frame RDF.
  const fs::path ref3 = scratch("ext_ref3.ply"), ref4 = scratch("ext_ref4.ply");
  write_bytes(scratch("ext_plain3.spz"), compress_with("gzip", plain3));
  write_bytes(scratch("ext_plain4.spz"), v4);
  ASSERT_EQ(convert(scratch("ext_plain3.spz"), ref3, {"--spz-frame", "RDF"}).exit_code, 0);
  ASSERT_EQ(convert(scratch("ext_plain4.spz"), ref4, {"--spz-frame", "RDF"}).exit_code, 0);
  struct Case {
    std::string name, bytes;
    fs::path reference;
    std::vector<std::string> args;
    std::string warning;
  };
  const std::vector<Case> cases = {
      {"v4 RDF", with_records_v4(v4, rdf), ref4, {}, ""},
      {"v4 RDF and an unknown record", with_records_v4(v4, other + rdf), ref4, {}, "0x12340001 (3 bytes)"},
      {"v4 RDF over --spz-frame", with_records_v4(v4, rdf), ref4, {"--spz-frame", "LUF"}, "not in --spz-frame LUF"},
      {"v3 RDF", compress_with("gzip", with_records_legacy(plain3, rdf)), ref3, {}, ""},
      {"v3 RDF and an unknown record",
       compress_with("gzip", with_records_legacy(plain3, rdf + other)),
       ref3,
       {},
       "0x12340001 (3 bytes)"},
      // Records of one unknown type are warned of once, counted.
      {"v4 three unknown records",
       with_records_v4(v4, other + rdf + other + other),
       ref4,
       {},
       "skipped 3 spz extension records of type 0x12340001 (9 bytes)"},
  };
  for (const Case& c : cases) {
    const fs::path spz = scratch("ext_in.spz"), ply = scratch("ext_out.ply");
    write_bytes(spz, c.bytes);
    const auto r = convert(spz, ply, c.args);
    ASSERT_EQ(r.exit_code, 0) << c.name << ": " << r.err;
    EXPECT_TRUE(read_file(ply) == read_file(c.reference)) << c.name << ": not read in the recorded frame";
    if (c.warning.empty())
      EXPECT_EQ(r.err.find("warning"), std::string::npos) << c.name << ": " << r.err;
    else
      EXPECT_NE(r.err.find("warning: " + spz.string()), std::string::npos) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.warning), std::string::npos) << c.name << ": " << r.err;
  }
  // Unknown records alone: read in the default frame, with the warning.
  {
    const fs::path spz = scratch("ext_other.spz"), ply = scratch("ext_other.ply"), ref = scratch("ext_other_ref.ply");
    write_bytes(spz, with_records_v4(v4, other));
    const auto r = convert(spz, ply);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("skipped an spz extension record of type 0x12340001"), std::string::npos) << r.err;
    ASSERT_EQ(convert(scratch("ext_plain4.spz"), ref).exit_code, 0);
    EXPECT_TRUE(read_file(ply) == read_file(ref));
  }
  // Bytes before the table of contents without flag 0x2 are no records: skipped, as the
  // reference loader skips them, with a warning (the file is read in the default frame).
  {
    std::string unflagged = with_records_v4(v4, rdf);
    unflagged[14] = static_cast<char>(unflagged[14] & ~2);
    const fs::path spz = scratch("ext_unflagged.spz"), ply = scratch("ext_unflagged.ply");
    write_bytes(spz, unflagged);
    const auto r = convert(spz, ply);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("12 bytes between the header and the table of contents, without flag 0x2"), std::string::npos)
        << r.err;
    EXPECT_TRUE(read_file(ply) == read_file(scratch("ext_other_ref.ply")));
  }
  // Written in RDF: the record (v4 in the header zone, v3 after the SH), read back
  // without --spz-frame.
  const Scene scene = random_scene(200, 2, 71);
  const fs::path in = scratch("ext_scene.ply");
  write_bytes(in, ply_bytes(scene));
  for (const std::string version : {"4", "3"}) {
    const fs::path spz = scratch("ext_rdf.spz"), back = scratch("ext_rdf_back.ply");
    auto r = convert(in, spz, {"--spz-frame", "RDF", "--spz-version", version});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::string bytes = read_file(spz);
    if (version == "3") {
      bytes = gunzip(bytes, "ext_rdf");
      ASSERT_FALSE(bytes.empty());
      EXPECT_EQ(bytes.substr(bytes.size() - 12), rdf);
    } else {
      EXPECT_EQ(bytes.substr(16, 4), u32_bytes(44));  // the table of contents after the record
      EXPECT_EQ(bytes.substr(32, 12), rdf);
    }
    EXPECT_EQ(bytes[14], 2) << "flags";
    r = convert(spz, back);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_mapped(scene, read_ply(back), Eigen::Matrix3d::Identity(), spz_tolerance(2), "RDF spz v" + version);
  }
  // Malformed records are refused, nothing written.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {with_records_v4(v4, spz_record(0xADBE0003, u32_bytes(17))), "coordinate system 17"},
      {with_records_v4(v4, spz_record(0xADBE0003, std::string(2, '\x06'))), "record of 2 bytes"},
      {with_records_v4(v4, rdf + rdf), "two SPZ_ADOBE_coordinate_system records"},
      {with_records_v4(v4, rdf.substr(0, 10)), "truncated extension record"},
      {compress_with("gzip", with_records_legacy(plain3, rdf.substr(0, 5))), "truncated extension record"},
      // Type 0 is reserved: a zone of zeros is not millions of empty records.
      {with_records_v4(v4, std::string(64, '\0')), "type 0x00000000"},
      {compress_with("gzip", with_records_legacy(plain3, std::string(64, '\0'))), "type 0x00000000"},
      // A gzip file's zone is bounded (16 MiB), not inflated as far as the stream goes:
      // here 17 MiB of one record in a file of about 17 KB.
      {compress_with("gzip", with_records_legacy(plain3, spz_record(0x12340001, std::string(17 << 20, 'x')))),
       "oversized: more than 16 MiB of extension records"},
  };
  for (const auto& [bytes, message] : bad) {
    const fs::path spz = scratch("ext_bad.spz"), out = scratch("ext_bad.ply");
    write_bytes(spz, bytes);
    expect_refused(spz, out, message);
  }
}

// Flag 0x1 (trained with antialiasing, which a viewer that honours it renders with) is
// carried from spz to spz (v4 and v3 written), and PLY, which has no such flag, is
// written with a warning that says so.
TEST(CliSplatFormats, SpzAntialiasedFlagIsCarriedOrWarnedOf) {
  std::string v4 = hand_v4();
  v4[14] = static_cast<char>(v4[14] | 1);
  const fs::path in = scratch("aa_in.spz");
  write_bytes(in, v4);
  for (const std::string version : {"4", "3"}) {
    const fs::path out = scratch("aa_out.spz");
    const auto r = convert(in, out, {"--spz-version", version});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    std::string bytes = read_file(out);
    if (version == "3") {
      bytes = gunzip(bytes, "aa_out");
      ASSERT_FALSE(bytes.empty());
    }
    EXPECT_EQ(bytes[14] & 1, 1) << "v" << version << ": the flag was dropped";
  }
  const auto r = convert(in, scratch("aa_out.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: " + in.string() + " says its splats were trained with antialiasing"),
            std::string::npos)
      << r.err;
}

// KHR_gaussian_splatting's colorSpace is carried from glTF to glTF; PLY and spz, which
// hold 3DGS's sRGB display colours, refuse a linear scene (its SH have no exact image);
// an unknown kernel or colour space is refused, nothing written.
TEST(CliSplatFormats, GltfColourSpaceAndKernel) {
  const Scene scene = random_scene(20, 1, 73);
  const fs::path in = scratch("cs_in.ply"), gltf = scratch("cs.gltf");
  write_bytes(in, ply_bytes(scene));
  ASSERT_EQ(convert(in, gltf).exit_code, 0);
  const nlohmann::json doc = nlohmann::json::parse(read_file(gltf));
  auto splat_object = [](const nlohmann::json& j) {
    return j["meshes"][0]["primitives"][0]["extensions"]["KHR_gaussian_splatting"];
  };
  EXPECT_EQ(splat_object(doc)["colorSpace"], "srgb_rec709_display");
  auto variant = [&](const std::string& name, const std::string& key, const std::string& value) {
    nlohmann::json j = doc;
    j["meshes"][0]["primitives"][0]["extensions"]["KHR_gaussian_splatting"][key] = value;
    const fs::path p = scratch(name);
    write_bytes(p, j.dump());
    return p;
  };
  const fs::path linear = variant("cs_lin.gltf", "colorSpace", "lin_rec709_display");
  for (const std::string ext : {".gltf", ".glb"}) {
    const fs::path out = scratch("cs_out" + ext), back = scratch("cs_back.gltf");
    auto r = convert(linear, out, {"--quat", "0.8,0.6,0,0"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = convert(out, back);  // through .glb too
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(splat_object(nlohmann::json::parse(read_file(back)))["colorSpace"], "lin_rec709_display") << ext;
  }
  struct Case {
    fs::path in;
    std::string ext, message;
  };
  const std::vector<Case> cases = {
      {linear, ".ply", "colour space lin_rec709_display"},
      {linear, ".spz", "colour space lin_rec709_display"},
      {variant("cs_unknown.gltf", "colorSpace", "acescg_display"), ".glb", "colorSpace 'acescg_display'"},
      {variant("cs_kernel.gltf", "kernel", "customShape"), ".ply", "kernel 'customShape'"},
      {variant("cs_kernel.gltf", "kernel", "customShape"), ".glb", "kernel 'customShape'"},
  };
  for (const Case& c : cases) {
    expect_refused(c.in, scratch("cs_refused" + c.ext), c.message);
  }
}

// The bound that transform-splats reports for --sh-bits, from the bucket sizes.
TEST(CliSplatFormats, QuantisationReport) {
  const Scene scene = random_scene(50, 3, 41);
  const fs::path in = scratch("report_in.ply"), out = scratch("report_out.spz");
  write_bytes(in, ply_bytes(scene));
  for (const auto& [bits, b1, b2] : std::vector<std::tuple<std::string, int, int>>{{"5,4", 8, 16}, {"8", 1, 1}, {"3,2", 32, 64}}) {
    const auto r = convert(in, out, {"--sh-bits", bits});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    double bound = 0;
    for (int l = 1; l <= 3; ++l) bound += ((l == 1 ? b1 : b2) / 2 + 0.5) / 128 * (2 * l + 1) / std::sqrt(4 * kPi);
    std::ostringstream text;
    text << "SH bands " << bound;
    EXPECT_NE(r.err.find(text.str()), std::string::npos) << bits << ": " << r.err << " wanted " << text.str();
  }
}

// spz's positions share one 24-bit fixed point: a splat past 2048 units lowers the
// fractional bits of every position. The writer does it and says so, naming the splat,
// how many lie that far and the step; a scene within 2048 units keeps 12 bits silently.
TEST(CliSplatFormats, FarSplatsCoarsenEverySpzPositionAndSaySo) {
  Scene scene = random_scene(20, 1, 7);
  const fs::path in = scratch("far_in.ply"), out = scratch("far_out.spz");
  const auto fractional_bits = [&] {
    std::ifstream f(out, std::ios::binary);
    std::string header(16, '\0');
    f.read(header.data(), 16);
    return static_cast<int>(static_cast<unsigned char>(header[13]));  // NGSP v4: degree, then fractionalBits
  };
  write_bytes(in, ply_bytes(scene));
  auto r = convert(in, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(fractional_bits(), 12);
  EXPECT_EQ(r.err.find("fractional bits"), std::string::npos) << r.err;

  Splat far = scene.splats[0];
  far.p = Eigen::Vector3d(5000, 1, -2);  // needs 10 bits: 5000 * 2^11 is past 2^23
  scene.splats.push_back(far);
  write_bytes(in, ply_bytes(scene));
  r = convert(in, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(fractional_bits(), 10);
  for (const char* part : {"splat 20 lies 5000 units", "1 of 21 splats", "stored with 10 fractional bits",
                           "a step of 0.000976562 units instead of 0.000244141"})
    EXPECT_NE(r.err.find(part), std::string::npos) << part << " not in: " << r.err;
  // The step is real: the near splats move by up to half of it, more than 12 bits allow.
  const Scene back = raw_values(out);
  ASSERT_EQ(back.splats.size(), scene.splats.size());
  double worst = 0;
  for (std::size_t i = 0; i < scene.splats.size(); ++i) {
    const Eigen::Vector3d p = scene.splats[i].p, q = back.splats[i].p;
    // PLY's RDF to spz's RUB: y and z change sign.
    worst = std::max(worst, (Eigen::Vector3d(p.x(), -p.y(), -p.z()) - q).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, std::ldexp(1.0, -11) + 1e-6);
  EXPECT_GT(worst, std::ldexp(1.0, -13));
  // Past 2^23 units no fixed point holds the position: refused, naming the splat, the
  // files and the range.
  far.p = Eigen::Vector3d(1e9, 0, 0);
  scene.splats.push_back(far);
  write_bytes(in, ply_bytes(scene));
  expect_refused(in, out,
                 "--out " + out.string() + " (from " + in.string() +
                     "): splat 21's x = 1e+09 is past spz's 24-bit fixed point, which holds positions within "
                     "-8388608..8388607 scene units");
}

// Options that neither file's format uses do nothing, and the job says so (a script may
// pass them for every file, so they are not refused).
TEST(CliSplatFormats, OptionsNeitherFormatUsesAreSaidToDoNothing) {
  const fs::path in = scratch("opts_in.ply"), glb = scratch("opts_out.glb"), spz = scratch("opts_out.spz");
  write_bytes(in, ply_bytes(random_scene(5, 1, 3)));
  auto r = convert(in, glb, {"--sh-bits", "1", "--spz-version", "3", "--spz-frame", "RDF", "--gltf-frame", "LUF"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* said : {"--sh-bits does nothing here", "--spz-version does nothing here",
                           "--spz-frame does nothing here: neither file is spz"})
    EXPECT_NE(r.err.find(said), std::string::npos) << said << " not in: " << r.err;
  EXPECT_EQ(r.err.find("--gltf-frame does nothing"), std::string::npos) << r.err;
  r = convert(in, spz, {"--sh-bits", "6", "--gltf-frame", "LUF"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("--sh-bits does nothing"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--gltf-frame does nothing here: neither file is glTF"), std::string::npos) << r.err;
}

// An empty scene has no spz (the reference loader refuses numPoints 0) and no glTF
// (accessors need a count of at least 1): refused alike, nothing written; PLY holds it.
TEST(CliSplatFormats, EmptySceneIsRefusedBySpzAndGltf) {
  const fs::path in = scratch("empty.ply");
  write_bytes(in, ply_bytes(Scene{1, {}}));
  for (const std::string ext : {".spz", ".glb", ".gltf"}) {
    SCOPED_TRACE(ext);
    expect_refused(in, scratch("empty_out" + ext), "cannot hold an empty splat scene");
  }
  for (const std::string version : {"3", "4"}) {
    const fs::path out = scratch("empty_out.spz");
    const auto r = convert(in, out, {"--spz-version", version});
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  const auto r = convert(in, scratch("empty_out.ply"), {"--sh-degree", "0"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // Nor is an spz of no splats read, in either container.
  std::string v4, v3;
  put32(v4, 0x5053474e), put32(v4, 4), put32(v4, 0);
  v4 += std::string("\x00\x0c\x00\x00", 4);  // degree 0, 12 bits, no flags, no streams
  put32(v4, 32);
  v4.append(12, '\0');
  put32(v3, 0x5053474e), put32(v3, 3), put32(v3, 0);
  v3 += std::string("\x00\x0c\x00\x00", 4);
  for (const std::string& bytes : {v4, compress_with("gzip", v3)}) {
    const fs::path spz = scratch("empty_in.spz");
    write_bytes(spz, bytes);
    expect_refused(spz, scratch("empty_back.ply"), "no splats");
  }
}

// The DC byte holds coefficients in [-0.5, 0.5] / 0.15 = +-3.33: the scene's DC figure
// counts what the clipping of larger ones changes (here -6 and 5 read back as -3.33 and
// 3.33: (6 - 10/3) y_0^0 = 0.752), where the byte step's bound is 0.0037.
TEST(CliSplatFormats, QuantisationReportCountsDcClipping) {
  Scene s = random_scene(2, 1, 83);
  for (int c = 0; c < 3; ++c) s.splats[0].sh[c][0] = s.splats[1].sh[c][0] = 0.1;
  s.splats[0].sh[0][0] = -6;
  s.splats[1].sh[1][0] = 5;
  const fs::path in = scratch("dc_in.ply"), out = scratch("dc_out.spz");
  write_bytes(in, ply_bytes(s));
  const auto r = convert(in, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string key = " from the byte step (coefficients in [-3.33, 3.33]), ";
  const std::size_t at = r.err.find(key);
  ASSERT_NE(at, std::string::npos) << r.err;
  const double scene_dc = std::stod(r.err.substr(at + key.size()));
  EXPECT_NEAR(scene_dc, (6 - 0.5 / 0.15) * C0, 1e-4) << r.err;
  const Scene back = read_ply([&] {
    const fs::path p = scratch("dc_back.ply");
    EXPECT_EQ(convert(out, p).exit_code, 0);
    return p;
  }());
  EXPECT_NEAR(std::abs(back.splats[0].sh[0][0] - s.splats[0].sh[0][0]) * C0, scene_dc, 1e-4);
}

TEST(CliSplatFormats, BadFilesAreRefusedWithNothingWritten) {
  const Scene scene = random_scene(20, 1, 43);
  const fs::path in = scratch("bad_src.ply"), v4 = scratch("bad_src.spz"), v3 = scratch("bad_src3.spz"),
                 glb = scratch("bad_src.glb");
  write_bytes(in, ply_bytes(scene));
  ASSERT_EQ(convert(in, v4).exit_code, 0);
  ASSERT_EQ(convert(in, v3, {"--spz-version", "3"}).exit_code, 0);
  ASSERT_EQ(convert(in, glb).exit_code, 0);
  const std::string s4 = read_file(v4), s3 = read_file(v3), sg = read_file(glb);
  std::string more_streams = s4;
  more_streams[15] = 5;
  std::string huge = s4;
  huge[8] = '\xff', huge[9] = '\xff', huge[10] = '\xff', huge[11] = '\x0f';
  std::string degree4 = s4;
  degree4[12] = 4;
  std::string gz_huge = compress_with("gzip", [] {
    std::string p;
    put32(p, 0x5053474e), put32(p, 3), put32(p, 0x0fffffff);
    p += std::string("\x00\x0c\x00\x00", 4);
    p.append(100, '\0');
    return p;
  }());
  std::string gz_long = compress_with("gzip", legacy_payload(3) + "extra");
  std::string glb_v1 = sg, glb_magic = sg;
  glb_v1[4] = 1;
  glb_magic[3] = 'X';
  std::string bad_glb = sg;
  const std::size_t at = bad_glb.find("OPACITY");
  ASSERT_NE(at, std::string::npos);
  bad_glb.replace(at, 7, "OPACITX");
  struct Case {
    std::string name, ext, bytes;
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"v4 truncated", ".spz", s4.substr(0, s4.size() - 5), {}, "truncated"},
      {"v4 header only", ".spz", s4.substr(0, 20), {}, "truncated"},
      {"v4 trailing bytes", ".spz", s4 + "zz", {}, "after the last stream"},
      {"v4 stream count", ".spz", more_streams, {}, "inconsistent"},
      {"v4 oversized", ".spz", huge, {}, "stream"},
      {"v4 degree 4", ".spz", degree4, {}, "degree 4"},
      {"v3 truncated", ".spz", s3.substr(0, s3.size() / 2), {}, "truncated"},
      {"v3 oversized", ".spz", gz_huge, {}, "oversized"},
      {"v3 longer than its splats", ".spz", gz_long, {}, "longer than"},
      {"not spz", ".spz", "hello", {}, "not an spz"},
      {"glb missing opacity", ".glb", bad_glb, {}, "OPACITY"},
      {"glb truncated", ".glb", sg.substr(0, sg.size() / 2), {}, "glTF"},
      // tinygltf reads any container version as 2's, and a .glb without its magic as JSON.
      {"glb container version 1", ".glb", glb_v1, {}, "GLB container version 1"},
      {"glb without its magic", ".glb", glb_magic, {}, "not a GLB: it does not begin with the magic 'glTF'"},
      {"unknown extension", ".splat", s4, {}, "unknown splat format"},
      {"bad frame", ".spz", s4, {"--frame", "RUX"}, "frame"},
      {"frame repeats an axis", ".spz", s4, {"--spz-frame", "RRU"}, "frame"},
      {"sh bits", ".spz", s4, {"--sh-bits", "9"}, "--sh-bits"},
      {"sh degree", ".spz", s4, {"--sh-degree", "4"}, "--sh-degree"},
      {"spz version", ".spz", s4, {"--spz-version", "2"}, "--spz-version"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path bad = scratch("bad" + c.ext);
    write_bytes(bad, c.bytes);
    expect_refused(bad, scratch("bad_out.spz"), c.message, c.args);
  }
}

// A v4 file whose streams claim more splats than its size makes plausible (the reference
// loader's numPoints <= file size x 1024 / 9) is refused before anything is allocated:
// here a million splats of zeros in about a kilobyte (each stream within zstd's own
// 32768:1).
TEST(CliSplatFormats, SpzPointCountBoundedByFileSize) {
  auto file = [](std::uint32_t n) {
    const std::uint64_t sizes[5] = {9ull * n, n, 3ull * n, 3ull * n, 4ull * n};  // degree 0: no SH stream
    std::string s;
    put32(s, 0x5053474e), put32(s, 4), put32(s, n);
    s += std::string("\x00\x0c\x00\x05", 4);  // degree 0, 12 bits, flags, 5 streams
    put32(s, 32);
    s.append(12, '\0');
    std::vector<std::string> z;
    for (std::uint64_t size : sizes) z.push_back(compress_with("zstd", std::string(size, '\0')));
    for (int k = 0; k < 5; ++k) put64(s, z[k].size()), put64(s, sizes[k]);
    for (const std::string& x : z) s += x;
    return s;
  };
  const fs::path spz = scratch("bomb.spz"), out = scratch("bomb.ply");
  const std::string bomb = file(1000000);
  ASSERT_LT(bomb.size() * 1024 / 9, 1000000u) << bomb.size();
  write_bytes(spz, bomb);
  expect_refused(spz, out, "implausible: 1000000 splats claimed");
  // The same streams for as many splats as the bound allows are read.
  const std::string small = file(100);
  write_bytes(spz, small);
  const auto r = convert(spz, out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// A glTF whose extensionsRequired lists an extension shtool does not implement (here
// EXT_meshopt_compression, whose buffer views would hold fallback data) is refused naming
// it; KHR_gaussian_splatting itself may be required.
TEST(CliSplatFormats, GltfRequiredExtensionsAreChecked) {
  const Scene scene = random_scene(10, 1, 79);
  const fs::path in = scratch("req_in.ply"), gltf = scratch("req.gltf");
  write_bytes(in, ply_bytes(scene));
  ASSERT_EQ(convert(in, gltf).exit_code, 0);
  nlohmann::json doc = nlohmann::json::parse(read_file(gltf));
  doc["extensionsRequired"] = {"KHR_gaussian_splatting"};
  const fs::path ok = scratch("req_ok.gltf"), ok_out = scratch("req_ok.ply");
  write_bytes(ok, doc.dump());
  const auto r = convert(ok, ok_out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  doc["extensionsUsed"].push_back("EXT_meshopt_compression");
  doc["extensionsRequired"].push_back("EXT_meshopt_compression");
  const fs::path bad = scratch("req_bad.gltf");
  write_bytes(bad, doc.dump());
  for (const std::string ext : {".ply", ".glb", ".spz"}) {
    SCOPED_TRACE(ext);
    expect_refused(bad, scratch("req_out" + ext), "requires the glTF extension EXT_meshopt_compression");
  }
}

// glTF stores linear scales: a log-scale past log(FLT_MAX) = 88.72 (here 89, in the
// input; and 50 under --scale 1e20, +46) has no float, and is refused naming the splat,
// nothing written.
TEST(CliSplatFormats, GlbScaleOverflowIsRefused) {
  Scene s = random_scene(3, 0, 7);
  s.splats[2].log_scale[0] = 89;
  const fs::path in = scratch("big_scale.ply");
  write_bytes(in, ply_bytes(s));
  Scene t = random_scene(3, 0, 7);
  t.splats[1].log_scale[2] = 50;
  const fs::path in2 = scratch("big_scale2.ply");
  write_bytes(in2, ply_bytes(t));
  for (const std::string ext : {".glb", ".gltf"}) {
    SCOPED_TRACE(ext);
    const fs::path out = scratch("big_scale" + ext);
    expect_refused(in, out, "splat 2: its log-scale 89");
    expect_refused(in2, out, "splat 1: its log-scale 96.05", {"--scale", "1e20"});
  }
}

// A finite value that a rotation alone takes past float (an SH coefficient or an
// orientation component near 3.4e38) is refused on every path, naming the splat, not
// written as inf: PLY streamed, PLY through the scene (--sh-degree), spz, glTF.
TEST(CliSplatFormats, OverflowUnderTheTurnIsRefusedOnEveryPath) {
  const std::vector<std::string> turn = {"--quat", "0.92388,0.38268,0,0"};  // 45 degrees about x
  Scene sh = random_scene(20, 3, 41);
  sh.splats[9].sh[0][1] = 3e38;  // red, band 1: the turn mixes it with its band's others
  sh.splats[9].sh[0][2] = 3e38;
  Scene rot = random_scene(20, 3, 43);
  rot.splats[11].rot = Eigen::Vector4d(3e38, -3e38, 0, 0);
  const fs::path in_sh = scratch("overflow_sh.ply"), in_rot = scratch("overflow_rot.ply");
  write_bytes(in_sh, ply_bytes(sh));
  write_bytes(in_rot, ply_bytes(rot));
  for (const auto& [ext, more] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {".ply", {}}, {".ply", {"--sh-degree", "3"}}, {".spz", {}}, {".glb", {}}, {".gltf", {}}}) {
    SCOPED_TRACE(ext + (more.empty() ? "" : " " + more[0]));
    std::vector<std::string> argv = turn;
    argv.insert(argv.end(), more.begin(), more.end());
    const fs::path out = scratch("overflow_out" + ext);
    expect_refused(in_sh, out, "splat 9: ", argv);
    expect_refused(in_sh, out, "overflows its type after the transform (a value of", argv);
    expect_refused(in_rot, out, "splat 11: ", argv);
  }
}

// The glTF and spz writers store unit orientations whatever the stored length: four
// quaternions of one turn (90 degrees about x), of lengths 1.4e20, 1.4e-25, 4.2e38 and
// 0.99, come out as one unit quaternion (up to sign; spz within its 10-bit step).
TEST(CliSplatFormats, OrientationsOfAnyLengthAreStoredAsUnitQuaternions) {
  Scene s = random_scene(4, 0, 47);
  const double lengths[4] = {1e20, 1e-25, 3e38, 0.7};
  for (int i = 0; i < 4; ++i) s.splats[i].rot = Eigen::Vector4d(lengths[i], lengths[i], 0, 0);
  const fs::path in = scratch("quat_lengths.ply");
  write_bytes(in, ply_bytes(s));
  for (const auto& [ext, tolerance] : std::vector<std::pair<std::string, double>>{{".glb", 1e-6}, {".spz", 2e-3}}) {
    SCOPED_TRACE(ext);
    const fs::path out = scratch("quat_lengths" + ext);
    const auto r = convert(in, out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Scene back = raw_values(out);
    ASSERT_EQ(back.splats.size(), 4u);
    // The last (length 0.99) as the reference: the frame change turns all four alike.
    const Eigen::Vector4d unit = back.splats[3].rot;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector4d q = back.splats[i].rot;
      EXPECT_NEAR(q.norm(), 1.0, tolerance) << i;
      EXPECT_NEAR(std::abs(q.dot(unit)), 1.0, tolerance)
          << i << ": " << q.transpose() << " against " << unit.transpose();
    }
  }
}

// The Khronos validator on the glTF outputs: no error but its verdict on the extension's
// attribute names, which it does not know (the messages are printed).
TEST(CliSplatFormats, GltfValidatorFaultsOnlyTheExtensionAttributeNames) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const Scene scene = random_scene(100, 3, 47);
  const fs::path in = scratch("val_in.ply");
  write_bytes(in, ply_bytes(scene));
  for (const std::string ext : {".glb", ".gltf"}) {
    const fs::path out = scratch("val_out" + ext);
    ASSERT_EQ(convert(in, out).exit_code, 0);
    const auto r = run_command({"node", (node_consumers_dir() / "validate_gltf.mjs").string(), out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json report = nlohmann::json::parse(r.out);
    // This validator (2.0.0-dev.3.10, the newest on npm) predates the extension: it knows
    // no attribute semantic outside core glTF but "_"-prefixed ones, and reports each of
    // the extension's as an error. Those are the only errors allowed.
    int others = 0;
    for (const nlohmann::json& m : report["issues"]["messages"])
      if (m["severity"] == 0 && !(m["code"] == "MESH_PRIMITIVE_INVALID_ATTRIBUTE" &&
                                  m["pointer"].get<std::string>().find("/attributes/KHR_gaussian_splatting:") !=
                                      std::string::npos))
        ++others;
    EXPECT_EQ(others, 0) << report["issues"].dump(1);
    EXPECT_EQ(report["issues"]["numErrors"], 3 + 16) << report["issues"].dump(1);  // rotation, scale, opacity, 16 SH
    EXPECT_EQ(report["info"]["drawCallCount"], 1) << report.dump(1);
    std::cout << ext << ": " << report["issues"]["numWarnings"] << " warnings, " << report["issues"]["numInfos"]
              << " infos " << report["issues"]["messages"].dump() << '\n';
  }
}

// @playcanvas/splat-transform (pinned in tests/consumer/node/package.json) both ways:
// shtool's .spz read back by splat-transform into PLY gives the original values, and
// splat-transform's .spz read by shtool into PLY gives them too, within the quantisation
// (colours from 64 directions). So both place the PLY's RDF axes and spz's RUB alike.
TEST(CliSplatFormats, SplatTransformReadsAndWritesTheSameSpz) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const Scene scene = random_scene(1000, 3, 53);
  const fs::path in = scratch("st_in.ply");
  write_bytes(in, ply_bytes(scene));
  const std::string cli = (node_consumers_dir() / "splat_transform_cli.mjs").string();
  for (const std::string version : {"4", "3"}) {
    const fs::path ours = scratch("st_ours.spz"), theirs_ply = scratch("st_theirs.ply");
    ASSERT_EQ(convert(in, ours, {"--spz-version", version}).exit_code, 0);
    const auto r = run_command({"node", cli, ours.string(), theirs_ply.string()});
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    expect_mapped(scene, read_ply(theirs_ply), Eigen::Matrix3d::Identity(), spz_tolerance(3),
                  "shtool spz v" + version + " -> splat-transform");
  }
  const fs::path theirs = scratch("st_theirs.spz"), back = scratch("st_back.ply");
  const auto r = run_command({"node", cli, in.string(), theirs.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string bytes = read_file(theirs);
  ASSERT_GE(bytes.size(), 8u);
  std::cout << "splat-transform wrote spz version " << int(static_cast<unsigned char>(bytes[4]))
            << (bytes.compare(0, 4, "NGSP") == 0 ? " (NGSP header)" : " (gzip)") << '\n';
  const auto s = convert(theirs, back);
  ASSERT_EQ(s.exit_code, 0) << s.err;
  expect_mapped(scene, read_ply(back), Eigen::Matrix3d::Identity(), spz_tolerance(3), "splat-transform spz -> shtool");
}

// @playcanvas/splat-transform writes glb (KHR_gaussian_splatting) but reads none: its
// glb, read by shtool into PLY, gives the original PLY's values when its axes are named
// LUF (its Transform.PLY, a half turn about z of the PLY), and the PLY turned half a
// turn about its vertical axis (diag(-1, 1, -1)) under glTF's default RUB.
TEST(CliSplatFormats, SplatTransformGlbReadByShtool) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  const Scene scene = random_scene(1000, 3, 61);
  const fs::path in = scratch("st_glb_in.ply"), theirs = scratch("st_theirs.glb");
  write_bytes(in, ply_bytes(scene));
  const auto r = run_command({"node", (node_consumers_dir() / "splat_transform_cli.mjs").string(), in.string(),
                              theirs.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  Tolerance t;  // float arithmetic on their side (a rotation, exp and sigmoid)
  t.position = 1e-4, t.covariance = 1e-4, t.colour = 1e-4;
  const fs::path luf = scratch("st_glb_luf.ply"), rub = scratch("st_glb_rub.ply");
  auto c = convert(theirs, luf, {"--gltf-frame", "LUF"});
  ASSERT_EQ(c.exit_code, 0) << c.err;
  expect_mapped(scene, read_ply(luf), Eigen::Matrix3d::Identity(), t, "splat-transform glb -> shtool (LUF)");
  c = convert(theirs, rub);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  expect_mapped(scene, read_ply(rub), Eigen::Vector3d(-1, 1, -1).asDiagonal().toDenseMatrix(), t,
                "splat-transform glb -> shtool (RUB)");
}

// Every output format: the same bytes with 1 and 3 threads (20000 splats: several chunks).
TEST(CliSplatFormats, SameBytesWhateverTheThreadCount) {
  const Scene scene = random_scene(20000, 3, 59);
  const fs::path in = scratch("threads_in.ply");
  write_bytes(in, ply_bytes(scene));
  for (const Format& f : formats()) {
    std::string bytes[2];
    for (int k = 0; k < 2; ++k) {
      const fs::path out = scratch("threads_" + std::to_string(k) + f.ext);
      const auto r = f.write(in, out, {"--quat", "0.5,0.5,-0.5,0.5", "--sh-degree", "3", "--threads", k ? "3" : "1"});
      ASSERT_EQ(r.exit_code, 0) << r.err;
      bytes[k] = read_file(out);
    }
    EXPECT_TRUE(bytes[0] == bytes[1]) << f.name;
  }
}
