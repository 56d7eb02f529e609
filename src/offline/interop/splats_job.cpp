#include "interop/splats_job.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
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

// Why the value `what` (a PLY property's name, or a SplatScene field's) that was finite
// may overflow after the transform: the user's scale or translation when there is one and
// it changes the value (positions, scales), else the rotation itself (|R p| per axis can
// reach sqrt(3) max |p_k|; SH colours, orientations and normals turn alike).
std::string overflow_cause(const TransformSplatsRequest& r, std::string_view what) {
  const bool scaled_or_moved = what == "x" || what == "y" || what == "z" || what == "position" ||
                               what == "scale" || what.starts_with("scale_");
  const bool moved = r.scale != 1 || r.translate[0] != 0 || r.translate[1] != 0 || r.translate[2] != 0;
  return moved && scaled_or_moved ? "--scale or --translate too large for " + r.in.string()
                                  : "a value of " + r.in.string() + " too close to its type's limit to be rotated";
}

std::string upper(std::string_view letters) {
  std::string up;
  for (char c : letters) up.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  return up;
}

// What PLY in, PLY out applies to every splat, in the file's own coordinates: the
// SplatMotion of the request (the orientations turned by its own quaternion when it
// gives one) and the orthogonal map of its SH colours.
struct PlyMotion {
  const OrthogonalMap map;
  const SplatMotion splat;

  static OrthogonalMap make_map(const Eigen::Matrix3d& rot, int degree) {
    Result<OrthogonalMap> made = OrthogonalMap::make(rot, degree + 1, 1e-6);
    if (!made) throw InputError("--matrix: " + made.error().message);
    return std::move(made.value());
  }
  PlyMotion(const TransformSplatsRequest& r, const Eigen::Matrix3d& rot, int degree)
      : map(make_map(rot, degree)),
        splat(rot, r.scale, Eigen::Vector3d(r.translate[0], r.translate[1], r.translate[2]), r.quaternion) {}
};

// Whether a PLY can be rewritten record by record at fixed offsets (rewrite_binary_ply):
// binary in the machine's byte order with every floating-point property float32, as
// 3DGS writes them.
bool rewritable_in_place(const PlyFile& ply, const PlyElement& v) {
  if (ply.format() == PlyFormat::ascii || !ply.native_order()) return false;
  for (const PlyProperty& p : v.properties)
    if (p.type == PlyType::float64) return false;
  return true;
}

