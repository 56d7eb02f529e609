#include "interop/splat_ply.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#include "common/input_error.h"
#include "common/parallel_for.h"

namespace shtool::interop {

SplatLayout find_splat_layout(const PlyElement& v, const std::filesystem::path& name) {
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
  // SuperSplat's (PlayCanvas's) compressed PLY: chunks of bounds, and vertices of packed
  // 32-bit words (packed_position, packed_rotation, packed_scale, packed_color).
  if (!v.find("x") && v.find("packed_position"))
    throw fail("a compressed PLY (SuperSplat / PlayCanvas: element 'chunk', vertex property 'packed_position'), "
               "which shtool does not support: it reads the 3DGS layout (x, y, z, f_dc_*, ...); decompress the "
               "file first (for example with @playcanvas/splat-transform into .ply)");
  SplatLayout l;
  for (int k = 0; k < 3; ++k) l.position[k] = floats(need(std::string(1, "xyz"[k])));
  l.normal = group(std::array<const char*, 3>{"nx", "ny", "nz"});
  l.rotation = group(std::array<const char*, 4>{"rot_0", "rot_1", "rot_2", "rot_3"});
  l.scale = group(std::array<const char*, 3>{"scale_0", "scale_1", "scale_2"});
  l.dc = group(std::array<const char*, 3>{"f_dc_0", "f_dc_1", "f_dc_2"});
  if (const std::optional<std::size_t> o = v.find("opacity")) l.opacity = floats(*o);
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

std::vector<std::size_t> splat_value_properties(const SplatLayout& l) {
  std::vector<std::size_t> out(l.position.begin(), l.position.end());
  if (l.rotation) out.insert(out.end(), l.rotation->begin(), l.rotation->end());
  if (l.scale) out.insert(out.end(), l.scale->begin(), l.scale->end());
  if (l.dc) out.insert(out.end(), l.dc->begin(), l.dc->end());
  if (l.opacity) out.push_back(*l.opacity);
  out.insert(out.end(), l.rest.begin(), l.rest.end());
  std::sort(out.begin(), out.end());
  return out;
}

SplatScene read_ply_splats(const PlyFile& ply, const std::filesystem::path& name, int threads) {
  const PlyElement* vertex = ply.element("vertex");
  if (!vertex) throw InputError(name.string() + ": no 'vertex' element");
  const PlyElement& v = *vertex;
  const SplatLayout l = find_splat_layout(v, name);
  auto missing = [&](const char* what) {
    return InputError(name.string() + ": the vertex element has no " + what + " (a 3DGS scene needs them)");
  };
  if (!l.rotation) throw missing("rot_0..3");
  if (!l.scale) throw missing("scale_0..2");
  if (!l.dc) throw missing("f_dc_0..2");
  if (!l.opacity) throw missing("opacity");
  SplatScene s;
  s.resize(v.count, l.degree);
  const std::size_t stride = s.sh_stride(), coefficients = stride / 3, k_rest = coefficients - 1;
  constexpr std::size_t kChunk = 4096;
  parallel_for((v.count + kChunk - 1) / kChunk, threads, [&](std::size_t chunk) {
    const std::size_t end = std::min(v.count, (chunk + 1) * kChunk);
    for (std::size_t i = chunk * kChunk; i < end; ++i) {
      for (int k = 0; k < 3; ++k) {
        s.position[3 * i + k] = static_cast<float>(ply.get(v, i, l.position[k]));
        s.log_scale[3 * i + k] = static_cast<float>(ply.get(v, i, (*l.scale)[k]));
        s.sh[i * stride + k] = static_cast<float>(ply.get(v, i, (*l.dc)[k]));
      }
      for (int k = 0; k < 4; ++k) s.rotation[4 * i + k] = static_cast<float>(ply.get(v, i, (*l.rotation)[k]));
      s.opacity[i] = static_cast<float>(ply.get(v, i, *l.opacity));
      for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t k = 0; k < k_rest; ++k)
          s.sh[i * stride + 3 * (k + 1) + c] = static_cast<float>(ply.get(v, i, l.rest[c * k_rest + k]));
    }
  });
  check_scene_finite(s, name.string());
  return s;
}

void rewrite_binary_ply(std::string_view bytes, const PlyElement& e, PendingFile& out, int threads,
                        const PlyRecordEdit& edit) {
  const std::size_t begin = e.data_offset, end = e.data_offset + e.count * e.record_size;
  out.write_at(0, bytes.substr(0, begin));
  out.write_at(end, bytes.substr(end));
  const std::size_t pieces = (e.count + kPlyPiece - 1) / kPlyPiece;
  std::vector<std::string> problems(pieces);
  // The earliest piece with a problem: later ones are skipped, earlier ones all run.
  std::atomic<std::size_t> failed{pieces};
  parallel_for(pieces, threads, [&](std::size_t piece) {
    if (piece > failed.load(std::memory_order_relaxed)) return;
    const std::size_t first = piece * kPlyPiece, count = std::min(e.count, first + kPlyPiece) - first;
    const std::string_view records = bytes.substr(begin + first * e.record_size, count * e.record_size);
    if (!edit) {
      out.write_at(begin + first * e.record_size, records);
      return;
    }
    // One buffer per thread, kept from piece to piece (fresh pages cost more than the copy).
    thread_local std::string buffer;
    buffer.assign(records);
    problems[piece] = edit(buffer.data(), first, count);
    if (!problems[piece].empty()) {
      std::size_t now = failed.load();
      while (piece < now && !failed.compare_exchange_weak(now, piece)) {
      }
      return;
    }
    out.write_at(begin + first * e.record_size, buffer);
  });
  for (const std::string& problem : problems)
    if (!problem.empty()) throw InputError(problem);
}

std::string write_ply_splats(const SplatScene& s) {
  const std::size_t stride = s.sh_stride(), k_rest = stride / 3 - 1;
  std::string h = "ply\nformat binary_little_endian 1.0\ncomment written by shtool transform-splats\nelement vertex " +
                  std::to_string(s.count) + "\n";
  for (const char* n : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    h += std::string("property float ") + n + "\n";
  for (std::size_t k = 0; k < 3 * k_rest; ++k) h += "property float f_rest_" + std::to_string(k) + "\n";
  for (const char* n : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    h += std::string("property float ") + n + "\n";
  h += "end_header\n";
  const std::size_t floats = 9 + 3 * k_rest + 8;
  std::string out(h.size() + s.count * floats * 4, '\0');
  std::memcpy(out.data(), h.data(), h.size());
  char* at = out.data() + h.size();
  std::vector<float> row(floats);
  for (std::size_t i = 0; i < s.count; ++i) {
    std::size_t k = 0;
    for (int c = 0; c < 3; ++c) row[k++] = s.position[3 * i + c];
    for (int c = 0; c < 3; ++c) row[k++] = 0.0f;
    for (int c = 0; c < 3; ++c) row[k++] = s.sh[i * stride + c];
    for (int c = 0; c < 3; ++c)
      for (std::size_t j = 0; j < k_rest; ++j) row[k++] = s.sh[i * stride + 3 * (j + 1) + c];
    row[k++] = s.opacity[i];
    for (int c = 0; c < 3; ++c) row[k++] = s.log_scale[3 * i + c];
    for (int c = 0; c < 4; ++c) row[k++] = s.rotation[4 * i + c];
    if constexpr (std::endian::native == std::endian::little) {
      std::memcpy(at, row.data(), floats * 4);
    } else {
      for (std::size_t j = 0; j < floats; ++j) {
        const auto u = __builtin_bswap32(std::bit_cast<std::uint32_t>(row[j]));
        std::memcpy(at + 4 * j, &u, 4);
      }
    }
    at += floats * 4;
  }
  return out;
}

}  // namespace shtool::interop
