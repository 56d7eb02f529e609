#include "render/render_job.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <embree3/rtcore.h>
#include <nlohmann/json.hpp>

#include "common/job_outputs.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/parallel_for.h"
#include "common/stopwatch.h"
#include "fit/deformation.h"
#include "fit/embree_scene.h"
#include "fit/transfer_file.h"
#include "fit/zh_fit.h"
#include "fit/zh_fit_table.h"
#include "fit/mesh.h"
#include "lighting/image_io.h"
#include "lighting/lighting_output.h"
#include "render/glossy_shading.h"
#include "render/texture_render.h"
#include "fit/texture_bake.h"
#include "render/wrinkle_shading.h"
#include "shtool/glossy.h"
#include "shtool/membrane.h"
#include "shtool/rotation.h"
#include "shtool/zh_fit_table.h"
#include "shtool/zh_shading.h"

namespace shtool::render {
namespace {

using Vec = Eigen::Vector3d;

using lighting::light_channel;

// Per-vertex quantities in the mesh's kept-vertex order.
struct VertexData {
  int transfer_order = 0;
  std::vector<double> transfer;                // V * n^2
  std::optional<ZhFitTable<double>> fit;       // rows reordered to the kept vertices
  std::vector<double> alpha;                   // membrane: transparency per vertex
  std::optional<WrinkleMap<double>> wrinkle;   // wrinkle: the map, and per vertex
  GrooveCoordinates groove;                    // its coordinates
  std::vector<Eigen::Matrix3d> groove_frames;  // and frame
};

// RGB exit radiance per vertex for a transfer- or fit-based shading.
std::vector<double> vertex_radiance(Shading shading, const VertexData& data, const lighting::Lighting& light,
                                    const fit::Mesh& mesh, int table_resolution, int threads) {
  const std::size_t v = mesh.positions.size();
  std::vector<double> out(v * 3, 0.0);
  if (shading == Shading::normals) {
    for (std::size_t k = 0; k < v; ++k)
      for (int c = 0; c < 3; ++c) out[k * 3 + c] = 0.5 * (mesh.normals[k][c] + 1.0);
    return out;
  }
  if (shading == Shading::membrane) {
    const int n = light.order;
    std::vector<double> lobe(n);
    for (int c = 0; c < 3; ++c) {
      const std::vector<double> e = light_channel(light, c, n);
      for (std::size_t k = 0; k < v; ++k) {
        membrane_lobe(data.alpha[k], lobe);
        const Vec3<double> axis = mesh.normals[k];
        out[k * 3 + c] = zh_shade_exact<double>(e, std::span<const Vec3<double>>(&axis, 1), lobe);
      }
    }
    return out;
  }
  if (shading == Shading::wrinkle) {
    const int n = data.wrinkle->order;
    const std::array<std::vector<double>, 3> e = {light_channel(light, 0, n), light_channel(light, 1, n),
                                                   light_channel(light, 2, n)};
    return wrinkle_radiance(*data.wrinkle, data.groove_frames, data.groove, e, threads);
  }
  std::vector<double> from_transfer, from_fit;
  if (shading == Shading::transfer || shading == Shading::error) {
    const int n = data.transfer_order;
    from_transfer.assign(v * 3, 0.0);
    const std::size_t n2 = static_cast<std::size_t>(n) * n;
    for (int c = 0; c < 3; ++c) {
      const std::vector<double> e = light_channel(light, c, n);
      for (std::size_t k = 0; k < v; ++k) {
        double r = 0;
        for (std::size_t i = 0; i < n2; ++i) r += data.transfer[k * n2 + i] * e[i];
        from_transfer[k * 3 + c] = r;
      }
    }
  }
  if (shading == Shading::zh || shading == Shading::zh_table || shading == Shading::error) {
    const ZhFitTable<double>& fit = *data.fit;
    from_fit.assign(v * 3, 0.0);
    for (int c = 0; c < 3; ++c) {
      const std::vector<double> e = light_channel(light, c, fit.order);
      std::optional<ZhLightTable<double>> table;
      if (shading == Shading::zh_table) table.emplace(fit.order, e, table_resolution);
      parallel_for(v, threads, [&](std::size_t k) {
        // [4] Eq. 13 (or its tabulated form), plus the coefficients stored directly.
        double r = table ? table->shade(fit.axes_of(k), fit.coeffs_of(k))
                         : zh_shade_exact<double>(e, fit.axes_of(k), fit.coeffs_of(k));
        const auto direct = fit.direct_of(k);  // at most order^2 (ZhFitTable::from_table)
        for (std::size_t i = 0; i < direct.size() && i < e.size(); ++i) r += direct[i] * e[i];
        from_fit[k * 3 + c] = r;
      });
    }
  }
  if (shading == Shading::transfer) return from_transfer;
  if (shading == Shading::error) {  // signed here; the pixel takes |.| after interpolation
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = from_fit[i] - from_transfer[i];
    return out;
  }
  return from_fit;
}

// What each pixel's primary ray hit: triangle and barycentric weights (triangle -1: none).
struct Hits {
  int width = 0, height = 0;
  std::vector<int> triangle;
  std::vector<double> w1, w2;
  std::size_t covered() const {
    return static_cast<std::size_t>(std::count_if(triangle.begin(), triangle.end(), [](int t) { return t >= 0; }));
  }
};

Hits cast_primary_rays(const fit::Mesh& mesh, const RenderRequest& r, const Camera& camera, int threads) {
  const double aspect = double(r.width) / r.height;
  const Vec eye = view::as_vector(camera.eye);
  const Vec forward = (view::as_vector(camera.target) - eye).normalized();
  const Vec right = forward.cross(view::as_vector(camera.up)).normalized();
  const Vec up = right.cross(forward);
  const double tan_half = std::tan(0.5 * r.fov * std::numbers::pi / 180.0);
  const std::unique_ptr<fit::EmbreeScene> scene = fit::build_scene(mesh);
  Hits hits;
  hits.width = r.width;
  hits.height = r.height;
  const std::size_t pixels = std::size_t(r.width) * r.height;
  hits.triangle.assign(pixels, -1);
  hits.w1.assign(pixels, 0.0);
  hits.w2.assign(pixels, 0.0);
  parallel_for(static_cast<std::size_t>(r.height), threads, [&](std::size_t y) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int x = 0; x < r.width; ++x) {
      // Through the pixel centre; rows top first.
      const double u = (2.0 * (x + 0.5) / r.width - 1.0) * tan_half * aspect;
      const double v = (1.0 - 2.0 * (y + 0.5) / r.height) * tan_half;
      const Vec dir = (forward + u * right + v * up).normalized();
      RTCRayHit hit{};
      hit.ray = scene->ray(eye, dir);
      hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene->scene, &context, &hit);
      if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      const std::size_t p = y * r.width + x;
      hits.triangle[p] = static_cast<int>(hit.hit.primID);
      hits.w1[p] = hit.hit.u;
      hits.w2[p] = hit.hit.v;
    }
  });
  return hits;
}