// The common 3DGS file, PLY in and out in one frame: streamed from the mapped input into
// the output in pieces of records (rewrite_binary_ply), each value at its known offset
// and the SH colours of SplatShLanes::kLanes splats at once. The same bits and the same
// messages as transform_ply_in_place.
void transform_ply_streamed(const TransformSplatsRequest& r, const Eigen::Matrix3d& rot, std::string_view bytes,
                            const PlyElement& v, const SplatLayout& layout, JobOutputs& io, int threads,
                            TransformSplatsReport& report) {
  const PlyMotion motion(r, rot, layout.degree);
  const SplatShLanes lanes(motion.map);
  const std::size_t size = v.record_size;
  auto at = [&](std::size_t p) { return v.properties[p].offset; };
  std::vector<std::size_t> floats;  // every float property's offset
  for (const PlyProperty& p : v.properties)
    if (p.type == PlyType::float32) floats.push_back(p.offset);
  // The splat values' offsets (all float32 here): each must be finite. Normals and other
  // properties are not splat data and are carried whatever they hold, as into the other
  // formats (which drop them).
  const std::vector<std::size_t> values = splat_value_properties(layout);
  std::vector<std::size_t> checked;
  for (std::size_t p : values) checked.push_back(at(p));
  const std::array<std::size_t, 3> position{at(layout.position[0]), at(layout.position[1]), at(layout.position[2])};
  std::vector<std::size_t> rest;  // f_rest_0.., channel-major as SplatShLanes takes them
  for (std::size_t p : layout.rest) rest.push_back(at(p));
  auto get = [](const char* record, std::size_t offset) {
    float f;
    std::memcpy(&f, record + offset, 4);
    return f;
  };
  auto put = [](char* record, std::size_t offset, double value) {
    const float f = static_cast<float>(value);
    std::memcpy(record + offset, &f, 4);
  };
  // Records of float32 alone (3DGS's) are checked as one run of words, in SIMD lanes;
  // only a run with a value that is not finite is looked at value by value.
  const bool all_float = floats.size() * 4 == size;
  auto finite_run = [](const char* from, std::size_t words) {
    std::uint32_t bad = 0;
    for (std::size_t w = 0; w < words; ++w) {
      std::uint32_t b;
      std::memcpy(&b, from + 4 * w, 4);
      bad |= static_cast<std::uint32_t>((b & 0x7f800000u) == 0x7f800000u);
    }
    return bad == 0;
  };
  auto finite = [&](const char* record) {
    std::uint32_t bad = 0;
    for (std::size_t o : checked) {
      std::uint32_t b;
      std::memcpy(&b, record + o, 4);
      bad |= static_cast<std::uint32_t>((b & 0x7f800000u) == 0x7f800000u);
    }
    return bad == 0;
  };
  // The first of records[0, count) that is not finite, or count.
  auto first_non_finite = [&](const char* records, std::size_t count) {
    if (all_float && finite_run(records, count * floats.size())) return count;
    std::size_t j = 0;
    while (j < count && finite(records + j * size)) ++j;
    return j;
  };
  // The name of the first splat value of a record that is not finite (its message).
  auto non_finite = [&](const char* record) -> const std::string& {
    for (std::size_t p : values)
      if (!std::isfinite(get(record, at(p)))) return v.properties[p].name;
    return v.properties.front().name;
  };
  PendingFile out(io.path("--out"));
  rewrite_binary_ply(bytes, v, out, threads, [&](char* records, std::size_t first, std::size_t count) -> std::string {
    // Up to the first splat whose input is not finite; a splat before it that overflows
    // after the transform is the problem reported, as one splat after another would find.
    const std::size_t limit = first_non_finite(records, count);
    // The first splat whose finite normal the turn took past float, and that component.
    std::size_t normal_overflow = limit;
    int normal_component = 0;
    for (std::size_t j = 0; j < limit; ++j) {
      char* s = records + j * size;
      const Eigen::Vector3d p(get(s, position[0]), get(s, position[1]), get(s, position[2]));
      const Eigen::Vector3d moved = motion.splat.position(p);
      for (int k = 0; k < 3; ++k) put(s, position[k], moved[k]);
      if (layout.normal) {
        const auto& idx = *layout.normal;
        const Eigen::Vector3d n(get(s, at(idx[0])), get(s, at(idx[1])), get(s, at(idx[2])));
        const Eigen::Vector3d turned = motion.splat.normal(n);
        for (int k = 0; k < 3; ++k) put(s, at(idx[k]), turned[k]);
        for (int k = 0; k < 3 && normal_overflow == limit && n.allFinite(); ++k)
          if (!std::isfinite(get(s, at(idx[k])))) normal_overflow = j, normal_component = k;
      }
      if (layout.rotation) {
        const auto& idx = *layout.rotation;
        const Eigen::Quaterniond q(get(s, at(idx[0])), get(s, at(idx[1])), get(s, at(idx[2])), get(s, at(idx[3])));
        const Eigen::Quaterniond turned = motion.splat.orientation(q);
        const double parts[4] = {turned.w(), turned.x(), turned.y(), turned.z()};
        for (int k = 0; k < 4; ++k) put(s, at(idx[k]), parts[k]);
      }
      if (layout.scale && motion.splat.log_s != 0)
        for (int k = 0; k < 3; ++k) {
          const std::size_t o = at((*layout.scale)[k]);
          put(s, o, motion.splat.log_scale(get(s, o)));
        }
    }
    if (!rest.empty()) {
      constexpr std::size_t L = SplatShLanes::kLanes;
      double sh_in[45 * L], sh_out[45 * L];
      for (std::size_t b = 0; b < limit; b += L) {
        const std::size_t n = std::min(L, limit - b);
        char* base = records + b * size;
        if (n == L) {  // the loops over lanes unrolled
          for (std::size_t j = 0; j < rest.size(); ++j)
            for (std::size_t s = 0; s < L; ++s) sh_in[j * L + s] = get(base + s * size, rest[j]);
        } else {
          for (std::size_t j = 0; j < rest.size(); ++j) {
            for (std::size_t s = 0; s < n; ++s) sh_in[j * L + s] = get(base + s * size, rest[j]);
            for (std::size_t s = n; s < L; ++s) sh_in[j * L + s] = 0;
          }
        }
        lanes.apply(sh_in, sh_out);
        if (n == L) {
          for (std::size_t j = 0; j < rest.size(); ++j)
            for (std::size_t s = 0; s < L; ++s) put(base + s * size, rest[j], sh_out[j * L + s]);
        } else {
          for (std::size_t j = 0; j < rest.size(); ++j)
            for (std::size_t s = 0; s < n; ++s) put(base + s * size, rest[j], sh_out[j * L + s]);
        }
      }
    }
    // A finite value beyond float32 (3.4e38) was stored as inf.
    const std::size_t overflow = std::min(first_non_finite(records, limit), normal_overflow);
    for (std::size_t j = overflow; j < limit; ++j)
      if (!finite(records + j * size) || j == normal_overflow) {
        const std::string& name = finite(records + j * size) ? v.properties[(*layout.normal)[normal_component]].name
                                                             : non_finite(records + j * size);
        return "splat " + std::to_string(first + j) + ": '" + name + "' overflows its type after the transform (" +
               overflow_cause(r, name) + ")";
      }
    if (limit < count)
      return r.in.string() + ": splat " + std::to_string(first + limit) + ": '" + non_finite(records + limit * size) +
             "' is not finite";
    return "";
  });
  io.set_written("--out", std::move(out));
  report.splats = v.count;
  report.degree = layout.degree;
}

