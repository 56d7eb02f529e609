#include "web/export_web_job.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <system_error>

#include <nlohmann/json.hpp>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/job_outputs.h"
#include "fit/deformation.h"
#include "fit/mesh.h"
#include "fit/zh_fit_gltf.h"
#include "interop/three_probe_grid.h"
#include "lighting/lighting_output.h"
#include "shaders/shader_source.h"
#include "shtool/probe_grid.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "shtool/version.h"
#include "shtool/zh_fit_table.h"
#include "web/web_assets.h"

namespace shtool::web {
namespace {

using Vec = Eigen::Vector3d;

// shtool's frame to glTF's (and three's): (x, y, z) -> (x, z, -y), a rotation.
Eigen::Matrix3d to_gltf() {
  Eigen::Matrix3d c;
  c << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return c;
}

nlohmann::json vec_json(const Vec& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }
// WebGL2 guarantees 16 vertex attributes: the position, each lobe's axis and coefficient
// groups, the stored coefficients.
constexpr int kMaxVertexAttributes = 16;

// The three.js files the page loads, relative to the package folder and to DIR/three.
const std::vector<std::string>& three_files() {
  static const std::vector<std::string> files = {"LICENSE", "package.json", "build/three.module.js",
                                                 "build/three.core.js",
                                                 "examples/jsm/lighting/LightProbeGridWebGL.js",
                                                 "examples/jsm/lighting/LightProbeGridUtils.js"};
  return files;
}

}  // namespace

ExportWebResult run_export_web(const ExportWebRequest& r) {
  view::check_view_options(r.width, r.height, r.fov, r.exposure);
  if (r.fit.empty()) throw InputError("--fit is required");
  if (r.light.empty()) throw InputError("--light is required");
  if (r.out.empty()) throw InputError("--out: an output folder is required");
  view::check_camera(r.camera);
  check_output_folder(r.out, "--out");
  std::error_code ec;

  const std::filesystem::path three = three_package_dir();
  if (!three.empty() && !std::filesystem::is_regular_file(three / "package.json", ec))
    throw InputError("three.js was not found at " + three.string() +
                     " ($SHTOOL_THREE_DIR): it must be the folder of the npm package three@" + interop::kThreeVersion +
                     ", with its package.json");
  if (three.empty())
    throw InputError("three.js " + std::string(interop::kThreeVersion) +
                     " was not found: set SHTOOL_THREE_DIR to the npm package's folder (npm install three@" +
                     interop::kThreeVersion + "), or run the tests once in the build tree, which install it");
  const std::filesystem::path web = web_source_dir();
  if (web.empty())
    throw InputError("shtool's page files (export-web.html, shtool-three.js) were not found: set SHTOOL_WEB_DIR to "
                     "the source tree's web/ folder");
  {
    const nlohmann::json package = read_json_input(three / "package.json", "three.js's package.json");
    if (!package.is_object() || package.value("version", std::string()) != interop::kThreeVersion)
      throw InputError((three / "package.json").string() + ": three " +
                       (package.is_object() ? package.value("version", std::string("?")) : std::string("?")) +
                       ", but the page is written for three " + interop::kThreeVersion);
  }

  JobOutputs io;  // inputs first: an output must not replace one of them
  io.input(r.mesh, "the mesh");
  io.input(r.pose, "the --pose mesh");
  io.input(r.fit, "the --fit table");
  io.input(r.light, "the --light");
  io.input(r.probes, "the --probes grid");

  Result<Table> read = read_table(r.fit);
  if (!read) throw InputError("--fit: " + read.error().message);
  const Table& table = read.value();
  if (table.kind != kZhFitKind)
    throw InputError("--fit " + r.fit.string() + ": a table of kind " + table.kind +
                     "; export-web shades a per-vertex zh-fit (fit-zh --out)");
  const fit::PosedMesh meshes = fit::load_posed_mesh(io, r.mesh, r.pose, r.up, fit::recorded_normals(table));
  const fit::Mesh& mesh = meshes.shown();

  check_same_up(table, meshes.rest.up, "--fit " + r.fit.string(), r.mesh.string());
  fit::check_same_mesh(table, meshes.rest, r.mesh, "--fit " + r.fit.string());
  {
    const nlohmann::json meta = nlohmann::json::parse(table.meta, nullptr, false);
    if (meta.is_object() && meta.contains("texture"))
      throw InputError("--fit " + r.fit.string() +
                       " is a texture-space bake: export-web takes a per-vertex fit (render shades texture bakes)");
  }
  Result<ZhFitTable<double>> z = ZhFitTable<double>::from_table(table);
  if (!z) throw InputError("--fit " + r.fit.string() + ": " + z.error().message);
  ZhFitTable<double> fit = fit::fit_for_mesh(std::move(z).value(), meshes.rest, "--fit " + r.fit.string());
  if (meshes.posed) fit = fit::deform_fit(fit, meshes.rotations);
  const int order = fit.order, lobes = fit.lobes;
  const int lo = std::max(shader_min_order(ShaderOperation::zxzxz_rotate), shader_min_order(ShaderOperation::zh_shade));
  const int hi = std::min(shader_max_order(ShaderOperation::zxzxz_rotate), shader_max_order(ShaderOperation::zh_shade));
  if (order < lo || order > hi)
    throw InputError("--fit " + r.fit.string() + ": order " + std::to_string(order) +
                     "; the page's generated shaders (zxzxz-rotate, zh-shade) take orders " + std::to_string(lo) +
                     ".." + std::to_string(hi));
  if (lobes < 1 || lobes > 16)
    throw InputError("--fit " + r.fit.string() + ": " + std::to_string(lobes) +
                     " lobes; the generated zh-shade takes 1..16");
  const int groups = (order + 3) / 4;
  const int attributes = 1 + lobes * (1 + groups) + (fit.direct_count > 0 ? 1 : 0);
  if (attributes > kMaxVertexAttributes)
    throw InputError("--fit " + r.fit.string() + ": " + std::to_string(lobes) + " lobes of order " +
                     std::to_string(order) + " need " + std::to_string(attributes) +
                     " vertex attributes; WebGL2 guarantees " + std::to_string(kMaxVertexAttributes));

  const lighting::Lighting light = lighting::read_lighting_json(r.light, "--light");
  if (light.quantity != lighting::Quantity::radiance)
    throw InputError("--light " + r.light.string() +
                     ": irradiance coefficients; the page shades radiance (project-env without --quantity irradiance)");
  if (light.order > hi)
    throw InputError("--light " + r.light.string() + ": order " + std::to_string(light.order) +
                     "; the page's generated rotation (zxzxz-rotate) takes orders up to " + std::to_string(hi));

  std::optional<ProbeGrid<double>> probes;
  if (!r.probes.empty()) {
    Result<ProbeGrid<double>> g = ProbeGrid<double>::load(r.probes);
    if (!g) throw InputError("--probes: " + g.error().message);
    if (g.value().encoding == ProbeEncoding::l1)
      throw InputError("--probes: an l1 grid: " + std::string(interop::kThreeCannotShowL1));
    probes.emplace(std::move(g).value());
  }

  // The light at the fit's order (truncated or padded, as render takes it), turned into
  // glTF's frame: the page works in three's y-up world, where the lobes are.
  const Eigen::Matrix3d c = to_gltf();
  nlohmann::json light_json = nlohmann::json::object();
  {
    ShRotation<double> rotation(order, nullptr);
    if (!rotation.set(c, RotationMethod::reference)) throw std::logic_error("the reference rotation needs no table");
    const char* names[3] = {"r", "g", "b"};
    for (int ch = 0; ch < 3; ++ch) {
      const std::vector<double> e = lighting::light_channel(light, ch, order);
      std::vector<double> turned(e.size());
      rotation.apply(std::span<const double>(e), std::span<double>(turned));
      for (std::size_t i = 0; i < turned.size(); ++i)
        if (!finite_as_float(turned[i]))
          throw InputError("--light " + r.light.string() + ": coefficient " + std::to_string(i) + " of channel " +
                           names[ch] + " is " + message_number(turned[i]) +
                           " in three's frame, beyond float32's range: the page shades in float");
      light_json[names[ch]] = turned;
    }
  }

  // render's camera for the same options, in three's frame.
  const view::Camera camera = r.camera ? *r.camera : view::frame_mesh(mesh, r.fov, double(r.width) / r.height);
  const view::MeshBounds bounds = view::mesh_bounds(mesh);
  const Vec& centre = bounds.centre;
  const double radius = bounds.radius;
  double extent = radius;  // of everything drawn, round the mesh's centre
  nlohmann::json scene = nlohmann::json::object();
  std::vector<std::string> warnings;  // printed by the caller
  if (probes) {
    const Vec pmin = probes->min, pmax = probes->max;
    for (int k = 0; k < 8; ++k) {
      const Vec corner((k & 1) ? pmax.x() : pmin.x(), (k & 2) ? pmax.y() : pmin.y(), (k & 4) ? pmax.z() : pmin.z());
      extent = std::max(extent, (corner - centre).norm());
    }
    // A ground under the mesh across the grid's box, and spheres beside the mesh, on the
    // ground, right and left of the view and behind, kept inside the box.
    const double ground = std::clamp(bounds.lo.z(), pmin.z(), pmax.z());
    // three samples the grid half a cell along the normal and leaves a point whose sample
    // falls outside the box unlit: the spheres' undersides go black where the box ends
    // less than half a cell below the ground, and any part of a sphere less than half a
    // cell from the box's other faces would too.
    const Vec cell = (pmax - pmin).cwiseQuotient(
        Vec(probes->resolution[0], probes->resolution[1], probes->resolution[2]));
    const Vec half_cell = 0.5 * cell;
    if (bounds.lo.z() < pmin.z())
      warnings.push_back("the probe grid's box starts " + message_number(pmin.z() - bounds.lo.z()) +
                         " above the mesh's lowest point: the page's ground is at the box's bottom, and three.js "
                         "leaves the spheres' undersides unlit; bake with --bounds reaching at least half a cell (" +
                         message_number(half_cell.z()) + ") below the mesh");
    else if (ground - half_cell.z() < pmin.z() - 0.01 * cell.z())
      warnings.push_back("the probe grid's box ends " + message_number(ground - pmin.z()) +
                         " below the ground, less than half a cell (" + message_number(half_cell.z()) +
                         "): three.js leaves the spheres' undersides unlit; bake with --bounds reaching at "
                         "least half a cell below the ground");
    // The atlas stacks 7 (NY + 2) slices of a 3D texture (three's z is shtool's y).
    const int depth = 7 * (probes->resolution[1] + 2);
    const char* axis_names[3] = {"x", "y", "z"};
    const int sides[3] = {probes->resolution[0], depth, probes->resolution[2]};
    for (int a = 0; a < 3; ++a)
      if (sides[a] > 256)
        warnings.push_back("the probe atlas is " + std::to_string(probes->resolution[0]) + " x " +
                           std::to_string(probes->resolution[2]) + " x " + std::to_string(depth) +
                           " texels, and its side for the grid's " + axis_names[a] + " (" + std::to_string(sides[a]) +
                           " texels) passes the 256 WebGL2 guarantees (at most 256 probes along x or z, 34 along "
                           "y): a WebGL with a smaller MAX_3D_TEXTURE_SIZE refuses the page");
    const Vec forward = (view::as_vector(camera.target) - view::as_vector(camera.eye)).normalized();
    Vec right = forward.cross(Vec::UnitZ());
    if (right.norm() < 1e-9) right = Vec::UnitX();
    right.normalize();
    Vec back = Vec::UnitZ().cross(right).normalized();
    // Each sphere at least half a cell inside every face of the box, so that three lights
    // all of it: smaller than a quarter of the mesh's radius where the box is too narrow.
    const double room = (0.5 * (pmax - pmin) - half_cell).minCoeff();
    const double s = std::min(0.25 * radius, 0.9 * room);
    nlohmann::json spheres = nlohmann::json::array();
    if (s > 0) {
      const Vec lo = pmin + half_cell + Vec::Constant(s), hi = pmax - half_cell - Vec::Constant(s);
      for (const Vec& offset : {Vec(1.5 * radius * right), Vec(-1.5 * radius * right), Vec(1.6 * radius * back)}) {
        Vec p = centre + offset;
        p.z() = ground + s;
        p = p.cwiseMax(lo).cwiseMin(hi);
        spheres.push_back({{"centre", vec_json(c * p)}, {"radius", s}});
      }
    }
    const Vec ground_centre(0.5 * (pmin.x() + pmax.x()), 0.5 * (pmin.y() + pmax.y()), ground);
    scene["probes"] = "probes/probes.json";
    scene["ground"] = {{"centre", vec_json(c * ground_centre)},
                       {"size", {pmax.x() - pmin.x(), pmax.y() - pmin.y()}}};
    scene["spheres"] = spheres;
  }
  const double distance = (view::as_vector(camera.eye) - centre).norm();
  const double near = std::max(0.5 * (distance - extent), 1e-4 * (distance + extent));
  const double far = 2 * (distance + extent);
  scene["camera"] = {{"eye", vec_json(c * view::as_vector(camera.eye))},
                     {"target", vec_json(c * view::as_vector(camera.target))},
                     {"up", vec_json(c * view::as_vector(camera.up))},
                     {"fov", r.fov},
                     {"near", near},
                     {"far", far}};
  scene["width"] = r.width;
  scene["height"] = r.height;
  scene["exposure"] = r.exposure;
  scene["order"] = order;
  scene["lobes"] = lobes;
  scene["direct"] = fit.direct_count;
  scene["mesh"] = "mesh.glb";
  scene["source"] = {{"mesh", r.mesh.filename().string()}, {"up", up_axis_name(meshes.rest.up)},
                     {"fit", r.fit.filename().string()}, {"light", r.light.filename().string()}};
  if (!r.pose.empty()) scene["source"]["pose"] = r.pose.filename().string();
  if (!r.probes.empty()) scene["source"]["probes"] = r.probes.filename().string();
  scene["light"] = light_json;
  scene["shaders"] = {{"rotate", "shtool-rotate.glsl"}, {"shade", "shtool-zh-shade.glsl"}};
  scene["three"] = interop::kThreeVersion;
  scene["generator"] = std::string("shtool ") + kVersion + " export-web";

  // The shaders, from the library functions gen-shader writes them with.
  ShaderRequest rotate_request;
  rotate_request.operation = ShaderOperation::zxzxz_rotate;
  rotate_request.order = order;
  rotate_request.command = "shtool gen-shader --lang glsl --what zxzxz-rotate --order " + std::to_string(order) +
                           " --precision float --out shtool-rotate.glsl";
  ShaderRequest shade_request;
  shade_request.operation = ShaderOperation::zh_shade;
  shade_request.order = order;
  shade_request.zh_lobes = lobes;
  shade_request.command = "shtool gen-shader --lang glsl --what zh-shade --order " + std::to_string(order) +
                          " --zh-lobes " + std::to_string(lobes) + " --precision float --out shtool-zh-shade.glsl";

  // The grey of COLOR_0: the fitted transfer's DC (each lobe adds g_i0 y_0^0).
  std::vector<double> dc(fit.vertices, 0.0);
  const double y00 = 0.5 / std::sqrt(std::numbers::pi);
  for (std::size_t v = 0; v < fit.vertices; ++v) {
    for (int k = 0; k < lobes; ++k) dc[v] += fit.coeffs_of(v)[std::size_t(k) * order] * y00;
    if (fit.direct_count > 0) dc[v] += fit.direct_of(v)[0];
  }

  // Bytes first, then the folders and the commit.
  std::vector<std::pair<std::filesystem::path, std::string>> files;
  files.emplace_back("index.html", read_input_file(web / "export-web.html", "shtool's page"));
  files.emplace_back("shtool-three.js", read_input_file(web / "shtool-three.js", "shtool's page module"));
  files.emplace_back("scene.json", scene.dump(1) + "\n");
  files.emplace_back("mesh.glb", fit::zh_fit_glb(mesh, fit, dc, std::string("shtool ") + kVersion + " export-web"));
  files.emplace_back("shtool-rotate.glsl", shader_source(rotate_request).text);
  files.emplace_back("shtool-zh-shade.glsl", shader_source(shade_request).text);
  for (const std::string& f : three_files())
    files.emplace_back(std::filesystem::path("three") / f, read_input_file(three / f, "three.js's " + f));

  std::optional<interop::ThreeProbeGridFiles> probe_files;
  if (probes) {
    interop::ThreeProbeGridInput grid;
    grid.resolution = probes->resolution;
    grid.min = probes->min;
    grid.max = probes->max;
    // What three.js evaluates linearly: l2 as stored, zh3 as the order-3 SH it stands for.
    if (probes->encoding == ProbeEncoding::l2) {
      grid.order = probes->order;
      grid.coefficients = probes->coefficients;
    } else {
      grid.order = 3;
      const std::size_t count = probes->coefficients.size() / probes->values_per_probe();
      for (std::size_t p = 0; p < count; ++p) {
        const std::span<const double> v = probes->coefficients_of(p);
        const std::array<double, 27> sh = interop::zh3_as_order3_sh(
            v.first<12>(), probes->stores_zonal() ? v.data() + 12 : nullptr, probes->zh3_axis);
        grid.coefficients.insert(grid.coefficients.end(), sh.begin(), sh.end());
      }
    }
    probe_files = interop::three_probe_grid_files(grid);
  }

  MadeFolders folders;
  folders.make(r.out, "--out");
  for (const char* d : {"three", "three/build", "three/examples", "three/examples/jsm", "three/examples/jsm/lighting"})
    folders.make(r.out / d, "--out");
  if (probes) folders.make(r.out / "probes", "--out");
  for (const auto& [name, bytes] : files) io.output(r.out / name, "--out " + name.string());
  if (probes) interop::declare_three_probe_grid(io, r.out / "probes", "--probes");
  for (auto& [name, bytes] : files) io.set("--out " + name.string(), std::move(bytes));
  if (probes) interop::set_three_probe_grid(io, "--probes", std::move(*probe_files));
  io.commit();
  folders.keep();

  ExportWebResult result;
  for (const auto& [name, bytes] : files) result.files.push_back(name);
  if (probes) {
    result.files.emplace_back("probes/probes.json");
    result.files.emplace_back("probes/probes.bin");
  }
  result.order = order;
  result.lobes = lobes;
  result.vertices = mesh.positions.size();
  result.triangles = mesh.triangles.size();
  result.warnings = std::move(warnings);
  return result;
}

}  // namespace shtool::web
