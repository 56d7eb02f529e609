#include "interop/splats_job.h"

#include <cctype>
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
#include "interop/splat_gltf.h"
#include "interop/splat_ply.h"
#include "interop/spz.h"
#include "shtool/euler.h"
#include "shtool/orthogonal_map.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool::interop {

Eigen::Matrix3d splat_rotation(const TransformSplatsRequest& r) {
  if (r.quaternion && r.matrix) throw InputError("give exactly one of --quat and --matrix, or neither");
  if (!r.quaternion && !r.matrix) return Eigen::Matrix3d::Identity();
  if (r.quaternion) {
    const auto& q = *r.quaternion;
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(n > 0) || !std::isfinite(n)) throw InputError("--quat must be a finite, non-zero quaternion w,x,y,z");
    return matrix_from_quaternion<double>(q[0] / n, q[1] / n, q[2] / n, q[3] / n);
  }
  Eigen::Matrix3d m;
  for (int k = 0; k < 9; ++k) m(k / 3, k % 3) = (*r.matrix)[k];
  if (!m.allFinite() || !(m.transpose() * m).isApprox(Eigen::Matrix3d::Identity(), 1e-6))
    throw InputError("--matrix must be orthogonal (a rotation or a reflection: orthonormal rows to 1e-6)");
  return m;
}

namespace {

// PLY in, PLY out in one frame: the file's values rewritten in place, every other
// property, the header and the encoding kept.
void transform_ply_in_place(const TransformSplatsRequest& r, const Eigen::Matrix3d& rot, std::string bytes,
                            JobOutputs& io, int threads, TransformSplatsReport& report) {
  PlyFile ply = PlyFile::parse(std::move(bytes), r.in);
  const PlyElement* vertex = ply.element("vertex");
  if (!vertex) throw InputError(r.in.string() + ": no 'vertex' element");
  const PlyElement& v = *vertex;
  const SplatLayout layout = find_splat_layout(v, r.in);
  Result<OrthogonalMap> made = OrthogonalMap::make(rot, layout.degree + 1, 1e-6);
  if (!made) throw InputError("--matrix: " + made.error().message);
  const OrthogonalMap& map = made.value();
  // Orientations turn by the proper part (a reflection's covariance M Sigma M^T is
  // P Sigma P^T); the given quaternion itself when there is one (no round trip through
  // the matrix).
  const Eigen::Quaterniond qr = r.quaternion ? Eigen::Quaterniond((*r.quaternion)[0], (*r.quaternion)[1],
                                                                  (*r.quaternion)[2], (*r.quaternion)[3])
                                                   .normalized()
                                             : Eigen::Quaterniond(map.proper());
  const double log_scale = std::log(r.scale);
  const Eigen::Vector3d t(r.translate[0], r.translate[1], r.translate[2]);
  const int order = layout.degree + 1;
  const int k_rest = sh_count(order) - 1;

  // One map for every splat, by the reference rotation: exact to rounding at every angle
  // (an identity leaves the colours' bits as they were).
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
    std::vector<double> f(3 * static_cast<std::size_t>(sh_count(order))), g(f.size());  // interleaved
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
          f[c] = ply.get(v, i, (*layout.dc)[c]);
          for (int k = 0; k < k_rest; ++k) f[3 * (1 + k) + c] = ply.get(v, i, layout.rest[c * k_rest + k]);
        }
        map.apply(f, g, 3);
        for (int c = 0; c < 3; ++c)
          for (int k = 0; k < k_rest; ++k) ply.set(v, i, layout.rest[c * k_rest + k], g[3 * (1 + k) + c]);
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
  report.splats = count;
  report.degree = layout.degree;
}

}  // namespace

Eigen::Matrix3d splat_frame(std::string_view letters) {
  std::string up;
  for (char c : letters) up.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  auto bad = [&] {
    return InputError("frame '" + std::string(letters) +
                      "': three letters, one of R/L, one of U/D and one of F/B, for the file's x, y, z axes (e.g. RDF, RUB)");
  };
  if (up.size() != 3) throw bad();
  Eigen::Matrix3d q = Eigen::Matrix3d::Zero();
  int seen = 0;
  for (int axis = 0; axis < 3; ++axis) {
    // shtool's frame in these letters is RFU: x right, y forward (away from the viewer), z up.
    int row = -1;
    double sign = 1;
    switch (up[axis]) {
      case 'R': row = 0; break;
      case 'L': row = 0, sign = -1; break;
      case 'F': row = 1; break;
      case 'B': row = 1, sign = -1; break;
      case 'U': row = 2; break;
      case 'D': row = 2, sign = -1; break;
      default: throw bad();
    }
    if (seen & (1 << row)) throw bad();
    seen |= 1 << row;
    q(row, axis) = sign;
  }
  return q;
}

