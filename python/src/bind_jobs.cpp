// fit_zh on transfer vectors, and the offline jobs on files (fit-zh on a mesh,
// project-env on an image file, transform-splats, gen-tensors, search-lobes): each
// builds the job's request from keyword arguments named as the CLI's options and calls
// the job, which checks it as the CLI's run does.
#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/mesh_frame.h"
#include "common/parallel_for.h"
#include "fit/fit_zh_job.h"
#include "fit/zh_fit.h"
#include "interop/splats_job.h"
#include "lighting/project_env_job.h"
#include "lobes/search_lobes_job.h"
#include "py_arrays.h"
#include "shtool/orthogonal_map.h"
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
  check_threads(threads);
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

// A Python value's type name and short repr, for messages.
std::string given(const py::handle& v) {
  std::string r = py::repr(v);
  if (r.size() > 40) r = r.substr(0, 37) + "...";
  return std::string(py::str(py::type::handle_of(v).attr("__name__"))) + " " + r;
}

// A path argument: str, bytes or os.PathLike, as the bytes os.fsencode gives (a name
// that is not UTF-8 reaches the file system as it is); TypeError naming `what`.
std::filesystem::path path_arg(const py::handle& v, const std::string& what) {
  if (py::isinstance<py::str>(v) || py::isinstance<py::bytes>(v) || py::hasattr(v, "__fspath__")) {
    try {
      return std::filesystem::path(py::module_::import("os").attr("fsencode")(v).cast<std::string>());
    } catch (const py::error_already_set&) {
    }
  }
  throw py::type_error(what + " must be a path (str, bytes or os.PathLike), got " + given(v));
}

// Keyword arguments as a request's fields, each converted from the Python value or a
// TypeError naming the argument and the type it takes; a TypeError for any the job does
// not take. None stands for "not given" (the request's default).
class Kwargs {
 public:
  Kwargs(const char* job, py::kwargs kw) : job_(job), kw_(std::move(kw)) {}