// PLY in, PLY out in one frame, any encoding: the file's values rewritten in place, every
// other property, the header and the encoding kept.
void transform_ply_in_place(const TransformSplatsRequest& r, const Eigen::Matrix3d& rot, std::string bytes,
                            JobOutputs& io, int threads, TransformSplatsReport& report) {
  PlyFile ply = PlyFile::parse(std::move(bytes), r.in);
  const PlyElement* vertex = ply.element("vertex");
  if (!vertex) throw InputError(r.in.string() + ": no 'vertex' element");
  const PlyElement& v = *vertex;
  const SplatLayout layout = find_splat_layout(v, r.in);
  const PlyMotion motion(r, rot, layout.degree);
  const OrthogonalMap& map = motion.map;
  const SplatMotion& splat = motion.splat;
  const int order = layout.degree + 1;
  const int k_rest = sh_count(order) - 1;

  // One map for every splat, by the reference rotation: exact to rounding at every angle
  // (an identity leaves the colours' bits as they were).
  const std::size_t count = v.count;
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (count + kChunk - 1) / kChunk;
  // The first problem of each chunk; the first chunk's is reported, whatever the threads.
  std::vector<std::string> problems(chunks);
  // The name of the first splat value of splat i that is not finite, or null (normals and
  // other properties are carried whatever they hold).
  const std::vector<std::size_t> values = splat_value_properties(layout);
  auto non_finite = [&](std::size_t i) -> const std::string* {
    for (std::size_t p : values)
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
      // A text value past its float property's range (an ASCII 1e39) is the input's problem.
      for (std::size_t p : values)
        if (v.properties[p].type == PlyType::float32 && !std::isfinite(static_cast<float>(ply.get(v, i, p)))) {
          std::ostringstream value;
          value.precision(9);
          value << ply.get(v, i, p);
          problems[chunk] = r.in.string() + ": splat " + std::to_string(i) + ": '" + v.properties[p].name + "' = " +
                            value.str() + " is past the range of its type, float";
          return;
        }
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = ply.get(v, i, layout.position[k]);
      const Eigen::Vector3d moved = splat.position(p);
      for (int k = 0; k < 3; ++k) ply.set(v, i, layout.position[k], moved[k]);
      if (layout.normal) {
        Eigen::Vector3d n;
        for (int k = 0; k < 3; ++k) n[k] = ply.get(v, i, (*layout.normal)[k]);
        const Eigen::Vector3d turned = splat.normal(n);
        for (int k = 0; k < 3; ++k) ply.set(v, i, (*layout.normal)[k], turned[k]);
        // Carried as they are when not finite, but the turn must not make them so.
        for (int k = 0; k < 3 && n.allFinite(); ++k)
          if (!std::isfinite(ply.get(v, i, (*layout.normal)[k]))) {
            const std::string& name = v.properties[(*layout.normal)[k]].name;
            problems[chunk] = "splat " + std::to_string(i) + ": '" + name +
                              "' overflows its type after the transform (" + overflow_cause(r, name) + ")";
            return;
          }
      }
      if (layout.rotation) {
        const auto& idx = *layout.rotation;
        const Eigen::Quaterniond q(ply.get(v, i, idx[0]), ply.get(v, i, idx[1]), ply.get(v, i, idx[2]),
                                   ply.get(v, i, idx[3]));
        const Eigen::Quaterniond out = splat.orientation(q);
        const double parts[4] = {out.w(), out.x(), out.y(), out.z()};
        for (int k = 0; k < 4; ++k) ply.set(v, i, idx[k], parts[k]);
      }
      if (layout.scale && splat.log_s != 0)
        for (int k = 0; k < 3; ++k)
          ply.set(v, i, (*layout.scale)[k], splat.log_scale(ply.get(v, i, (*layout.scale)[k])));
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
        problems[chunk] = "splat " + std::to_string(i) + ": '" + *name + "' overflows its type after the transform (" +
                          overflow_cause(r, *name) + ")";
        return;
      }
    }
  });
  for (const std::string& problem : problems)
    if (!problem.empty()) throw InputError(problem);
  io.set("--out", ply.format() == PlyFormat::ascii ? ply.bytes() : ply.take_binary_bytes());
  report.splats = count;
  report.degree = layout.degree;
}

