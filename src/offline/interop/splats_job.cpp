#include "interop/splats_job.h"

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "common/job_outputs.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/parallel_for.h"
#include "common/stopwatch.h"
#include "interop/ply.h"
#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool::interop {
namespace {

// The properties of a 3DGS vertex this job reads and writes (indices into the
// element's properties), found by name.
struct SplatLayout {
  std::array<std::size_t, 3> position{};
  std::optional<std::array<std::size_t, 3>> normal;
  std::optional<std::array<std::size_t, 4>> rotation;
  std::optional<std::array<std::size_t, 3>> scale;
  std::optional<std::array<std::size_t, 3>> dc;
  std::vector<std::size_t> rest;  // f_rest_0 .. f_rest_{K-1}
  int degree = 0;
};

SplatLayout find_layout(const PlyElement& v, const std::filesystem::path& name) {
  auto fail = [&](const std::string& why) { return InputError(name.string() + ": " + why); };
  auto need = [&](const std::string& p) {
    const std::optional<std::size_t> i = v.find(p);
    if (!i) throw fail("the vertex element has no property '" + p + "'");
    return *i;
  };
  auto floats = [&](std::size_t i) {
    if (v.properties[i].type != PlyType::float32 && v.properties[i].type != PlyType::float64)
      throw fail("property '" + v.properties[i].name + "' must be float or double");
    return i;
  };
  auto group = [&]<std::size_t N>(const std::array<const char*, N>& names) -> std::optional<std::array<std::size_t, N>> {
    std::size_t found = 0;
    for (const char* n : names) found += v.find(n).has_value();
    if (found == 0) return std::nullopt;
    if (found != N) throw fail(std::string("properties ") + names[0] + ".." + names[N - 1] + " are incomplete");
    std::array<std::size_t, N> out{};
    for (std::size_t k = 0; k < N; ++k) out[k] = floats(need(names[k]));
    return out;
  };
  SplatLayout l;
  for (int k = 0; k < 3; ++k) l.position[k] = floats(need(std::string(1, "xyz"[k])));
  l.normal = group(std::array<const char*, 3>{"nx", "ny", "nz"});
  l.rotation = group(std::array<const char*, 4>{"rot_0", "rot_1", "rot_2", "rot_3"});
  l.scale = group(std::array<const char*, 3>{"scale_0", "scale_1", "scale_2"});
  l.dc = group(std::array<const char*, 3>{"f_dc_0", "f_dc_1", "f_dc_2"});
  for (std::size_t k = 0;; ++k) {
    const std::optional<std::size_t> i = v.find("f_rest_" + std::to_string(k));
    if (!i) break;
    l.rest.push_back(floats(*i));
  }
  for (const PlyProperty& p : v.properties)
    if (p.name.rfind("f_rest_", 0) == 0) {
      bool listed = false;
      for (std::size_t i : l.rest) listed = listed || v.properties[i].name == p.name;
      if (!listed) throw fail("f_rest properties must be numbered from 0 without gaps ('" + p.name + "')");
    }
  const std::size_t per_channel = l.rest.size() / 3;
  if (l.rest.size() % 3 != 0 || (per_channel != 0 && per_channel != 3 && per_channel != 8 && per_channel != 15))
    throw fail(std::to_string(l.rest.size()) + " f_rest properties: 0, 9, 24 or 45 expected (SH degree 0..3)");
  if (!l.rest.empty() && !l.dc) throw fail("f_rest properties without f_dc_0..2");
  l.degree = per_channel == 0 ? 0 : per_channel == 3 ? 1 : per_channel == 8 ? 2 : 3;
  return l;
}

}  // namespace

Eigen::Matrix3d splat_rotation(const TransformSplatsRequest& r) {
  if (r.quaternion.has_value() == r.matrix.has_value()) throw InputError("give exactly one of --quat and --matrix");
  if (r.quaternion) {
    const auto& q = *r.quaternion;
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(n > 0) || !std::isfinite(n)) throw InputError("--quat must be a finite, non-zero quaternion w,x,y,z");
    return matrix_from_quaternion<double>(q[0] / n, q[1] / n, q[2] / n, q[3] / n);
  }
  Eigen::Matrix3d m;
  for (int k = 0; k < 9; ++k) m(k / 3, k % 3) = (*r.matrix)[k];
  if (!m.allFinite() || !(m.transpose() * m).isApprox(Eigen::Matrix3d::Identity(), 1e-6))
    throw InputError("--matrix must be a rotation (orthonormal rows to 1e-6)");
  if (m.determinant() < 0)
    throw InputError("--matrix is a reflection (determinant -1): 3DGS orientations are rotations, and mirrored SH "
                     "colours would need the basis's parity too; mirror the scene in its own tool");
  return m;
}