  void get(const char* key, int& field) {
    if (const py::object v = take(key)) field = integer(v, key);
  }
  void get(const char* key, std::optional<int>& field) {
    if (const py::object v = take(key)) field = integer(v, key);
  }
  void get(const char* key, std::uint64_t& field) {
    if (const py::object v = take(key)) {
      if (py::isinstance<py::bool_>(v) || is_numpy_bool(v) || !PyIndex_Check(v.ptr())) throw type(key, "an int", v);
      const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(v.ptr()));
      const unsigned long long n = PyLong_AsUnsignedLongLong(i.ptr());
      if (PyErr_Occurred()) {
        PyErr_Clear();
        throw py::value_error(name(key) + " = " + std::string(py::repr(v)) + " is out of range (0..2^64-1)");
      }
      field = n;
    }
  }
  void get(const char* key, double& field) {
    if (const py::object v = take(key)) field = number(v, key);
  }
  void get(const char* key, std::optional<double>& field) {
    if (const py::object v = take(key)) field = number(v, key);
  }
  void get(const char* key, bool& field) {
    if (const py::object v = take(key)) {
      if (!py::isinstance<py::bool_>(v) && !is_numpy_bool(v)) throw type(key, "a bool", v);
      field = v.cast<bool>();
    }
  }
  void get(const char* key, std::string& field) {
    if (const py::object v = take(key)) {
      if (!py::isinstance<py::str>(v)) throw type(key, "a str", v);
      field = v.cast<std::string>();
    }
  }
  void get(const char* key, std::filesystem::path& field) {
    if (const py::object v = take(key)) field = path_arg(v, name(key));
  }
  // A list of names: a list or tuple of str, or one str of comma-separated names (the CLI's).
  void get(const char* key, std::vector<std::string>& field) {
    if (const py::object v = take(key)) {
      std::vector<std::string> names;
      if (py::isinstance<py::str>(v)) {
        std::string item;
        for (char c : v.cast<std::string>() + ",") {
          if (c != ',') {
            item += c;
          } else if (!item.empty()) {
            names.push_back(item);
            item.clear();
          }
        }
      } else if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
        for (const py::handle& item : v) {
          if (!py::isinstance<py::str>(item)) throw type(key, "a list of str (or one comma-separated str)", v);
          names.push_back(item.cast<std::string>());
        }
      } else {
        throw type(key, "a list of str (or one comma-separated str)", v);
      }
      field = names;
    }
  }
  // N numbers: any array-like of N numbers (a 3x3 matrix for 9).
  template <std::size_t N>
  void get(const char* key, std::array<double, N>& field) {
    if (const py::object v = take(key)) field = numbers<N>(v, key);
  }
  template <std::size_t N>
  void get(const char* key, std::optional<std::array<double, N>>& field) {
    if (const py::object v = take(key)) field = numbers<N>(v, key);
  }
  template <class E>
  void get_enum(const char* key, E& field, const std::vector<std::pair<std::string, E>>& names) {
    std::string value;
    get(key, value);
    if (!value.empty()) field = choice(value, names, key);
  }
  // threads=, checked as every call checks it.
  void threads(const char* key, int& field) {
    get(key, field);
    check_threads(field);
  }
  // The value of `key`, removed (so that done() sees only unknown ones); null when not
  // given or None.
  py::object take(const char* key) {
    if (!kw_.contains(key)) return {};
    py::object v = kw_[key];
    PyDict_DelItemString(kw_.ptr(), key);
    return v.is_none() ? py::object() : v;
  }
  bool has(const char* key) const { return kw_.contains(key) && !py::object(kw_[key]).is_none(); }
  void done() const {
    if (py::len(kw_) == 0) return;
    throw py::type_error(job_ + ": unexpected keyword argument '" + std::string(py::str(*kw_.begin()->first)) + "'");
  }
  std::string name(const char* key) const { return job_ + ": " + key; }
  py::type_error type(const char* key, const std::string& expected, const py::handle& v) const {
    return py::type_error(name(key) + " must be " + expected + ", got " + given(v));
  }
  long long integer(const py::handle& v, const char* key, long long low = std::numeric_limits<int>::min(),
                    long long high = std::numeric_limits<int>::max()) const {
    // int and numpy's integers (__index__), not bool, float or str.
    if (py::isinstance<py::bool_>(v) || is_numpy_bool(v) || !PyIndex_Check(v.ptr())) throw type(key, "an int", v);
    const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(v.ptr()));
    int overflow = 0;
    const long long n = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
    if (overflow || n < low || n > high)
      throw py::value_error(name(key) + " = " + std::string(py::repr(v)) + " is out of range (" + std::to_string(low) +
                            ".." + std::to_string(high) + ")");
    return n;
  }

 private:
  static bool is_numpy_bool(const py::handle& v) {
    return std::string(py::str(py::type::handle_of(v).attr("__name__"))) == "bool_";
  }
  double number(const py::handle& v, const char* key) const {
    // int, float and numpy's scalars; not bool or str.
    if (py::isinstance<py::bool_>(v) || is_numpy_bool(v) || py::isinstance<py::str>(v) ||
        py::isinstance<py::bytes>(v) || !PyNumber_Check(v.ptr()) || py::isinstance<py::array>(v))
      throw type(key, "a number", v);
    const double d = PyFloat_AsDouble(v.ptr());
    if (d == -1.0 && PyErr_Occurred()) {
      PyErr_Clear();
      throw type(key, "a number", v);
    }
    return d;
  }
  template <std::size_t N>
  std::array<double, N> numbers(const py::handle& v, const char* key) const {
    const std::string expected = N == 9 ? "9 numbers (or a 3x3 matrix)" : std::to_string(N) + " numbers";
    if (py::isinstance<py::str>(v) || py::isinstance<py::bytes>(v)) throw type(key, expected, v);
    py::array_t<double, py::array::c_style> a;
    try {
      a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
    } catch (const py::error_already_set&) {
    }
    if (!a || static_cast<std::size_t>(a.size()) != N || (N == 9 && a.ndim() == 2 && a.shape(0) != 3))
      throw type(key, expected, v);
    std::array<double, N> out{};
    std::copy(a.data(), a.data() + N, out.begin());
    return out;
  }

  std::string job_;
  py::dict kw_;
};

