#include "interop/splat_scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "common/input_error.h"

namespace shtool::interop {

void SplatScene::set_degree(int deg) {
  if (deg == degree) return;
  const std::size_t from = sh_stride();
  const std::size_t to = 3 * static_cast<std::size_t>((deg + 1) * (deg + 1));
  std::vector<float> out(to * count, 0.0f);
  const std::size_t keep = std::min(from, to);
  for (std::size_t i = 0; i < count; ++i)
    std::copy_n(sh.begin() + static_cast<std::ptrdiff_t>(i * from), keep, out.begin() + static_cast<std::ptrdiff_t>(i * to));
  sh = std::move(out);
  degree = deg;
}

SplatFormat splat_format_of(const std::filesystem::path& path, const std::string& what) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".ply") return SplatFormat::ply;
  if (ext == ".spz") return SplatFormat::spz;
  if (ext == ".gltf") return SplatFormat::gltf;
  if (ext == ".glb") return SplatFormat::glb;
  throw InputError(what + " " + path.string() + ": unknown splat format '" + ext +
                   "' (.ply, .spz, .gltf or .glb by extension)");
}

const char* splat_format_name(SplatFormat format) {
  switch (format) {
    case SplatFormat::ply: return "PLY";
    case SplatFormat::spz: return "spz";
    case SplatFormat::gltf: return "glTF";
    case SplatFormat::glb: return "glb";
  }
  return "?";
}

void check_scene_finite(const SplatScene& s, const std::string& name) {
  const std::size_t stride = s.sh_stride();
  for (std::size_t i = 0; i < s.count; ++i) {
    auto bad = [&](const std::vector<float>& v, std::size_t per, const char* what) {
      for (std::size_t k = 0; k < per; ++k)
        if (!std::isfinite(v[i * per + k]))
          throw InputError(name + ": splat " + std::to_string(i) + ": its " + what + " is not finite");
    };
    bad(s.position, 3, "position");
    bad(s.log_scale, 3, "scale");
    bad(s.rotation, 4, "rotation");
    bad(s.opacity, 1, "opacity");
    bad(s.sh, stride, "SH colour");
  }
}

}  // namespace shtool::interop