// spz's positions share one fixed point: a scene reaching past 2048 units stores every
// position with fewer fractional bits, so a few far splats (often stray outliers of a
// capture) coarsen the whole scene. Says how far, how many, and the step it costs.
std::string coarse_positions_warning(const SplatScene& scene, int bits) {
  std::size_t beyond = 0, farthest = 0;
  float reach = 0;
  for (std::size_t i = 0; i < scene.count; ++i) {
    bool in = true;
    for (int c = 0; c < 3; ++c) {
      const float p = scene.position[3 * i + c];
      in = in && spz_fixed_point_holds(p, kSpzFractionalBits);
      if (std::abs(p) > reach) reach = std::abs(p), farthest = i;
    }
    if (!in) ++beyond;
  }
  std::ostringstream w;
  w << "spz stores positions in 24-bit fixed point: splat " << farthest << " lies " << reach
    << " units from the origin along an axis, and " << beyond << " of " << scene.count
    << " splats lie beyond the 2048 units that " << kSpzFractionalBits << " fractional bits reach, "
    << "so every position is stored with " << bits << " fractional bits, a step of " << std::ldexp(1.0, -bits)
    << " units instead of " << std::ldexp(1.0, -kSpzFractionalBits)
    << " (remove the far splats, or --scale the scene down, to keep the finer step)";
  return w.str();
}

}  // namespace