py::dict fit_zh_mesh(const py::object& mesh, py::kwargs kwargs) {
  fit::FitZhRequest r;
  r.mesh = path_arg(mesh, "fit_zh_mesh: mesh");
  Kwargs kw("fit_zh_mesh", std::move(kwargs));
  kw.get("out", r.out), kw.get("json", r.json), kw.get("ply", r.ply), kw.get("save_transfer", r.save_transfer);
  kw.get("gltf", r.gltf);
  kw.get_enum("format", r.encoding, encoding_names());
  kw.get_enum("mode", r.mode, fit::transfer_mode_names());
  kw.get_enum("normals", r.normals, fit::normal_source_names());
  kw.get_enum("up", r.up, up_axis_names());
  kw.get("order", r.order);
  kw.get("lobes", r.lobes), kw.get("rays", r.rays), kw.get("bounces", r.bounces), kw.get("albedo", r.albedo);
  kw.get("seed", r.seed), kw.get("effort", r.effort), kw.get("starts", r.starts);
  kw.get("restart_above", r.restart_above), kw.get("direct", r.direct), kw.threads("threads", r.threads);
  kw.get("texture", r.texture), kw.get("shard", r.shard);
  kw.get_enum("fit_method", r.fit_method, fit::fit_method_names());
  kw.done();
  r.order_given = true;
  fit::FitZhReport report;
  std::vector<std::string> warnings;
  {
    py::gil_scoped_release release;
    std::mutex lock;
    fit::FitZhCallbacks cb;
    cb.warning = [&](const std::string& w) {
      const std::lock_guard<std::mutex> held(lock);
      warnings.push_back(w);
    };
    report = fit::run_fit_zh(r, cb);
  }
  py::list said;
  for (const std::string& w : warnings) said.append(message_text(w));
  return py::dict(py::arg("count") = report.count, py::arg("out") = path_text(report.out.string()),
                  py::arg("simulate_seconds") = report.simulate_seconds, py::arg("fit_seconds") = report.fit_seconds,
                  py::arg("normalized_rms") = report.normalized_rms, py::arg("threads") = report.threads,
                  py::arg("sharded") = report.sharded, py::arg("warnings") = said);
}

