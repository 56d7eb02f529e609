#include "lighting/project_env_job.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>

#include "common/job_outputs.h"
#include "common/enum_names.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/stopwatch.h"
#include "common/table_writer.h"
#include "shtool/env_projection.h"
#include "shtool/irradiance.h"
#include "shtool/orthogonal_map.h"
#include "shtool/sh.h"

namespace shtool::lighting {
namespace {

// The direction an equirect preset gives a texel, as Q times shtool's own direction of
// that texel (docs/lighting.md, "Equirect mappings"):
//   three     u = atan2(z, x) / 2 pi + 1/2, v = asin(y) / pi + 1/2 in three's y-up frame
//             (equirectUv in three.js' common.glsl.js): shtool's mapping exactly;
//   filament  cmgen's default: CubemapUtils::equirectangularToCubemap (image centre
//             along +z of the y-up frame), then mirrorCubemap (x negated): a quarter
//             turn, w = (s_y, -s_x, s_z);
//   google    google/spherical-harmonics' ImageXToPhi / ImageYToTheta, z up, the
//             azimuth growing to the right: a mirror, w = (-s_x, s_y, s_z).
Eigen::Matrix3d preset_map(EquirectPreset preset) {
  Eigen::Matrix3d q = Eigen::Matrix3d::Identity();
  if (preset == EquirectPreset::filament) q << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  if (preset == EquirectPreset::google) q.diagonal() << -1, 1, 1;
  return q;
}

// Blocks of a projector in parallel into their own partials, added in block order: the
// bytes do not depend on the thread count.
template <class Projector, class Images>
std::vector<double> project_parallel(const Projector& p, const Images& images, int channels, int threads) {
  std::vector<std::vector<double>> partials(p.block_count(), std::vector<double>(p.partial_size(channels), 0.0));
  // Each block's error kept by index, the first block's reported: the same message
  // whatever the thread count.
  std::vector<std::string> errors(partials.size());
  parallel_for(partials.size(), threads, [&](std::size_t b) {
    const Result<Ok> r = p.accumulate_block(images, static_cast<int>(b), partials[b]);
    if (!r) errors[b] = r.error().message;
  });
  for (const std::string& e : errors)
    if (!e.empty()) throw InputError(e);
  std::vector<double> sum(p.partial_size(channels), 0.0);
  for (const std::vector<double>& part : partials)
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += part[i];
  return sum;
}

}  // namespace

// A cross image cut into six faces (CubeFace order). Both layouts put +Y, -X +Z +X, -Y
// in the same places; -Z sits right of +X (horizontal, 4:3) or below -Y turned by 180
// degrees (vertical, 3:4): cmft's imageCubemapFromCross and filament's
// CubemapUtils::crossToCubemap agree on it.
std::array<Image, 6> faces_from_cross(const Image& cross, const std::filesystem::path& name) {
  const bool horizontal = cross.width * 3 == cross.height * 4;
  const bool vertical = cross.width * 4 == cross.height * 3;
  if (!horizontal && !vertical)
    throw InputError(name.string() + ": a cross must be 4:3 (horizontal) or 3:4 (vertical), got " +
                     std::to_string(cross.width) + " x " + std::to_string(cross.height));
  const int size = horizontal ? cross.width / 4 : cross.width / 3;
  // (column, row) of each face in face units, CubeFace order +X -X +Y -Y +Z -Z.
  const std::array<std::array<int, 2>, 6> at = {
      {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, horizontal ? std::array<int, 2>{3, 1} : std::array<int, 2>{1, 3}}};
  std::array<Image, 6> faces;
  for (int f = 0; f < 6; ++f) {
    Image& face = faces[f];
    face.width = face.height = size;
    face.channels = cross.channels;
    face.texels.resize(static_cast<std::size_t>(size) * size * cross.channels);
    const bool turned = vertical && f == static_cast<int>(CubeFace::nz);
    const std::size_t run = static_cast<std::size_t>(size) * cross.channels;
    for (int y = 0; y < size; ++y) {
      const int sy = turned ? size - 1 - y : y;
      const auto src = cross.texels.begin() +
                       (static_cast<std::size_t>(at[f][1] * size + sy) * cross.width + at[f][0] * size) * cross.channels;
      const auto dst = face.texels.begin() + static_cast<std::size_t>(y) * run;
      if (!turned) {
        std::copy_n(src, run, dst);
        continue;
      }
      for (int x = 0; x < size; ++x)
        std::copy_n(src + static_cast<std::size_t>(size - 1 - x) * cross.channels, cross.channels,
                    dst + static_cast<std::size_t>(x) * cross.channels);
    }
  }
  return faces;
}

constexpr std::array<const char*, 6> kFaceSuffix = {"px", "nx", "py", "ny", "pz", "nz"};


const EnumNames<Layout>& layout_names() {
  using enum Layout;
  static const EnumNames<Layout> names = {
      {"auto", automatic}, {"equirect", equirect}, {"cross", cross}, {"faces", faces}};
  return names;
}

const EnumNames<EquirectPreset>& equirect_preset_names() {
  using enum EquirectPreset;
  static const EnumNames<EquirectPreset> names = {
      {"shtool", shtool}, {"three", three}, {"filament", filament}, {"google", google}};
  return names;
}

const EnumNames<WindowChoice>& window_names() {
  using enum WindowChoice;
  static const EnumNames<WindowChoice> names = {
      {"none", none}, {"hann", hann}, {"lanczos", lanczos}, {"sinc4", sinc4}, {"auto", automatic}};
  return names;
}

Image render_equirect(const Lighting& lighting, int width, int height, int threads) {
  Image img;
  img.width = width;
  img.height = height;
  img.texels.resize(static_cast<std::size_t>(width) * height * 3);
  const int n = sh_count(lighting.order);
  parallel_for(static_cast<std::size_t>(height), threads, [&](std::size_t y) {
    std::vector<double> basis(n);
    for (int x = 0; x < width; ++x) {
      const double t = std::numbers::pi * (y + 0.5) / height;
      const double p = std::numbers::pi - 2 * std::numbers::pi * (x + 0.5) / width;
      eval_sh<double>(lighting.order, direction_from_angles(t, p), basis);
      for (int c = 0; c < 3; ++c) {
        double v = 0;
        for (int i = 0; i < n; ++i) v += lighting.coefficients[3 * i + c] * basis[i];
        img.texels[(y * width + x) * 3 + c] = static_cast<float>(v);
      }
    }
  });
  return img;
}

namespace {

// The texel of a W x H equirect in shtool's mapping that direction w falls in.
std::size_t equirect_texel(const Eigen::Vector3d& w, int width, int height) {
  const double t = std::acos(std::clamp(w.z(), -1.0, 1.0)), p = std::atan2(w.y(), w.x());
  const int x = std::clamp(static_cast<int>(std::floor((std::numbers::pi - p) * width / (2 * std::numbers::pi))), 0,
                           width - 1);
  const int y = std::clamp(static_cast<int>(std::floor(t * height / std::numbers::pi)), 0, height - 1);
  return static_cast<std::size_t>(y) * width + x;
}

// The face and texel of an R x R cubemap that direction w (shtool's frame) falls in: the
// inverse of the face table of shtool/env_projection.h.
std::pair<int, std::size_t> cube_texel(const Eigen::Vector3d& w, int size, bool mirror_x) {
  const double X = mirror_x ? -w.x() : w.x(), Y = w.z(), Z = -w.y();  // the y-up cube frame
  const double ax = std::abs(X), ay = std::abs(Y), az = std::abs(Z);
  int face;
  double s, t;
  if (ax >= ay && ax >= az) {
    face = X > 0 ? 0 : 1;
    s = X > 0 ? -Z / ax : Z / ax;
    t = -Y / ax;
  } else if (ay >= az) {
    face = Y > 0 ? 2 : 3;
    s = X / ay;
    t = Y > 0 ? Z / ay : -Z / ay;
  } else {
    face = Z > 0 ? 4 : 5;
    s = Z > 0 ? X / az : -X / az;
    t = -Y / az;
  }
  const auto texel = [size](double u) {
    return std::clamp(static_cast<int>(std::floor((u + 1) / 2 * size)), 0, size - 1);
  };
  return {face, static_cast<std::size_t>(texel(t)) * size + texel(s)};
}

}  // namespace

Image source_equirect(const Image& equirect, const Eigen::Matrix3d& preset, const std::vector<Image>& faces,
                      bool mirror_x, int width, int height, int threads) {
  Image img;
  img.width = width;
  img.height = height;
  img.texels.resize(static_cast<std::size_t>(width) * height * 3);
  parallel_for(static_cast<std::size_t>(height), threads, [&](std::size_t y) {
    for (int x = 0; x < width; ++x) {
      const double t = std::numbers::pi * (y + 0.5) / height;
      const double p = std::numbers::pi - 2 * std::numbers::pi * (x + 0.5) / width;
      const Eigen::Vector3d w = direction_from_angles(t, p);
      const float* texel;
      if (faces.empty()) {
        // The preset's texel showing w is shtool's texel of Q^T w.
        texel = &equirect.texels[equirect_texel(preset.transpose() * w, equirect.width, equirect.height) *
                                 equirect.channels];
      } else {
        const auto [face, at] = cube_texel(w, faces[0].width, mirror_x);
        texel = &faces[face].texels[at * faces[face].channels];
      }
      std::copy_n(texel, 3, img.texels.begin() + (y * width + x) * 3);
    }
  });
  return img;
}

std::vector<double> project_env_views(const ProjectEnvRequest& r, std::span<const FloatImageView> views, int threads,
                                      nlohmann::json& window) {
  if (views.size() != 1 && views.size() != 6) throw InputError("an environment is one equirect image or six faces");
  const int channels = views[0].channels;
  for (const FloatImageView& v : views)
    if (v.channels != channels) throw InputError("the six faces must have the same channels");
  if (r.order < 1 || r.order > kMaxEnvOrder)
    throw InputError("order " + std::to_string(r.order) + " is outside 1.." + std::to_string(kMaxEnvOrder));
  std::vector<double> coefficients;
  if (views.size() == 1) {
    Result<EquirectProjector> p = EquirectProjector::create(views[0].width, views[0].height, r.order);
    if (!p) throw InputError(p.error().message);
    coefficients = project_parallel(p.value(), views[0], channels, threads);
    if (r.preset != EquirectPreset::shtool) {
      const Result<Ok> m = apply_orthogonal_map(preset_map(r.preset), channels, coefficients);
      if (!m) throw InputError(m.error().message);
    }
  } else {
    for (const FloatImageView& v : views)
      if (v.width != views[0].width || v.height != v.width)
        throw InputError("the six faces must be square and of one size");
    Result<CubemapProjector> p = CubemapProjector::create(views[0].width, r.order, r.mirror_x);
    if (!p) throw InputError(p.error().message);
    coefficients = project_parallel(p.value(), std::span<const FloatImageView, 6>(views.data(), 6), channels, threads);
  }

  // ---- window, then quantity (both zonal: they commute)
  std::vector<double> factors(r.order, 1.0);
  if (r.window == WindowChoice::automatic) {
    const Result<AutoWindow> w = choose_auto_window(coefficients, channels);
    if (!w) throw InputError(w.error().message);
    factors = w.value().factors;
    window = {{"type", "auto"}, {"shape", "sinc4"}, {"factors", factors}, {"minimum", w.value().minimum}};
    window["cutoff"] = w.value().cutoff ? nlohmann::json(*w.value().cutoff) : nlohmann::json(nullptr);
  } else if (r.window != WindowChoice::none) {
    const ShWindow shape = *sh_window_from_name(name_of(r.window, window_names()));
    const double cutoff = r.cutoff.value_or(r.order);
    factors = sh_window_factors(shape, cutoff, r.order);
    window = {{"type", sh_window_name(shape)}, {"cutoff", cutoff}, {"factors", factors}};
  } else {
    window = {{"type", "none"}};
  }
  scale_bands(factors, channels, coefficients);
  if (r.quantity == Quantity::irradiance) radiance_to_irradiance(channels, coefficients);
  return coefficients;
}

ProjectEnvReport run_project_env(const ProjectEnvRequest& r) {
  if (r.order < 1 || r.order > kMaxEnvOrder)
    throw InputError("--order " + std::to_string(r.order) + " is outside 1.." + std::to_string(kMaxEnvOrder));
  if (r.json.empty()) throw InputError("--json is required");
  if (r.cutoff && !(*r.cutoff > 0 && std::isfinite(*r.cutoff)))
    throw InputError("--cutoff must be a positive number");
  if (r.cutoff && (r.window == WindowChoice::none || r.window == WindowChoice::automatic))
    throw InputError("--cutoff applies to --window hann, lanczos or sinc4");
  const bool pattern = r.image.string().find("%s") != std::string::npos;
  if (r.layout == Layout::faces && !pattern)
    throw InputError("--layout faces needs an image pattern with %s (replaced by px nx py ny pz nz)");
  const Layout layout_choice = r.layout == Layout::automatic && pattern ? Layout::faces : r.layout;
  if (r.preset != EquirectPreset::shtool && (layout_choice == Layout::cross || layout_choice == Layout::faces))
    throw InputError("--equirect-preset applies to equirect images");
  JobOutputs io;
  if (pattern) {
    const std::string text = r.image.string();
    const std::size_t at = text.find("%s");
    for (const char* suffix : kFaceSuffix)
      io.input(text.substr(0, at) + suffix + text.substr(at + 2), "a face of the environment");
  } else {
    io.input(r.image, "the environment image");
  }
  io.output(r.json, "--json");
  io.output(r.out, "--out");
  io.output(r.render_back, "--render-back");
  io.output(r.render_source, "--render-source");
  // The extensions, early.
  if (io.requested("--render-back")) encode_image_for(r.render_back, Image{1, 1, 3, {0, 0, 0}}, "--render-back");
  if (io.requested("--render-source"))
    encode_image_for(r.render_source, Image{1, 1, 3, {0, 0, 0}}, "--render-source");
  const int threads = resolve_threads(r.threads);
  ProjectEnvReport report;
  report.threads = threads;

  // ---- read
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json inputs;
  std::vector<Image> faces;
  Image equirect;
  Layout layout = layout_choice;
  if (layout == Layout::faces) {
    std::string text = r.image.string();
    const std::size_t at = text.find("%s");
    inputs = nlohmann::json::array();
    for (const char* suffix : kFaceSuffix) {
      const std::filesystem::path path = text.substr(0, at) + suffix + text.substr(at + 2);
      ImageFile f = read_image(path, "image", threads);
      inputs.push_back({{"image", path.filename().string()}, {"input_crc32", f.crc32}});
      faces.push_back(std::move(f.image));
    }
    for (const Image& f : faces)
      if (f.width != faces[0].width || f.height != faces[0].height || f.width != f.height)
        throw InputError("the six faces of '" + text + "' must be square and of one size (" +
                         std::to_string(faces[0].width) + " x " + std::to_string(faces[0].height) + " and " +
                         std::to_string(f.width) + " x " + std::to_string(f.height) + " given)");
    report.layout = "faces " + std::to_string(faces[0].width) + " x " + std::to_string(faces[0].width);
  } else {
    ImageFile f = read_image(r.image, "image", threads);
    inputs = {{"image", r.image.filename().string()}, {"input_crc32", f.crc32}};
    const Image& img = f.image;
    if (layout == Layout::automatic) {
      if (img.width == 2 * img.height) layout = Layout::equirect;
      else if (img.width * 3 == img.height * 4 || img.width * 4 == img.height * 3) layout = Layout::cross;
      else
        throw InputError(r.image.string() + ": " + std::to_string(img.width) + " x " + std::to_string(img.height) +
                         " is neither an equirect (2:1) nor a cross (4:3 or 3:4); --layout faces reads six files");
    }
    if (layout == Layout::equirect) {
      if (img.width != 2 * img.height)
        throw InputError(r.image.string() + ": an equirect image must be 2:1, got " + std::to_string(img.width) +
                         " x " + std::to_string(img.height));
      equirect = std::move(f.image);
      report.layout = "equirect " + std::to_string(equirect.width) + " x " + std::to_string(equirect.height);
    } else {
      const std::array<Image, 6> cut = faces_from_cross(img, r.image);
      faces.assign(cut.begin(), cut.end());
      report.layout = std::string(img.width > img.height ? "horizontal" : "vertical") + " cross, faces " +
                      std::to_string(faces[0].width) + " x " + std::to_string(faces[0].width);
    }
  }
  if (r.preset != EquirectPreset::shtool && layout != Layout::equirect)
    throw InputError("--equirect-preset applies to equirect images, not to " + report.layout);
  if (r.mirror_x && layout == Layout::equirect) throw InputError("--mirror-x applies to cubemaps, not to equirect images");
  report.read_seconds = seconds_since(t0);

  // ---- project
  const auto t1 = std::chrono::steady_clock::now();
  Lighting& out = report.lighting;
  out.order = r.order;
  out.quantity = r.quantity;
  std::vector<FloatImageView> views;
  if (layout == Layout::equirect) views.push_back(equirect.view());
  for (const Image& f : faces) views.push_back(f.view());
  try {
    out.coefficients = project_env_views(r, views, threads, out.window);
  } catch (const InputError& e) {
    throw InputError(r.image.string() + ": " + e.what());
  }
  report.project_seconds = seconds_since(t1);

  // ---- outputs, all or none
  nlohmann::json params = {{"order", r.order},
                           {"layout", name_of(layout, layout_names())},
                           {"quantity", quantity_name(r.quantity)},
                           {"window", name_of(r.window, window_names())}};
  if (layout == Layout::faces) params["faces"] = inputs;
  else {
    params["image"] = inputs["image"];
    params["input_crc32"] = inputs["input_crc32"];
  }
  if (layout == Layout::equirect) params["equirect_preset"] = name_of(r.preset, equirect_preset_names());
  else params["mirror_x"] = r.mirror_x;
  if (r.cutoff) params["cutoff"] = *r.cutoff;
  io.set("--json", lighting_json(out));
  if (io.requested("--out"))
    io.set("--out", encode_table(lighting_table(out, generator_record("shtool project-env", params)), r.encoding));
  // The render-back and the source share a size, so they can be set side by side.
  const int h = std::clamp(layout == Layout::equirect ? equirect.height : 2 * faces[0].width, 256, 1024);
  if (io.requested("--render-back"))
    io.set("--render-back", encode_image_for(r.render_back, render_equirect(out, 2 * h, h, threads), "--render-back"));
  if (io.requested("--render-source"))
    io.set("--render-source",
           encode_image_for(r.render_source,
                            source_equirect(equirect, preset_map(r.preset), faces, r.mirror_x, 2 * h, h, threads),
                            "--render-source"));
  io.commit();
  return report;
}

}  // namespace shtool::lighting