// Per-vertex RGB interpolated over the hit triangles (|.| after interpolation for an error
// map); alpha is coverage.
lighting::Image shade_panel(const Hits& hits, const fit::Mesh& mesh, const std::vector<double>& radiance,
                            bool absolute) {
  lighting::Image image{hits.width, hits.height, 4,
                        std::vector<float>(std::size_t(hits.width) * hits.height * 4, 0.0f)};
  for (std::size_t p = 0; p < hits.triangle.size(); ++p) {
    if (hits.triangle[p] < 0) continue;
    const Eigen::Vector3i& tri = mesh.triangles[hits.triangle[p]];
    const double w1 = hits.w1[p], w2 = hits.w2[p], w0 = 1.0 - w1 - w2;
    float* px = &image.texels[p * 4];
    for (int c = 0; c < 3; ++c) {
      const double value =
          w0 * radiance[tri[0] * 3 + c] + w1 * radiance[tri[1] * 3 + c] + w2 * radiance[tri[2] * 3 + c];
      px[c] = static_cast<float>(absolute ? std::abs(value) : value);
    }
    px[3] = 1.0f;
  }
  return image;
}

// A 5 x 7 pixel font for the strip's labels: the characters they use.
const char* glyph(char c) {
  switch (c) {
    case '0': return "01110100011001110101110011000101110";
    case '1': return "00100011000010000100001000010001110";
    case '2': return "01110100010000100010001000100011111";
    case '3': return "11111000100010000010000011000101110";
    case '4': return "00010001100101010010111110001000010";
    case '5': return "11111100001111000001000011000101110";
    case '6': return "00110010001000011110100011000101110";
    case '7': return "11111000010001000100010000100001000";
    case '8': return "01110100011000101110100011000101110";
    case '9': return "01110100011000101111000010001001100";
    case '.': return "00000000000000000000000000110001100";
    case '=': return "00000000001111100000111110000000000";
    case 'X': return "10001100010101000100010101000110001";
    case 'A': return "01110100011000111111100011000110001";
    case 'E': return "11111100001000011110100001000011111";
    case 'F': return "11111100001000011110100001000010000";
    case 'H': return "10001100011000111111100011000110001";
    case 'M': return "10001110111010110101100011000110001";
    case 'N': return "10001100011100110101100111000110001";
    case 'O': return "01110100011000110001100011000101110";
    case 'R': return "11110100011000111110101001001010001";
    case 'S': return "01111100001000001110000010000111110";
    case 'T': return "11111001000010000100001000010000100";
    case 'Z': return "11111000010001000100010001000011111";
    default: return "00000000000000000000000000000000000";
  }
}