TransformSplatsReport run_transform_splats(const TransformSplatsRequest& r) {
  const Eigen::Matrix3d rot = splat_rotation(r);
  if (!(r.scale > 0) || !std::isfinite(r.scale)) throw InputError("--scale must be a positive number");
  for (double t : r.translate)
    if (!std::isfinite(t)) throw InputError("--translate must be finite");
  if (r.out.empty()) throw InputError("--out is required");
  if (r.sh_degree) check_option_range("--sh-degree", *r.sh_degree, 0, 3);
  splat_frame(r.ply_frame), splat_frame(r.spz_frame), splat_frame(r.gltf_frame);  // all checked, used or not
  const SplatFormat in_format = splat_format_of(r.in, "the input");
  const SplatFormat out_format = splat_format_of(r.out, "--out");
  auto frame_of = [&](SplatFormat f) {
    return f == SplatFormat::ply ? splat_frame(r.ply_frame) : f == SplatFormat::spz ? splat_frame(r.spz_frame)
                                                                                    : splat_frame(r.gltf_frame);
  };
  const Eigen::Matrix3d frame_change = frame_of(out_format).transpose() * frame_of(in_format);
  SpzWriteOptions spz;
  spz.version = r.spz_version;
  spz.sh1_bits = r.sh_bits[0];
  spz.sh_rest_bits = r.sh_bits[1];
  if (out_format == SplatFormat::spz) {
    if (spz.version != 3 && spz.version != 4) throw InputError("--spz-version must be 3 or 4");
    for (int b : r.sh_bits)
      if (b < 1 || b > 8) throw InputError("--sh-bits must be in 1..8, got " + std::to_string(b));
  }
  JobOutputs io;
  io.input(r.in, "the input scene");
  io.output(r.out, "--out");
  const int threads = resolve_threads(r.threads);
  const auto t0 = std::chrono::steady_clock::now();
  TransformSplatsReport report;
  report.threads = threads;
  report.reflects = (frame_change * rot).determinant() < 0;
  std::string bytes = read_input_file(r.in, "input");
  if (in_format == SplatFormat::ply && out_format == SplatFormat::ply && !r.sh_degree) {
    transform_ply_in_place(r, rot, std::move(bytes), io, threads, report);
  } else {
    SplatScene scene;
    switch (in_format) {
      case SplatFormat::ply: scene = read_ply_splats(PlyFile::parse(std::move(bytes), r.in), r.in, threads); break;
      case SplatFormat::spz: scene = read_spz(bytes, r.in.string(), nullptr, threads); break;
      case SplatFormat::gltf:
      case SplatFormat::glb: scene = read_gltf_splats(bytes, r.in, threads); break;
    }
    report.degree_in = scene.degree;
    const Eigen::Vector3d t(r.translate[0], r.translate[1], r.translate[2]);
    // The user's transform acts in the input's coordinates, then the frame changes.
    transform_splat_scene(scene, frame_change * rot, r.scale, frame_change * t, threads);
    if (r.sh_degree) scene.set_degree(*r.sh_degree);
    for (std::size_t i = 0; i < scene.position.size(); ++i)
      if (!std::isfinite(scene.position[i]) || !std::isfinite(scene.log_scale[i]))
        throw InputError("splat " + std::to_string(i / 3) +
                         ": a position or scale overflows float after the transform (--scale or --translate too large for " +
                         r.in.string() + ")");
    std::string out;
    switch (out_format) {
      case SplatFormat::ply: out = write_ply_splats(scene); break;
      case SplatFormat::spz:
        out = write_spz(scene, spz, threads);
        report.spz_sh_bound = spz_sh_error_bound(scene.degree, spz);
        report.spz_sh_scene = spz_sh_error_of(scene, spz, threads);
        report.spz_dc_bound = spz_dc_error_bound();
        break;
      case SplatFormat::gltf: out = write_gltf_splats(scene, false); break;
      case SplatFormat::glb: out = write_gltf_splats(scene, true); break;
    }
    io.set("--out", std::move(out));
    report.splats = scene.count;
    report.degree = scene.degree;
  }
  io.commit();
  report.seconds = seconds_since(t0);
  return report;
}

}  // namespace shtool::interop
