// project_env, irradiance, window, light: the lighting side of the runtime and of the
// project-env and light jobs, on arrays.
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/parallel_for.h"
#include "lighting/light_job.h"
#include "lighting/project_env_job.h"
#include "py_arrays.h"
#include "shtool/irradiance.h"
#include "shtool/sh.h"
#include "shtool/sh_window.h"

namespace shtool::python {
namespace {

// Coefficients (..., N^2) times factors[band], in the array's own dtype, in chunks of
// vectors on `threads` workers with the GIL released; `what` names the operation in the
// overflow refusal (irradiance multiplies band 0 by pi).
template <class T>
py::array scale_by_band(const py::array& coeffs_in, const std::vector<double>& factors, int threads,
                        const std::string& what) {
  const auto coeffs = contiguous<T>(coeffs_in);
  const std::size_t n2 = coeffs.shape(coeffs.ndim() - 1);
  py::array_t<T, py::array::c_style> out(shape_of(coeffs));
  const T* in = coeffs.data();
  T* o = out.mutable_data();
  std::vector<double> per_index(n2);
  for (std::size_t i = 0; i < n2; ++i) per_index[i] = factors[sh_band(static_cast<int>(i))];
  const std::size_t count = n2 ? static_cast<std::size_t>(coeffs.size()) / n2 : 0;
  py::gil_scoped_release release;
  for_chunks(count, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin * n2; k < end * n2; ++k) o[k] = static_cast<T>(in[k] * per_index[k % n2]);
  });
  refuse_overflow(what, static_cast<const T*>(o), count, n2,
                  [&](std::size_t k) { return all_finite(in + k * n2, n2); });
  return out;
}

py::array scale_any(const py::array& coeffs, const std::vector<double>& factors, int threads, const std::string& what) {
  return precision_of(coeffs, "coeffs") == Precision::f32 ? scale_by_band<float>(coeffs, factors, threads, what)
                                                          : scale_by_band<double>(coeffs, factors, threads, what);
}

int coeffs_order(const py::array& coeffs) {
  if (coeffs.ndim() < 1) throw py::value_error("coeffs must have at least one axis");
  return order_of_count(coeffs.shape(coeffs.ndim() - 1), "coeffs");
}

// The windows of sh_window.h, "auto" included: every vector of `coeffs` is one channel
// of one lighting, as the auto window of project-env treats r, g and b.
py::tuple window(const py::array& coeffs, const std::string& kind, std::optional<double> cutoff, int threads) {
  check_threads(threads);
  precision_of(coeffs, "coeffs");
  const int order = coeffs_order(coeffs);
  if (cutoff && !(*cutoff > 0 && std::isfinite(*cutoff))) throw py::value_error("cutoff must be a positive number");
  std::vector<double> factors;
  py::object used_cutoff = py::none();
  if (kind == "auto") {
    if (cutoff) throw py::value_error("cutoff applies to the windows hann, lanczos and sinc4");
    const auto d = as_f64(coeffs, "coeffs");
    const std::size_t n2 = sh_count(order), channels = d.size() / n2;
    if (channels == 0) throw py::value_error("coeffs holds no vector: the auto window is chosen from at least one");
    AutoWindow w;
    {
      py::gil_scoped_release release;
      std::vector<double> interleaved(d.size());
      for (std::size_t c = 0; c < channels; ++c)
        for (std::size_t i = 0; i < n2; ++i) interleaved[i * channels + c] = d.data()[c * n2 + i];
      w = value_or_raise(choose_auto_window(interleaved, static_cast<int>(channels)));
    }
    factors = w.factors;
    if (w.cutoff) used_cutoff = py::float_(*w.cutoff);
  } else {
    const std::optional<ShWindow> shape = sh_window_from_name(kind);
    if (!shape) throw py::value_error("kind: unknown window '" + kind + "' (none, hann, lanczos, sinc4, auto)");
    if (cutoff && *shape == ShWindow::none) throw py::value_error("cutoff applies to the windows hann, lanczos and sinc4");
    const double c = cutoff.value_or(order);
    factors = sh_window_factors(*shape, c, order);
    if (*shape != ShWindow::none) used_cutoff = py::float_(c);
  }
  return py::make_tuple(scale_any(coeffs, factors, threads, "window: the windowed vector"),
                        py::array_t<double>(factors.size(), factors.data()), used_cutoff);
}

py::array irradiance(const py::array& coeffs, int threads) {
  check_threads(threads);
  precision_of(coeffs, "coeffs");
  const int order = coeffs_order(coeffs);
  std::vector<double> factors(order);
  for (int l = 0; l < order; ++l) factors[l] = clamped_cosine_band(l);
  return scale_any(coeffs, factors, threads, "irradiance: the irradiance");
}