// Draws `text` in white at (x, y) (top left) with scale x scale pixels per font pixel
// (characters 6 scale apart).
void draw_text(lighting::Image& image, int x, int y, const std::string& text, int scale) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char* g = glyph(text[k]);
    for (int row = 0; row < 7; ++row)
      for (int col = 0; col < 5; ++col) {
        if (g[row * 5 + col] != '1') continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int px = x + static_cast<int>(k) * 6 * scale + col * scale + dx, py = y + row * scale + dy;
            if (px < 0 || py < 0 || px >= image.width || py >= image.height) continue;
            float* t = &image.texels[(std::size_t(py) * image.width + px) * image.channels];
            for (int c = 0; c < 3; ++c) t[c] = 1e3f;  // white after any tone mapping
            t[3] = 1.0f;
          }
      }
  }
}

// [4] Fig. 3's layout: the transfer (ground truth), ZH fits with N = 1..4 lobes fitted
// here at default effort, and the error map of N = 4 (8x), side by side, each panel labelled
// with its normalized RMS over the vertices (sqrt(sum residual^2 / sum |t|^2)).
lighting::Image compare_strip(const Hits& hits, const fit::Mesh& mesh, VertexData& data,
                              const lighting::Lighting& light, int threads, std::vector<double>& nrms) {
  constexpr int kPanels = 6, kLabel = 22;
  const std::vector<double> truth = vertex_radiance(Shading::transfer, data, light, mesh, 32, threads);
  std::vector<lighting::Image> panels;
  panels.push_back(shade_panel(hits, mesh, truth, false));
  std::vector<std::string> labels = {"TRANSFER"};
  std::vector<double> last;
  for (int lobes = 1; lobes <= 4; ++lobes) {
    fit::ZhFitOptions options;
    options.order = data.transfer_order;
    options.lobes = lobes;
    ZhFitTable<double> table = fit::fit_zh_all(data.transfer, options, threads);
    nrms.push_back(fit::normalized_rms(table));
    data.fit = std::move(table);
    last = vertex_radiance(Shading::zh, data, light, mesh, 32, threads);
    panels.push_back(shade_panel(hits, mesh, last, false));
    char text[32];
    std::snprintf(text, sizeof text, "N=%d %.4f", lobes, nrms.back());
    labels.push_back(text);
  }
  // The error is a few percent of the radiance: shown 8x brighter.
  for (std::size_t i = 0; i < last.size(); ++i) last[i] = 8.0 * (last[i] - truth[i]);
  panels.push_back(shade_panel(hits, mesh, last, true));
  labels.push_back("ERROR N=4 X8");
  lighting::Image strip{hits.width * kPanels, hits.height + kLabel, 4,
                        std::vector<float>(std::size_t(hits.width) * kPanels * (hits.height + kLabel) * 4, 0.0f)};
  for (int k = 0; k < kPanels; ++k) {
    for (int y = 0; y < hits.height; ++y)
      std::copy_n(&panels[k].texels[std::size_t(y) * hits.width * 4], std::size_t(hits.width) * 4,
                  &strip.texels[(std::size_t(y) * strip.width + std::size_t(k) * hits.width) * 4]);
  }
  // The label band is opaque black, the labels white.
  for (std::size_t p = std::size_t(hits.height) * strip.width; p < std::size_t(strip.height) * strip.width; ++p)
    strip.texels[p * 4 + 3] = 1.0f;
  // Each label within its panel: half size where the full one would run into the next
  // panel, cut short where even that would.
  for (int k = 0; k < kPanels; ++k) {
    const int room = hits.width - 8, len = static_cast<int>(labels[k].size());
    const int scale = len * 12 <= room ? 2 : 1;
    draw_text(strip, k * hits.width + 4, hits.height + 4, labels[k].substr(0, std::max(0, room / (6 * scale))), scale);
  }
  return strip;
}

}  // namespace