TransformSplatsReport run_transform_splats(const TransformSplatsRequest& r) {
  const Eigen::Matrix3d rot = splat_rotation(r);
  if (!(r.scale > 0) || !std::isfinite(r.scale)) throw InputError("--scale must be a positive number");
  for (double t : r.translate)
    if (!std::isfinite(t)) throw InputError("--translate must be finite");
  if (r.out.empty()) throw InputError("--out is required");
  JobOutputs io;
  io.input(r.in, "the input scene");
  io.output(r.out, "--out");
  const int threads = resolve_threads(r.threads);
  const auto t0 = std::chrono::steady_clock::now();

  PlyFile ply = PlyFile::parse(read_input_file(r.in, "input"), r.in);
  const PlyElement* vertex = ply.element("vertex");
  if (!vertex) throw InputError(r.in.string() + ": no 'vertex' element");
  const PlyElement& v = *vertex;
  const SplatLayout layout = find_layout(v, r.in);
  // The given quaternion itself when there is one (no round trip through the matrix).
  const Eigen::Quaterniond qr = r.quaternion ? Eigen::Quaterniond((*r.quaternion)[0], (*r.quaternion)[1],
                                                                  (*r.quaternion)[2], (*r.quaternion)[3])
                                                   .normalized()
                                             : Eigen::Quaterniond(rot);
  const double log_scale = std::log(r.scale);
  const Eigen::Vector3d t(r.translate[0], r.translate[1], r.translate[2]);
  const int order = layout.degree + 1;
  const int k_rest = sh_count(order) - 1;

  // One rotation for every splat, by the reference method: exact to rounding at every
  // angle (an identity leaves the colours' bits as they were).
  ShRotation<double> sh_rotation(order, nullptr);
  sh_rotation.set(rot, RotationMethod::reference);
  const std::size_t count = v.count;
  const bool moves = !rot.isIdentity(0) || r.scale != 1 || !t.isZero(0);
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (count + kChunk - 1) / kChunk;
  // The first problem of each chunk; the first chunk's is reported, whatever the threads.
  std::vector<std::string> problems(chunks);
  // The name of the first property of splat i that is not finite, or null.
  auto non_finite = [&](std::size_t i) -> const std::string* {
    for (std::size_t p = 0; p < v.properties.size(); ++p)
      if (!std::isfinite(ply.get(v, i, p))) return &v.properties[p].name;
    return nullptr;
  };
  parallel_for(chunks, threads, [&](std::size_t chunk) {
    std::array<std::vector<double>, 3> f, g;
    for (int c = 0; c < 3; ++c) f[c].resize(sh_count(order)), g[c].resize(sh_count(order));
    const std::size_t end = std::min(count, (chunk + 1) * kChunk);
    for (std::size_t i = chunk * kChunk; i < end; ++i) {
      if (const std::string* name = non_finite(i)) {
        problems[chunk] = r.in.string() + ": splat " + std::to_string(i) + ": '" + *name + "' is not finite";
        return;
      }
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = ply.get(v, i, layout.position[k]);
      const Eigen::Vector3d moved = moves ? Eigen::Vector3d(r.scale * (rot * p) + t) : p;
      for (int k = 0; k < 3; ++k) ply.set(v, i, layout.position[k], moved[k]);
      if (layout.normal) {
        Eigen::Vector3d n;
        for (int k = 0; k < 3; ++k) n[k] = ply.get(v, i, (*layout.normal)[k]);
        const Eigen::Vector3d turned = rot * n;
        for (int k = 0; k < 3; ++k) ply.set(v, i, (*layout.normal)[k], turned[k]);
      }
      if (layout.rotation) {
        const auto& idx = *layout.rotation;
        const Eigen::Quaterniond q(ply.get(v, i, idx[0]), ply.get(v, i, idx[1]), ply.get(v, i, idx[2]),
                                   ply.get(v, i, idx[3]));
        const Eigen::Quaterniond out = qr * q;  // |out| = |q|: qr is unit
        const double parts[4] = {out.w(), out.x(), out.y(), out.z()};
        for (int k = 0; k < 4; ++k) ply.set(v, i, idx[k], parts[k]);
      }
      if (layout.scale && log_scale != 0)
        for (int k = 0; k < 3; ++k) ply.set(v, i, (*layout.scale)[k], ply.get(v, i, (*layout.scale)[k]) + log_scale);
      if (layout.degree > 0) {
        for (int c = 0; c < 3; ++c) {
          f[c][0] = ply.get(v, i, (*layout.dc)[c]);
          for (int k = 0; k < k_rest; ++k) f[c][1 + k] = ply.get(v, i, layout.rest[c * k_rest + k]);
        }
        sh_rotation.apply_rgb({f[0], f[1], f[2]}, {g[0], g[1], g[2]});
        for (int c = 0; c < 3; ++c)
          for (int k = 0; k < k_rest; ++k) ply.set(v, i, layout.rest[c * k_rest + k], g[c][1 + k]);
      }
      // A finite value beyond the property's type (float32 past 3.4e38) was stored as inf.
      if (const std::string* name = non_finite(i)) {
        problems[chunk] = "splat " + std::to_string(i) + ": '" + *name +
                          "' overflows its type after the transform (--scale or --translate too large for " +
                          r.in.string() + ")";
        return;
      }
    }
  });
  for (const std::string& problem : problems)
    if (!problem.empty()) throw InputError(problem);
  io.set("--out", ply.format() == PlyFormat::ascii ? ply.bytes() : std::string(ply.binary_bytes()));
  io.commit();
  TransformSplatsReport report;
  report.splats = count;
  report.degree = layout.degree;
  report.threads = threads;
  report.seconds = seconds_since(t0);
  return report;
}

}  // namespace shtool::interop