py::array light(const std::string& kind, int order, const py::object& direction, std::optional<double> half_angle,
                const py::object& color, const py::object& ground, const std::string& quantity) {
  lighting::LightSpec spec;
  spec.type = choice(kind, lighting::light_type_names(), "kind");
  auto triple = [](const py::object& v, const char* what) {
    const auto a = as_f64(v, what);
    if (a.size() != 3) throw py::value_error(std::string(what) + " must hold 3 numbers");
    return std::array<double, 3>{a.data()[0], a.data()[1], a.data()[2]};
  };
  if (spec.type != lighting::LightType::constant) spec.direction = triple(direction, "direction");
  // Said in the call's own words: the library's messages name --half-angle and a list.
  const bool angled = spec.type == lighting::LightType::cone || spec.type == lighting::LightType::sphere;
  if (angled && !half_angle) throw py::value_error("light('" + kind + "') needs half_angle= (degrees)");
  if (!angled && half_angle) throw py::value_error("half_angle= is for the cone and sphere lights, not '" + kind + "'");
  spec.half_angle_degrees = half_angle;
  spec.color = triple(color, "color");
  if (!ground.is_none()) {
    if (spec.type != lighting::LightType::hemisphere) throw py::value_error("ground applies to the hemisphere light");
    spec.ground = triple(ground, "ground");
  }
  const lighting::Lighting l =
      lighting::light_coefficients({spec}, order, choice(quantity, lighting::quantity_names(), "quantity"));
  py::array_t<double> out({static_cast<py::ssize_t>(sh_count(order)), py::ssize_t(3)});
  std::copy(l.coefficients.begin(), l.coefficients.end(), out.mutable_data());
  return out;
}

// The texel index (i, j, ...) of flat index k of an array of `shape`, as numpy prints it.
std::string index_text(std::size_t k, const std::vector<py::ssize_t>& shape) {
  std::vector<std::size_t> index(shape.size());
  for (std::size_t a = shape.size(); a-- > 0;) {
    index[a] = k % static_cast<std::size_t>(shape[a]);
    k /= static_cast<std::size_t>(shape[a]);
  }
  std::string text;
  for (std::size_t i : index) {
    if (!text.empty()) text += ", ";
    text += std::to_string(i);
  }
  return text;
}

// A NaN or infinite texel is named by its numpy index (the projection's own message says
// texel (x, y), the column first, as the CLI's images are addressed).
void refuse_non_finite_texels(const py::array_t<float, py::array::c_style>& texels) {
  const float* p = texels.data();
  const std::size_t count = static_cast<std::size_t>(texels.size());
  std::size_t bad = count;
  {
    py::gil_scoped_release release;
    for (std::size_t k = 0; k < count && bad == count; ++k)
      if (!std::isfinite(p[k])) bad = k;
  }
  if (bad < count)
    throw py::value_error("image[" + index_text(bad, shape_of(texels)) + "] is " +
                          (std::isnan(p[bad]) ? "NaN" : "infinite"));
}

// An image as float32 texels (the projection reads float texels, as the CLI reads a
// file's): the caller's memory when it is C-contiguous float32; float64 rounded to
// float32, with a ValueError for a finite value beyond float32's range (it would become
// infinite); NaN and infinities refused, each named by its numpy index.
py::array_t<float, py::array::c_style> float_texels(const py::array& image) {
  if (precision_of(image, "image") == Precision::f32) {
    auto texels = contiguous<float>(image);
    refuse_non_finite_texels(texels);
    return texels;
  }
  const auto d = contiguous<double>(image);
  py::array_t<float, py::array::c_style> f(shape_of(d));
  const double* in = d.data();
  float* o = f.mutable_data();
  const std::size_t count = static_cast<std::size_t>(d.size());
  std::size_t bad = count;
  {
    py::gil_scoped_release release;
    for (std::size_t k = 0; k < count; ++k) {
      o[k] = static_cast<float>(in[k]);
      if (std::isinf(o[k]) && std::isfinite(in[k]) && bad == count) bad = k;
    }
  }
  if (bad < count) {
    char value[32];
    const auto end = std::to_chars(value, value + sizeof value, in[bad]).ptr;  // the shortest round trip
    throw py::value_error("image[" + index_text(bad, shape_of(d)) + "] = " + std::string(value, end) +
                          " is beyond float32's range (|x| <= 3.4028235e38): project_env computes in float32");
  }
  refuse_non_finite_texels(f);
  return f;
}