Eigen::Matrix3d splat_frame(std::string_view letters) {
  const std::string up = upper(letters);
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
  // Options that neither file's format uses are said to do nothing, not refused: a
  // script may pass them for every file it converts.
  const auto is = [&](std::initializer_list<SplatFormat> formats) {
    return std::find(formats.begin(), formats.end(), in_format) != formats.end() ||
           std::find(formats.begin(), formats.end(), out_format) != formats.end();
  };
  const std::string out_kind = std::string(splat_format_name(out_format));
  if (out_format != SplatFormat::spz && r.sh_bits != std::array<int, 2>{5, 4})
    report.warnings.push_back("--sh-bits does nothing here: it sets the SH quantisation of spz output, and " +
                              r.out.string() + " is " + out_kind);
  if (out_format != SplatFormat::spz && r.spz_version != 4)
    report.warnings.push_back("--spz-version does nothing here: it sets the version of spz output, and " +
                              r.out.string() + " is " + out_kind);
  if (!is({SplatFormat::spz}) && upper(r.spz_frame) != "RUB")
    report.warnings.push_back("--spz-frame does nothing here: neither file is spz");
  if (!is({SplatFormat::ply}) && upper(r.ply_frame) != "RDF")
    report.warnings.push_back("--frame (the PLY frame) does nothing here: neither file is PLY");
  if (!is({SplatFormat::gltf, SplatFormat::glb}) && upper(r.gltf_frame) != "RUB")
    report.warnings.push_back("--gltf-frame does nothing here: neither file is glTF");
  if (in_format == SplatFormat::ply && out_format == SplatFormat::ply && !r.sh_degree) {
    report.reflects = rot.determinant() < 0;
    // Mapped, not read: the common file is streamed from the page cache to the output.
    const MappedInput in(r.in, "input");
    const PlyFile header = PlyFile::parse_header(in.bytes(), r.in);
    const PlyElement* vertex = header.element("vertex");
    if (vertex && rewritable_in_place(header, *vertex))
      transform_ply_streamed(r, rot, in.bytes(), *vertex, find_splat_layout(*vertex, r.in), io, threads, report);
    else
      transform_ply_in_place(r, rot, std::string(in.bytes()), io, threads, report);
  } else {
    std::string bytes = read_input_file(r.in, "input");
    SplatScene scene;
    Eigen::Matrix3d in_frame = frame_of(in_format);
    switch (in_format) {
      case SplatFormat::ply: scene = read_ply_splats(PlyFile::parse(std::move(bytes), r.in), r.in, threads); break;
      case SplatFormat::spz: {
        SpzHeader header;
        scene = read_spz(bytes, r.in.string(), &header, threads);
        report.warnings.insert(report.warnings.end(), header.warnings.begin(), header.warnings.end());
        if (header.antialiased) {
          if (out_format == SplatFormat::spz)
            spz.antialiased = true;
          else
            report.warnings.push_back(r.in.string() +
                                      " says its splats were trained with antialiasing (spz flag 0x1): " +
                                      splat_format_name(out_format) + " has no such flag, and " + r.out.string() +
                                      " does not say so (a viewer renders them without the antialiasing filter)");
        }
        if (!header.frame.empty()) {
          // The file names the frame its values are in: that one, not --spz-frame.
          const std::string asked = upper(r.spz_frame);
          if (asked != header.frame && asked != "RUB")
            report.warnings.push_back(r.in.string() + " records its frame, " + header.frame +
                                      " (SPZ_ADOBE_coordinate_system): read in it, not in --spz-frame " + r.spz_frame);
          in_frame = splat_frame(header.frame);
        }
        break;
      }
      case SplatFormat::gltf:
      case SplatFormat::glb: scene = read_gltf_splats(bytes, r.in, threads); break;
    }
    report.degree_in = scene.degree;
    // PLY and spz hold 3DGS's colours, BT.709 sRGB display-referred. The SH of colours in
    // another transfer function have no exact image in it (the transfer function is not
    // linear, the SH are), so such a scene stays in glTF.
    if (scene.colour_space != SplatColourSpace::srgb_rec709_display &&
        (out_format == SplatFormat::ply || out_format == SplatFormat::spz))
      throw InputError(r.in.string() + ": its splats are in the colour space " +
                       splat_colour_space_name(scene.colour_space) + " (KHR_gaussian_splatting colorSpace), and " +
                       splat_format_name(out_format) +
                       " holds SH colours in 3DGS's srgb_rec709_display: SH coefficients cannot be converted between "
                       "transfer functions exactly (write .glb or .gltf, which keep the colour space)");
    const Eigen::Matrix3d frame_change = frame_of(out_format).transpose() * in_frame;
    report.reflects = (frame_change * rot).determinant() < 0;
    const Eigen::Vector3d t(r.translate[0], r.translate[1], r.translate[2]);
    // The user's transform acts in the input's coordinates, then the frame changes.
    transform_splat_scene(scene, frame_change * rot, r.scale, frame_change * t, threads);
    if (r.sh_degree) scene.set_degree(*r.sh_degree);
    // Read values are finite (each reader checks): one that is not was taken past float.
    if (const auto bad = first_non_finite(scene))
      throw InputError("splat " + std::to_string(bad->splat) + ": its " + bad->what +
                       " overflows its type after the transform (" + overflow_cause(r, bad->what) + ")");
    std::string out;
    // A scene the output format cannot hold: named with the files (the splats are counted
    // as in the input).
    try {
      switch (out_format) {
        case SplatFormat::ply:
          out = write_ply_splats(scene);
          break;
        case SplatFormat::spz:
          // A frame other than spz's default is recorded in the file (when the record can name it).
          if (const std::string frame = upper(r.spz_frame); frame != "RUB") {
            spz.coordinate_system = spz_coordinate_system_value(frame);
            if (spz.coordinate_system == 0)
              report.warnings.push_back("--spz-frame " + frame +
                                        ": spz's coordinate-system record names no such frame "
                                        "(only those with x along R or L), so " +
                                        r.out.string() + " records none and readers will take its axes as RUB");
          }
          out = write_spz(scene, spz, threads);
          if (const int bits = spz_fractional_bits(scene); bits < kSpzFractionalBits)
            report.warnings.push_back(coarse_positions_warning(scene, bits));
          report.spz_sh_bound = spz_sh_error_bound(scene.degree, spz);
          report.spz_sh_scene = spz_sh_error_of(scene, spz, threads);
          report.spz_dc_bound = spz_dc_error_bound();
          report.spz_dc_scene = spz_dc_error_of(scene, threads);
          break;
        case SplatFormat::gltf:
          out = write_gltf_splats(scene, false);
          break;
        case SplatFormat::glb:
          out = write_gltf_splats(scene, true);
          break;
      }
    } catch (const InputError& e) {
      throw InputError("--out " + r.out.string() + " (from " + r.in.string() + "): " + e.what());
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
