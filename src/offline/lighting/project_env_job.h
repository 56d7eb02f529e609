// shtool project-env: an environment image (equirect, cross or six faces; EXR, HDR,
// PNG, JPEG) projected exactly onto SH, then optionally windowed and turned into
// irradiance (docs/lighting.md). The CLI (src/cli/project_env.cpp) fills the request.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/enum_names.h"
#include "lighting/image_io.h"
#include "lighting/lighting_output.h"
#include "shtool/sh_window.h"

namespace shtool::lighting {

enum class Layout { automatic, equirect, cross, faces };
const EnumNames<Layout>& layout_names();

// Equirect mappings of other tools, each an orthogonal map from shtool's own mapping
// (docs/lighting.md has the sources).
enum class EquirectPreset { shtool, three, filament, google };
const EnumNames<EquirectPreset>& equirect_preset_names();

// "auto" joins the windows of the runtime (sh_window.h).
enum class WindowChoice { none, hann, lanczos, sinc4, automatic };
const EnumNames<WindowChoice>& window_names();

struct ProjectEnvRequest {
  std::filesystem::path image;  // for --layout faces: a pattern with %s (px nx py ny pz nz)
  int order = 3;
  Layout layout = Layout::automatic;
  EquirectPreset preset = EquirectPreset::shtool;
  bool mirror_x = false;
  Quantity quantity = Quantity::radiance;
  WindowChoice window = WindowChoice::none;
  std::optional<double> cutoff;  // default: the order
  std::filesystem::path json;
  std::filesystem::path out;  // optional table
  TableEncoding encoding = TableEncoding::binary;
  std::filesystem::path render_back;    // optional equirect image (.exr or .png)
  std::filesystem::path render_source;  // optional: the source as the render-back's equirect
  int threads = 0;
};

struct ProjectEnvReport {
  std::string layout;  // "equirect 4096 x 2048", "cross 3 x 4 faces of 256", ...
  int threads = 1;
  double read_seconds = 0, project_seconds = 0;
  Lighting lighting;
};

ProjectEnvReport run_project_env(const ProjectEnvRequest& request);

// The projection of images already in memory (what run_project_env does after reading):
// one equirect view or six faces in CubeFace order, any number of channels, projected
// exactly in the request's order, preset and mirror_x, then windowed and turned into
// the requested quantity. Coefficients [i * channels + c]; `window` receives the record
// the lighting JSON stores. InputError on a bad size, order or non-finite texel.
std::vector<double> project_env_views(const ProjectEnvRequest& request, std::span<const FloatImageView> views,
                                      int threads, nlohmann::json& window);

// A cross image (4:3 horizontal or 3:4 vertical) cut into six faces (CubeFace order);
// InputError naming `name` for any other shape.
std::array<Image, 6> faces_from_cross(const Image& cross, const std::filesystem::path& name);

// The render-back: the reconstruction sum_i c_i y_i(w) at the texel centres of a W x H
// equirect image in shtool's mapping (rows in parallel).
Image render_equirect(const Lighting& lighting, int width, int height, int threads);

// The source image seen through the same W x H equirect in shtool's mapping, to set
// beside the render-back: each texel takes the source texel its centre's direction falls
// in (no filtering). The source is `equirect` in the mapping `preset` (a texel of the
// preset's mapping shows the direction preset * w of shtool's texel w) when `faces` is
// empty, else the six faces in CubeFace order.
Image source_equirect(const Image& equirect, const Eigen::Matrix3d& preset, const std::vector<Image>& faces,
                      bool mirror_x, int width, int height, int threads);

}  // namespace shtool::lighting