py::tuple project_env(const py::array& image, int order, const std::string& layout_name, const std::string& quantity,
                      const std::string& window_name, std::optional<double> cutoff, const std::string& preset,
                      bool mirror_x, int threads) {
  lighting::ProjectEnvRequest r;
  r.order = order;
  r.quantity = choice(quantity, lighting::quantity_names(), "quantity");
  r.window = choice(window_name, lighting::window_names(), "window");
  r.preset = choice(preset, lighting::equirect_preset_names(), "preset");
  r.mirror_x = mirror_x;
  r.cutoff = cutoff;
  if (cutoff && !(*cutoff > 0 && std::isfinite(*cutoff))) throw py::value_error("cutoff must be a positive number");
  if (cutoff && (r.window == lighting::WindowChoice::none || r.window == lighting::WindowChoice::automatic))
    throw py::value_error("cutoff applies to the windows hann, lanczos and sinc4");
  lighting::Layout layout = choice(layout_name, lighting::layout_names(), "layout");
  if (image.ndim() != 3 && image.ndim() != 4) throw py::value_error("image must have shape (H, W, C) or (6, S, S, C)");
  if (layout == lighting::Layout::automatic)
    layout = image.ndim() == 4                      ? lighting::Layout::faces
             : image.shape(1) == 2 * image.shape(0) ? lighting::Layout::equirect
                                                    : lighting::Layout::cross;
  if (layout != lighting::Layout::faces && image.ndim() == 4)
    throw py::value_error(std::string("an image of shape (6, S, S, C) is six cube faces: pass layout=\"faces\" (or "
                                      "\"auto\"); layout=\"") +
                          layout_name + "\" takes an array (H, W, C)");
  if (layout == lighting::Layout::faces && image.ndim() != 4)
    throw py::value_error(
        "layout=\"faces\" takes an array (6, S, S, C), faces +X -X +Y -Y +Z -Z; an (H, W, C) image "
        "is equirect or a cross (layout=\"equirect\", \"cross\" or \"auto\")");
  if (image.shape(image.ndim() - 1) < 1 || image.size() == 0) throw py::value_error("image is empty");
  if (const py::ssize_t c = image.shape(image.ndim() - 1); c > 4)
    throw py::value_error("image has " + std::to_string(c) + " channels; 1 to 4 supported");
  if (layout == lighting::Layout::equirect && image.shape(1) != 2 * image.shape(0))
    throw py::value_error("an equirect image must be 2:1 (W = 2 H), got " + std::to_string(image.shape(1)) + " x " +
                          std::to_string(image.shape(0)));
  if (layout == lighting::Layout::faces && (image.shape(0) != 6 || image.shape(1) != image.shape(2)))
    throw py::value_error("faces must have shape (6, S, S, C)");
  if (r.preset != lighting::EquirectPreset::shtool && layout != lighting::Layout::equirect)
    throw py::value_error("preset applies to equirect images");
  if (mirror_x && layout == lighting::Layout::equirect)
    throw py::value_error("mirror_x applies to cubemaps, not to equirect images");
  check_threads(threads);
  const auto texels = float_texels(image);
  const int resolved_threads = resolve_threads(threads);
  const int channels = static_cast<int>(texels.shape(texels.ndim() - 1));
  std::vector<double> coefficients;
  nlohmann::json window;
  {
    py::gil_scoped_release release;
    std::vector<FloatImageView> views;
    std::array<lighting::Image, 6> cut;
    if (layout == lighting::Layout::equirect) {
      views.push_back({texels.data(), static_cast<int>(texels.shape(1)), static_cast<int>(texels.shape(0)), channels});
    } else if (layout == lighting::Layout::faces) {
      const std::size_t face = static_cast<std::size_t>(texels.size() / 6);
      for (int f = 0; f < 6; ++f)
        views.push_back({texels.data() + f * face, static_cast<int>(texels.shape(2)), static_cast<int>(texels.shape(1)),
                         channels});
    } else {
      lighting::Image cross{static_cast<int>(texels.shape(1)), static_cast<int>(texels.shape(0)), channels,
                            std::vector<float>(texels.data(), texels.data() + texels.size())};
      cut = lighting::faces_from_cross(cross, "image");
      for (const lighting::Image& f : cut) views.push_back(f.view());
    }
    coefficients = lighting::project_env_views(r, views, resolved_threads, window);
  }
  py::array_t<double> out({static_cast<py::ssize_t>(sh_count(order)), static_cast<py::ssize_t>(channels)});
  std::copy(coefficients.begin(), coefficients.end(), out.mutable_data());
  return py::make_tuple(out, py::str(window.dump()));
}

}  // namespace

void bind_lighting(py::module_& m) {
  m.def("_window", &window, py::arg("coeffs").noconvert(), py::arg("kind"), py::arg("cutoff"), py::arg("threads") = 0);
  m.def("_irradiance", &irradiance, py::arg("coeffs").noconvert(), py::arg("threads") = 0);
  m.def("light", &light, py::arg("kind"), py::arg("order"), py::arg("direction") = py::make_tuple(0, 0, 1),
        py::arg("half_angle") = py::none(), py::arg("color") = py::make_tuple(1, 1, 1), py::arg("ground") = py::none(),
        py::arg("quantity") = "radiance",
        "Analytic light as radiance (or irradiance) coefficients (order**2, 3); half_angle in degrees.");
  m.def("_project_env", &project_env, py::arg("image").noconvert(), py::arg("order"), py::arg("layout"),
        py::arg("quantity"), py::arg("window"), py::arg("cutoff"), py::arg("preset"), py::arg("mirror_x"),
        py::arg("threads"));
}

}  // namespace shtool::python
