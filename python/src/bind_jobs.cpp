// fit_zh on transfer vectors, and the offline jobs on files (fit-zh on a mesh,
// project-env on an image file, transform-splats, gen-tensors, search-lobes): each
// builds the job's request from keyword arguments named as the CLI's options and calls
// the job, which checks it as the CLI's run does.
#include <string>
#include <vector>

#include "common/parallel_for.h"
#include "fit/fit_zh_job.h"
#include "fit/zh_fit.h"
#include "interop/splats_job.h"
#include "lighting/project_env_job.h"
#include "lobes/search_lobes_job.h"
#include "py_arrays.h"
#include "shtool/sh.h"
#include "tensors/gen_tensors_job.h"

namespace shtool::python {
namespace {

const std::vector<std::pair<std::string, TableEncoding>>& encoding_names() {
  static const std::vector<std::pair<std::string, TableEncoding>> names = {{"binary", TableEncoding::binary},
                                                                            {"json", TableEncoding::json}};
  return names;
}

template <class A>
py::array_t<double> array_of(const std::vector<A>& v, std::vector<py::ssize_t> shape) {
  py::array_t<double> out(shape);
  std::copy(reinterpret_cast<const double*>(v.data()), reinterpret_cast<const double*>(v.data()) + out.size(),
            out.mutable_data());
  return out;
}

py::tuple fit_zh(const py::array& transfer_in, int lobes, std::optional<int> effort, std::optional<std::uint64_t> seed,
                 std::optional<int> starts, std::optional<double> restart_above, bool direct, const std::string& method,
                 int threads) {
  const auto t = as_f64(transfer_in, "transfer");
  if (t.ndim() != 2) throw py::value_error("transfer must have shape (V, N^2)");
  const int order = order_of_count(t.shape(1), "transfer");
  fit::FitZhRequest r;
  r.lobes = lobes;
  if (effort) r.effort = *effort;
  if (seed) r.seed = *seed;
  r.starts = starts;
  r.restart_above = restart_above;
  r.direct = direct;
  r.fit_method = choice(method, fit::fit_method_names(), "method");
  r.threads = threads;
  const fit::ZhFitOptions options = fit::fit_zh_options(r, order);
  for (py::ssize_t k = 0; k < t.size(); ++k)
    if (!std::isfinite(t.data()[k])) throw py::value_error("transfer holds a non-finite value");
  const int resolved = resolve_threads(threads);
  ZhFitTable<double> fits;
  {
    py::gil_scoped_release release;
    fits = fit::fit_zh_all(std::span<const double>(t.data(), t.size()), options, resolved);
  }
  const py::ssize_t v = t.shape(0), n = lobes;
  return py::make_tuple(array_of(fits.axes, {v, n, 3}), array_of(fits.coeffs, {v, n, py::ssize_t(order)}),
                        array_of(fits.residual, {v}), array_of(fits.norm, {v}),
                        array_of(fits.direct, {v, py::ssize_t(fits.direct_count)}));
}

// Keyword arguments as a request's fields; a TypeError for any the job does not take.
class Kwargs {
 public:
  explicit Kwargs(py::kwargs kw) : kw_(std::move(kw)) {}
  template <class T>
  void get(const char* key, T& field) {
    if (!kw_.contains(key)) return;
    field = kw_[key].cast<T>();
    PyDict_DelItemString(kw_.ptr(), key);
  }
  template <class E>
  void get_enum(const char* key, E& field, const std::vector<std::pair<std::string, E>>& names) {
    std::string name;
    get(key, name);
    if (!name.empty()) field = choice(name, names, key);
  }
  void done(const char* job) const {
    if (py::len(kw_) == 0) return;
    throw py::type_error(std::string(job) + ": unexpected keyword argument '" +
                         std::string(py::str(*kw_.begin()->first)) + "'");
  }