py::dict project_env_file(const py::object& image, const py::object& json, py::kwargs kwargs) {
  lighting::ProjectEnvRequest r;
  r.image = path_arg(image, "project_env_file: image");
  r.json = path_arg(json, "project_env_file: json");
  Kwargs kw("project_env_file", std::move(kwargs));
  kw.get("out", r.out), kw.get("render_back", r.render_back), kw.get("render_source", r.render_source);
  kw.get("order", r.order), kw.get("mirror_x", r.mirror_x), kw.get("cutoff", r.cutoff);
  kw.threads("threads", r.threads);
  kw.get_enum("layout", r.layout, lighting::layout_names());
  kw.get_enum("equirect_preset", r.preset, lighting::equirect_preset_names());
  kw.get_enum("window", r.window, lighting::window_names());
  kw.get_enum("format", r.encoding, encoding_names());
  kw.get_enum("quantity", r.quantity, lighting::quantity_names());
  kw.done();
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

py::dict transform_splats(const py::object& in, const py::object& out, py::kwargs kwargs) {
  interop::TransformSplatsRequest r;
  r.in = path_arg(in, "transform_splats: path_in");
  r.out = path_arg(out, "transform_splats: path_out");
  Kwargs kw("transform_splats", std::move(kwargs));
  if (kw.has("quat") && kw.has("quaternion"))
    throw py::type_error("transform_splats: give quaternion= or its CLI name quat=, not both");
  kw.get("quaternion", r.quaternion), kw.get("quat", r.quaternion), kw.get("matrix", r.matrix);
  kw.get("translate", r.translate), kw.get("scale", r.scale), kw.threads("threads", r.threads);
  kw.get("frame", r.ply_frame), kw.get("spz_frame", r.spz_frame), kw.get("gltf_frame", r.gltf_frame);
  kw.get("sh_degree", r.sh_degree), kw.get("spz_version", r.spz_version);
  if (const py::object bits = kw.take("sh_bits")) {
    // One number for every band, or (band 1, bands 2..3), as --sh-bits B or B1,B2.
    std::vector<int> b;
    if (PyIndex_Check(bits.ptr()) && !py::isinstance<py::bool_>(bits)) {
      b.push_back(static_cast<int>(kw.integer(bits, "sh_bits")));
    } else if (py::isinstance<py::list>(bits) || py::isinstance<py::tuple>(bits)) {
      for (const py::handle& x : bits) b.push_back(static_cast<int>(kw.integer(x, "sh_bits")));
    } else {
      throw kw.type("sh_bits", "an int or two ints", bits);
    }
    if (b.empty() || b.size() > 2) throw kw.type("sh_bits", "an int or two ints", bits);
    r.sh_bits = {b[0], b.back()};
  }
  kw.done();
  interop::TransformSplatsReport report;
  {
    py::gil_scoped_release release;
    report = interop::run_transform_splats(r);
  }
  py::list said;
  for (const std::string& w : report.warnings) said.append(message_text(w));
  return py::dict(py::arg("splats") = report.splats, py::arg("degree") = report.degree,
                  py::arg("seconds") = report.seconds, py::arg("reflects") = report.reflects,
                  py::arg("warnings") = said);
}

// transform_splat_arrays: the job's own arithmetic (SplatMotion, and the orthogonal map
// of the SH colours) on float64 arrays, each None or given: positions, log_scales and
// normals (S, 3), rotations (S, 4) w x y z, sh (S, 3, N^2); the module checks their
// shapes and rounds each result to its caller's dtype once, as the job rounds to float.
py::dict transform_splat_arrays(const py::object& sh, const py::object& positions, const py::object& rotations,
                                const py::object& log_scales, const py::object& normals,
                                const std::optional<std::array<double, 4>>& quaternion,
                                const std::optional<std::array<double, 9>>& matrix,
                                const std::array<double, 3>& translate, double scale) {
  interop::TransformSplatsRequest r;
  r.quaternion = quaternion, r.matrix = matrix, r.translate = translate, r.scale = scale;
  const Eigen::Matrix3d m = interop::splat_rotation(r);
  const interop::SplatMotion motion(m, scale, Eigen::Vector3d(translate[0], translate[1], translate[2]), quaternion);
  py::dict out;
  auto each_row = [&](const py::object& given, const char* name, std::size_t width, const auto& f) {
    if (given.is_none()) return;
    const auto in = contiguous<double>(given);
    py::array_t<double, py::array::c_style> moved(shape_of(in));
    const double* src = in.data();
    double* dst = moved.mutable_data();
    const std::size_t rows = static_cast<std::size_t>(in.size()) / width;
    {
      py::gil_scoped_release release;
      for (std::size_t i = 0; i < rows; ++i) f(src + i * width, dst + i * width);
    }
    out[name] = moved;
  };
  using Vec = Eigen::Vector3d;
  each_row(positions, "positions", 3, [&](const double* p, double* o) {
    const Vec moved = motion.position(Vec(p[0], p[1], p[2]));
    for (int k = 0; k < 3; ++k) o[k] = moved[k];
  });
  each_row(normals, "normals", 3, [&](const double* n, double* o) {
    const Vec turned = motion.normal(Vec(n[0], n[1], n[2]));
    for (int k = 0; k < 3; ++k) o[k] = turned[k];
  });
  each_row(rotations, "rotations", 4, [&](const double* q, double* o) {
    const Eigen::Quaterniond turned = motion.orientation(Eigen::Quaterniond(q[0], q[1], q[2], q[3]));
    o[0] = turned.w(), o[1] = turned.x(), o[2] = turned.y(), o[3] = turned.z();
  });
  each_row(log_scales, "log_scales", 3, [&](const double* v, double* o) {
    for (int k = 0; k < 3; ++k) o[k] = motion.log_scale(v[k]);
  });
  if (!sh.is_none()) {
    const auto c = contiguous<double>(sh);
    const std::size_t n2 = static_cast<std::size_t>(c.shape(c.ndim() - 1));
    const Result<OrthogonalMap> map = OrthogonalMap::make(m, order_of_count(static_cast<py::ssize_t>(n2), "sh"), 1e-6);
    if (!map) throw py::value_error("transform_splat_arrays: " + map.error().message);
    each_row(sh, "sh", n2, [&](const double* f, double* g) {
      map.value().apply(std::span<const double>(f, n2), std::span<double>(g, n2));
    });
  }
  return out;
}

py::list gen_tensors(int order, const py::object& out, py::kwargs kwargs) {
  GenTensorsRequest r;
  r.order = order;
  r.out = path_arg(out, "gen_tensors: out");
  Kwargs kw("gen_tensors", std::move(kwargs));
  kw.get("what", r.what), kw.get("inputs", r.inputs);
  kw.get_enum("format", r.encoding, encoding_names());
  kw.done();
  std::vector<GeneratedFile> files;
  {
    py::gil_scoped_release release;
    files = run_gen_tensors(r);
  }
  py::list paths;
  for (const GeneratedFile& f : files) paths.append(path_text(f.path.string()));
  return paths;
}

std::string search_lobes(py::kwargs kwargs) {
  lobes::SearchLobesRequest r;
  Kwargs kw("search_lobes", std::move(kwargs));
  // bands: a list of bands, one band, or the CLI's 'a-b'; band: one band (--band l).
  if (const py::object bands = kw.take("bands")) {
    if (py::isinstance<py::str>(bands)) {
      r.bands = lobes::parse_band_range(bands.cast<std::string>());
    } else if (PyIndex_Check(bands.ptr()) && !py::isinstance<py::bool_>(bands)) {
      r.bands.push_back(static_cast<int>(kw.integer(bands, "bands")));
    } else if (py::isinstance<py::list>(bands) || py::isinstance<py::tuple>(bands) ||
               py::isinstance<py::array>(bands)) {
      for (const py::handle& b : bands) r.bands.push_back(static_cast<int>(kw.integer(b, "bands")));
    } else {
      throw kw.type("bands", "a list of ints, an int or a str 'a-b'", bands);
    }
  }
  if (const py::object band = kw.take("band")) {
    if (!r.bands.empty()) throw py::value_error("search_lobes: give band= or bands=, not both");
    r.bands.push_back(static_cast<int>(kw.integer(band, "band")));
  }
  kw.get("shared", r.shared), kw.get("order", r.order), kw.get("paper", r.paper);
  kw.get("out", r.out), kw.get("json", r.json);
  kw.get("population", r.search.population), kw.get("stall", r.search.stall);
  kw.get("crossover", r.search.crossover), kw.get("mutation", r.search.mutation);
  kw.get("elitism", r.search.elitism), kw.get("max_cond", r.search.max_cond);
  kw.get("max_generations", r.search.max_generations), kw.get("seed", r.search.seed);
  kw.threads("threads", r.search.threads);
  std::optional<int> restarts;
  kw.get("restarts", restarts);
  if (restarts) r.search.restarts = *restarts, r.restarts_given = true;
  if (kw.has("theta_candidates")) {
    kw.get_enum("theta_candidates", r.search.theta,
                std::vector<std::pair<std::string, lobes::ThetaCandidates>>{
                    {"band", lobes::ThetaCandidates::band}, {"pooled", lobes::ThetaCandidates::pooled}});
    r.theta_given = true;
  }
  bool no_local_search = false, no_secondary = false;
  kw.get("no_local_search", no_local_search), kw.get("no_secondary", no_secondary);
  if (no_local_search) r.search.local_search = false;
  if (no_secondary) r.search.secondary = false;
  kw.done();
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
  m.def("_transform_splats", &transform_splats, py::arg("path_in"), py::arg("path_out"));
  m.def("_transform_splat_arrays", &transform_splat_arrays, py::arg("sh"), py::arg("positions"), py::arg("rotations"),
        py::arg("log_scales"), py::arg("normals"), py::arg("quaternion"), py::arg("matrix"), py::arg("translate"),
        py::arg("scale"));
  m.def("_gen_tensors", &gen_tensors, py::arg("order"), py::arg("out"));
  m.def("_search_lobes", &search_lobes);
}

}  // namespace shtool::python