const EnumNames<Shading>& shading_names() {
  using enum Shading;
  static const EnumNames<Shading> names = {
      {"transfer", transfer}, {"zh", zh}, {"zh-table", zh_table}, {"error", error}, {"normals", normals},
      {"membrane", membrane}, {"wrinkle", wrinkle}, {"glossy", glossy}};
  return names;
}

RenderResult run_render(const RenderRequest& r) {
  view::check_view_options(r.width, r.height, r.fov, r.exposure);
  // The image encoders index with int: keep the largest output (the compare strip is six
  // panels wide) far below that.
  if (std::int64_t(r.width) * r.height * (r.compare ? 6 : 1) > (std::int64_t(1) << 26))
    throw InputError("--width x --height: at most 2^26 pixels in the output image");
  if (r.compare && r.shading != Shading::automatic)
    throw InputError("--compare makes its own panels (transfer, ZH fits, error): drop --shading");
  Shading shading = r.compare ? Shading::transfer : r.shading;
  if (shading == Shading::automatic) shading = r.transfer.empty() ? Shading::zh : Shading::transfer;
  const bool needs_transfer = shading == Shading::transfer || shading == Shading::error;
  bool needs_fit = shading == Shading::zh || shading == Shading::zh_table || shading == Shading::error;
  if (shading == Shading::glossy && r.fit.empty()) throw InputError("--shading glossy needs --fit (a fit-glossy table)");
  if (r.compare && r.transfer.empty()) throw InputError("--compare needs --transfer (the ground truth it fits)");
  if (needs_transfer && r.transfer.empty()) throw InputError("this shading needs --transfer");
  if (needs_fit && r.fit.empty()) throw InputError("this shading needs --fit");
  const bool no_bake = shading == Shading::membrane || shading == Shading::normals || shading == Shading::wrinkle;
  if (!no_bake && r.fit.empty() && r.transfer.empty())
    throw InputError("one of --fit and --transfer is required");
  // A bake the image does not use is not read, and said so.
  RenderResult result;
  const bool uses_fit = needs_fit || shading == Shading::glossy;
  const std::string shading_name = name_of(shading, shading_names());
  if (!r.fit.empty() && !uses_fit)
    result.notes.push_back(r.compare ? "--fit is not used: --compare fits its own lobes (N = 1..4) to --transfer"
                                     : "--fit is not used by --shading " + shading_name +
                                           (shading == Shading::transfer ? " (--shading error compares the two)" : ""));
  if (!r.transfer.empty() && !needs_transfer)
    result.notes.push_back("--transfer is not used by --shading " + shading_name);
  if (!(r.alpha >= 0 && r.alpha <= 1)) throw InputError("--alpha must be between 0 and 1");
  if (!r.alpha_map.empty() && shading != Shading::membrane)
    throw InputError("--alpha-map applies to --shading membrane only");
  if (r.alpha != 0 && shading != Shading::membrane) throw InputError("--alpha applies to --shading membrane only");
  if (shading == Shading::wrinkle && (r.wrinkle.empty() || r.wrinkle_map.empty()))
    throw InputError("--shading wrinkle needs --wrinkle (a wrinkle-zh table) and --wrinkle-map (groove coordinates)");
  if (shading != Shading::wrinkle && (!r.wrinkle.empty() || !r.wrinkle_map.empty()))
    throw InputError("--wrinkle and --wrinkle-map apply to --shading wrinkle only");
  if (shading != Shading::normals && r.light.empty()) throw InputError("--light is required");
  view::check_camera(r.camera);
  // Checked before any work, so that a bad output name costs nothing.
  JobOutputs io;
  io.input(r.mesh, "the mesh");
  io.input(r.pose, "the --pose mesh");
  io.input(r.fit, "the --fit table");
  if (!r.fit.empty()) {
    // A texture-space bake's maps, read beside its table.
    io.input(fit::dc_linear_map_path(r.fit), "a map of the --fit bake");
    io.input(fit::lobes_map_path(r.fit), "a map of the --fit bake");
  }
  io.input({{r.transfer, "the --transfer vectors"}, {r.light, "the --light"}, {r.alpha_map, "the --alpha-map"},
            {r.wrinkle, "the --wrinkle table"}, {r.wrinkle_map, "the --wrinkle-map"},
            {r.reference, "the --reference"}});
  io.output(r.out, "--out");
  (void)lighting::encode_image_for(r.out, lighting::Image{1, 1, 4, std::vector<float>(4, 0.0f)}, "--out");

  // The bake is read before the mesh: the mesh is loaded with the normals it was baked
  // with (fit::recorded_normals), so that its frames and checksum are the bake's.
  VertexData data;
  std::optional<Table> fit_table;
  if (uses_fit) {
    Result<Table> read = read_table(r.fit);
    if (!read) throw InputError("--fit: " + read.error().message);
    fit_table = std::move(read).value();
    if (fit_table->kind != kZhFitKind && fit_table->kind != kGlossyZhKind)
      throw InputError("--fit " + r.fit.string() + ": a table of kind " + fit_table->kind +
                       "; render shades a zh-fit (fit-zh, deform) or glossy-zh (fit-glossy) table" +
                       (fit_table->kind == kWrinkleZhKind ? " (a wrinkle table is --wrinkle's)" : ""));
  }
  fit::TransferMeshRecord record;
  if (needs_transfer)
    data.transfer =
        fit::parse_transfer_json(read_input_file(r.transfer, "--transfer"), r.transfer, data.transfer_order, &record);
  const fit::NormalSource normals =
      fit_table ? fit::recorded_normals(*fit_table) : fit::recorded_normals(record.normals);
  const fit::PosedMesh meshes = fit::load_posed_mesh(io, r.mesh, r.pose, r.up, normals);
  const fit::Mesh& rest = meshes.rest;
  const std::optional<fit::Mesh>& posed = meshes.posed;
  const std::vector<Eigen::Matrix3d>& rotations = meshes.rotations;
  const fit::Mesh& mesh = meshes.shown();
  std::optional<GlossyFit<double>> glossy;
  std::vector<Eigen::Matrix3d> frames;  // glossy: the vertex frames of the mesh rendered
  std::optional<ZhFitTable<double>> zh_fit;  // a per-vertex fit-zh bake
  std::optional<TextureBake> texture;        // a fit-zh --texture bake: its maps are sampled per pixel
  if (needs_fit) {
    // Its kind and meta say how it is shaded.
    const Table& table = *fit_table;
    if (table.kind_version.rfind("1.", 0) != 0)
      throw InputError("--fit " + r.fit.string() + ": kind_version " + table.kind_version + " is not supported");
    check_same_up(table, rest.up, "--fit " + r.fit.string(), r.mesh.string());
    fit::check_same_mesh(table, rest, r.mesh, "--fit " + r.fit.string());
    if (table.kind == kGlossyZhKind && r.shading == Shading::automatic) {
      // A fit-glossy table given without --shading is shaded as what it is.
      Result<GlossyFit<double>> g = GlossyFit<double>::from_table(table);
      if (!g) throw InputError("--fit " + r.fit.string() + ": " + g.error().message);
      glossy.emplace(std::move(g).value());
      shading = Shading::glossy;
      needs_fit = false;
    } else {
      Result<ZhFitTable<double>> z = ZhFitTable<double>::from_table(table);
      if (!z) throw InputError("--fit " + r.fit.string() + ": " + z.error().message);
      texture = texture_bake_of(r.fit, table);
      if (!texture) zh_fit.emplace(std::move(z).value());
    }
  }
  if (shading == Shading::glossy) {
    if (!glossy) {
      Result<GlossyFit<double>> g = GlossyFit<double>::from_table(*fit_table);
      if (!g) throw InputError("--fit " + r.fit.string() + ": " + g.error().message);
      check_same_up(*fit_table, rest.up, "--fit " + r.fit.string(), r.mesh.string());
      fit::check_same_mesh(*fit_table, rest, r.mesh, "--fit " + r.fit.string());
      glossy.emplace(std::move(g).value());
    }
    glossy = glossy_fit_for_mesh(std::move(*glossy), rest, "--fit " + r.fit.string());
    if (posed) glossy = deform_glossy_fit(*glossy, rotations);
    frames = fit::vertex_frames(rest, mesh);
  }
  if (needs_transfer) {
    const std::string& transfer_up = record.mesh_up;
    if (!transfer_up.empty() && transfer_up != up_axis_name(rest.up))
      throw InputError("--transfer " + r.transfer.string() + " was simulated on a mesh read " + transfer_up +
                       "-up, but " + r.mesh.string() + " is read " + up_axis_name(rest.up) +
                       "-up: give the --up it was simulated with, " + transfer_up);
    if (record.mesh_crc32)
      fit::check_mesh_crc32(*record.mesh_crc32, record.normals, rest, r.mesh, "--transfer " + r.transfer.string());
    const std::size_t rows = data.transfer.size() / (static_cast<std::size_t>(data.transfer_order) *
                                                     data.transfer_order);
    if (rows != mesh.positions.size())
      throw InputError("--transfer " + r.transfer.string() + ": " + std::to_string(rows) +
                       " vectors for a mesh of " + std::to_string(mesh.positions.size()) + " vertices");
    if (posed) {  // an SH transfer vector rotates exactly, by M(R_p)
      const int n = data.transfer_order;
      const std::size_t n2 = static_cast<std::size_t>(n) * n;
      ShRotation<double> rotation(n, nullptr);
      std::vector<double> turned(n2);
      for (std::size_t v = 0; v < rows; ++v) {
        if (!rotation.set(rotations[v], RotationMethod::reference))
          throw std::logic_error("the reference rotation needs no table");
        rotation.apply(std::span<const double>(data.transfer.data() + v * n2, n2), turned);
        std::copy(turned.begin(), turned.end(), data.transfer.begin() + v * n2);
      }
    }
  }
  if (texture && (shading == Shading::error || posed))
    throw InputError("--fit " + r.fit.string() + " is a texture-space bake: it renders with --shading zh or "
                     "zh-table, without --pose");
  if (texture && mesh.uvs.empty())
    throw InputError(r.mesh.string() + ": no texture coordinates, and --fit " + r.fit.string() +
                     " is a texture-space bake (sampled at the UV of each hit)");
  if (texture && fit::uv_layout_crc32(mesh) != texture->uv_crc32)
    throw InputError(r.mesh.string() + ": its UV layout is not the one --fit " + r.fit.string() +
                     " was baked on (was it baked on another mesh?)");
  if (zh_fit) {
    data.fit = fit::fit_for_mesh(std::move(*zh_fit), rest, "--fit " + r.fit.string());
    if (needs_transfer && data.fit->order != data.transfer_order)
      throw InputError("--fit " + r.fit.string() + " is of order " + std::to_string(data.fit->order) +
                       " and --transfer " + r.transfer.string() + " of order " + std::to_string(data.transfer_order) +
                       ": the error image compares a fit with the vectors it was fitted to");
    if (posed) data.fit = fit::deform_fit(*data.fit, rotations);
  }
  if (shading == Shading::membrane) {
    data.alpha.assign(mesh.positions.size(), r.alpha);
    if (!r.alpha_map.empty()) {
      const nlohmann::json doc = read_json_input(r.alpha_map, "--alpha-map");
      if (!doc.is_object() || !doc.contains("alpha") || !doc["alpha"].is_array() ||
          doc["alpha"].size() != mesh.positions.size())
        throw InputError("--alpha-map " + r.alpha_map.string() + ": expected {\"alpha\": [" +
                         std::to_string(mesh.positions.size()) + " numbers in [0, 1]]}, one per mesh vertex");
      for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
        const nlohmann::json& a = doc["alpha"][k];
        if (!a.is_number() || !(a.get<double>() >= 0 && a.get<double>() <= 1))
          throw InputError("--alpha-map " + r.alpha_map.string() + ": alpha[" + std::to_string(k) +
                           "] is not a number in [0, 1]");
        data.alpha[k] = a.get<double>();
      }
    }
  }
  if (shading == Shading::wrinkle) {
    Result<WrinkleMap<double>> loaded = WrinkleMap<double>::load(r.wrinkle);
    if (!loaded) throw InputError("--wrinkle: " + loaded.error().message);
    data.wrinkle = std::move(loaded).value();
    data.groove = read_groove_coordinates(r.wrinkle_map, mesh, data.wrinkle->max_depth);
    // The frames follow the surface that is drawn: with --pose, the posed one.
    data.groove_frames = groove_frames(mesh, data.groove.x);
  }
  lighting::Lighting light;
  if (shading != Shading::normals) {
    light = lighting::read_lighting_json(r.light, "--light");
    if (light.quantity != lighting::Quantity::radiance)
      throw InputError("--light " + r.light.string() +
                       ": irradiance coefficients; render needs radiance (project-env without --quantity irradiance)");
  }
  const int threads = resolve_threads(r.threads);
  std::optional<lighting::Image> reference;
  if (!r.reference.empty()) {
    if (r.compare) throw InputError("--reference measures one image; --compare makes a strip");
    // A PNG holds tone-mapped, 8-bit values: not radiance to measure against.
    if (r.reference.extension() != ".exr")
      throw InputError("--reference " + r.reference.string() + ": an EXR (linear radiance) is needed");
    reference = lighting::decode_image(read_input_file(r.reference, "--reference"), r.reference);
    // The error is relative to the reference's own size: undefined against black.
    bool any = false;
    for (std::size_t p = 0; p < std::size_t(reference->width) * reference->height && !any; ++p)
      for (int c = 0; c < 3; ++c) any = any || reference->texels[p * reference->channels + c] != 0;
    if (!any)
      throw InputError("--reference " + r.reference.string() +
                       ": every pixel is black, so an error relative to it is undefined; give a render of the "
                       "same view");
  }

  const auto start = std::chrono::steady_clock::now();
  const Camera camera = r.camera ? *r.camera : view::frame_mesh(mesh, r.fov, double(r.width) / r.height);
  const Hits hits = cast_primary_rays(mesh, r, camera, threads);
  result.covered_pixels = hits.covered();
  lighting::Image image;
  if (glossy) {
    result.shading = shading;
    image = glossy_panel({hits.width, hits.height, hits.triangle, hits.w1, hits.w2}, mesh, frames, *glossy, light,
                         view::as_vector(camera.eye), threads);
  } else if (!r.compare) {
    result.shading = shading;
    image = texture ? shade_texture_bake(*texture, mesh, light, hits.width, hits.height, hits.triangle, hits.w1,
                                         hits.w2, shading == Shading::zh_table ? r.zh_table_resolution : 0, threads)
                    : shade_panel(hits, mesh,
                                  vertex_radiance(shading, data, light, mesh, r.zh_table_resolution, threads),
                                  shading == Shading::error);
  } else {
    result.shading = Shading::transfer;
    image = compare_strip(hits, mesh, data, light, threads, result.compare_nrms);
  }
  result.seconds = seconds_since(start);
  result.width = image.width;
  result.height = image.height;
  const int colours = std::min(image.channels, 3);
  for (std::size_t p = 0; p < std::size_t(image.width) * image.height; ++p) {
    const float* px = &image.texels[p * image.channels];
    const float lowest = *std::min_element(px, px + colours);
    if (lowest < 0) ++result.negative_pixels;
    result.minimum = std::min(result.minimum, double(lowest));
  }
  if (reference) {
    if (reference->width != image.width || reference->height != image.height)
      throw InputError("--reference " + r.reference.string() + ": " + std::to_string(reference->width) + " x " +
                       std::to_string(reference->height) + " against an image of " + std::to_string(image.width) +
                       " x " + std::to_string(image.height));
    double difference = 0, norm = 0;
    for (std::size_t p = 0; p < std::size_t(image.width) * image.height; ++p)
      for (int c = 0; c < 3; ++c) {
        const double a = image.texels[p * image.channels + c], b = reference->texels[p * reference->channels + c];
        difference += (a - b) * (a - b);
        norm += b * b;
      }
    result.reference_nrms = std::sqrt(difference / norm);  // norm > 0: checked on reading
  }
  io.set("--out", lighting::encode_image_for(r.out, image, "--out", r.exposure));
  io.commit();
  return result;
}

}  // namespace shtool::render