 private:
  py::dict kw_;
};

py::dict fit_zh_mesh(const std::string& mesh, py::kwargs kwargs) {
  fit::FitZhRequest r;
  r.mesh = mesh;
  Kwargs kw(std::move(kwargs));
  std::string out, json, ply, save_transfer, gltf;
  kw.get("out", out), kw.get("json", json), kw.get("ply", ply), kw.get("save_transfer", save_transfer);
  kw.get("gltf", gltf);
  r.out = out, r.json = json, r.ply = ply, r.save_transfer = save_transfer, r.gltf = gltf;
  kw.get_enum("format", r.encoding, encoding_names());
  kw.get_enum("mode", r.mode, fit::transfer_mode_names());
  kw.get_enum("normals", r.normals, fit::normal_source_names());
  kw.get("order", r.order);
  kw.get("lobes", r.lobes), kw.get("rays", r.rays), kw.get("bounces", r.bounces), kw.get("albedo", r.albedo);
  kw.get("seed", r.seed), kw.get("effort", r.effort), kw.get("starts", r.starts);
  kw.get("restart_above", r.restart_above), kw.get("direct", r.direct), kw.get("threads", r.threads);
  kw.get("texture", r.texture);
  kw.get_enum("fit_method", r.fit_method, fit::fit_method_names());
  kw.done("fit_zh_mesh");
  r.order_given = true;
  fit::FitZhReport report;
  {
    py::gil_scoped_release release;
    report = fit::run_fit_zh(r);
  }
  return py::dict(py::arg("count") = report.count, py::arg("out") = report.out.string(),
                  py::arg("simulate_seconds") = report.simulate_seconds, py::arg("fit_seconds") = report.fit_seconds,
                  py::arg("normalized_rms") = report.normalized_rms, py::arg("threads") = report.threads);
}

py::dict project_env_file(const std::string& image, const std::string& json, py::kwargs kwargs) {
  lighting::ProjectEnvRequest r;
  r.image = image;
  r.json = json;
  Kwargs kw(std::move(kwargs));
  std::string out;
  kw.get("out", out);
  r.out = out;
  kw.get("order", r.order), kw.get("mirror_x", r.mirror_x), kw.get("cutoff", r.cutoff), kw.get("threads", r.threads);
  kw.get_enum("layout", r.layout, lighting::layout_names());
  kw.get_enum("equirect_preset", r.preset, lighting::equirect_preset_names());
  kw.get_enum("window", r.window, lighting::window_names());
  kw.get_enum("format", r.encoding, encoding_names());
  kw.get_enum("quantity", r.quantity, lighting::quantity_names());
  kw.done("project_env_file");
  lighting::ProjectEnvReport report;
  {
    py::gil_scoped_release release;
    report = lighting::run_project_env(r);
  }
  const auto& c = report.lighting.coefficients;
  py::array_t<double> coeffs({static_cast<py::ssize_t>(c.size() / 3), py::ssize_t(3)});
  std::copy(c.begin(), c.end(), coeffs.mutable_data());
  return py::dict(py::arg("coefficients") = coeffs, py::arg("layout") = report.layout,
                  py::arg("window") = report.lighting.window.dump());
}

py::dict transform_splats(const std::string& in, const std::string& out, py::kwargs kwargs) {
  interop::TransformSplatsRequest r;
  r.in = in;
  r.out = out;
  Kwargs kw(std::move(kwargs));
  kw.get("quaternion", r.quaternion), kw.get("matrix", r.matrix), kw.get("translate", r.translate);
  kw.get("scale", r.scale), kw.get("threads", r.threads);
  kw.done("transform_splats");
  interop::TransformSplatsReport report;
  {
    py::gil_scoped_release release;
    report = interop::run_transform_splats(r);
  }
  return py::dict(py::arg("splats") = report.splats, py::arg("degree") = report.degree,
                  py::arg("seconds") = report.seconds);
}

std::vector<std::string> gen_tensors(int order, const std::string& out, py::kwargs kwargs) {
  GenTensorsRequest r;
  r.order = order;
  r.out = out;
  Kwargs kw(std::move(kwargs));
  kw.get("what", r.what), kw.get("inputs", r.inputs);
  kw.get_enum("format", r.encoding, encoding_names());
  kw.done("gen_tensors");
  std::vector<GeneratedFile> files;
  {
    py::gil_scoped_release release;
    files = run_gen_tensors(r);
  }
  std::vector<std::string> paths;
  for (const GeneratedFile& f : files) paths.push_back(f.path.string());
  return paths;
}

std::string search_lobes(py::kwargs kwargs) {
  lobes::SearchLobesRequest r;
  Kwargs kw(std::move(kwargs));
  std::string out, json;
  kw.get("bands", r.bands), kw.get("shared", r.shared), kw.get("order", r.order), kw.get("paper", r.paper);
  kw.get("out", out), kw.get("json", json);
  r.out = out, r.json = json;
  kw.get("population", r.search.population), kw.get("stall", r.search.stall);
  kw.get("max_generations", r.search.max_generations), kw.get("seed", r.search.seed);
  kw.get("threads", r.search.threads);
  std::optional<int> restarts;
  kw.get("restarts", restarts);
  if (restarts) r.search.restarts = *restarts, r.restarts_given = true;
  kw.done("search_lobes");
  lobes::SearchLobesReport report;
  {
    py::gil_scoped_release release;
    report = lobes::run_search_lobes(r);
  }
  return report.summary.dump();
}

}  // namespace

void bind_jobs(py::module_& m) {
  m.def("_fit_zh", &fit_zh, py::arg("transfer"), py::arg("lobes"), py::arg("effort"), py::arg("seed"),
        py::arg("starts"), py::arg("restart_above"), py::arg("direct"), py::arg("method"), py::arg("threads"));
  m.def("_fit_zh_mesh", &fit_zh_mesh, py::arg("mesh"));
  m.def("_project_env_file", &project_env_file, py::arg("image"), py::arg("json"));
  m.def("transform_splats", &transform_splats, py::arg("path_in"), py::arg("path_out"),
        "transform-splats on a PLY file: keyword arguments quaternion=(w, x, y, z) or matrix=(9 numbers, "
        "row-major), translate=(x, y, z), scale, threads; writes path_out as the CLI does.");
  m.def("gen_tensors", &gen_tensors, py::arg("order"), py::arg("out"),
        "gen-tensors: writes the tables into the folder `out`; keyword arguments what=[...], inputs, format. "
        "Returns the paths written.");
  m.def("_search_lobes", &search_lobes);
}

}  // namespace shtool::python
