// An engine's view of shtool: built against the installed package with -fno-exceptions
// and -fno-rtti, it loads every table kind it is given through X::load, in float and in
// double (the shipped tables through SHTOOL_TABLES; argv[1] a fit-zh output, argv[2]
// an env-sh lighting, argv[3] a probe-grid and argv[4] lighting of a lower order than
// the fit, when given), rotates by three methods, multiplies, maps glossy view
// directions and blends wrinkle weights, shades the fit-zh output, and runs the program
// of docs/engine.md (engine_example.cpp). Every result is checked against an independent route (closed forms,
// evaluation at rotated directions, pointwise products, the lobes summed into SH), so a
// package whose headers and library disagree, or whose tables do not load, fails here.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <span>
#include <vector>

#include <shtool/euler.h>
#include <shtool/fourier_tensors.h>
#include <shtool/glossy.h>
#include <shtool/lighting.h>
#include <shtool/probe_grid.h>
#include <shtool/product.h>
#include <shtool/rotation.h>
#include <shtool/sh.h>
#include <shtool/table.h>
#include <shtool/tripling_product.h>
#include <shtool/version.h>
#include <shtool/wrinkle_map.h>
#include <shtool/zh.h>
#include <shtool/zh_fit_table.h>
#include <shtool/zh_shading.h>
#include <shtool/zhf_rotation.h>

#if defined(__cpp_exceptions) || defined(__GXX_RTTI)
#error "the consumer must be compiled with -fno-exceptions -fno-rtti"
#endif

// engine_example.cpp, the program docs/engine.md shows.
bool shade_vertex(const char* fit_path, const char* lighting_path, const shtool::Mat3<float>& object, float rgb[3]);
float multiply_by_one(std::span<const float> f);

namespace {

int failures = 0;

void check(const char* name, double got, double want, double tol) {
  if (!(std::abs(got - want) <= tol * std::max(1.0, std::abs(want)))) {
    std::fprintf(stderr, "consumer: %s = %.17g, expected %.17g (tolerance %.3g)\n", name, got, want, tol);
    ++failures;
  }
}

void require(bool ok, const char* what, const char* detail = "") {
  if (!ok) {
    std::fprintf(stderr, "consumer: %s %s\n", what, detail);
    ++failures;
  }
}

// A fixed, non-trivial SH vector of the given order.
std::vector<double> test_vector(int order) {
  std::vector<double> f(shtool::sh_count(order));
  for (std::size_t i = 0; i < f.size(); ++i) f[i] = std::sin(1.7 * static_cast<double>(i) + 0.3) / (1.0 + i / 4.0);
  return f;
}

double evaluate(const std::vector<double>& f, int order, const shtool::Vec3<double>& w) {
  std::vector<double> y(shtool::sh_count(order));
  shtool::eval_sh<double>(order, w, y);
  double s = 0;
  for (std::size_t i = 0; i < y.size(); ++i) s += f[i] * y[i];
  return s;
}

const shtool::Vec3<double> kDirections[] = {{0.3, -0.5, 0.8}, {-0.9, 0.1, 0.2}, {0.0, 0.0, -1.0}, {0.5, 0.5, 0.5}};

void check_sh_closed_forms() {
  const double c = std::sqrt(3 / (4 * std::numbers::pi));
  shtool::Vec3<double> w(0.3, -0.5, 0.8);
  w.normalize();
  std::vector<double> y(shtool::sh_count(2));
  shtool::eval_sh<double>(2, w, y);
  const double ulp4 = 4 * 2.220446049250313e-16;
  check("y_0^0", y[shtool::sh_index(0, 0)], 0.28209479177387814, ulp4);
  check("y_1^-1", y[shtool::sh_index(1, -1)], -c * w.y(), ulp4);
  check("y_1^0", y[shtool::sh_index(1, 0)], c * w.z(), ulp4);
  check("y_1^1", y[shtool::sh_index(1, 1)], -c * w.x(), ulp4);
}

// g = rotate(f) must satisfy g(R w) = f(w) ([2]: g(w) = f(R^-1 w)).
void check_rotated(const char* name, const std::vector<double>& f, const std::vector<double>& g, int order,
                   const shtool::Mat3<double>& r, double tol) {
  for (shtool::Vec3<double> w : kDirections) {
    w.normalize();
    check(name, evaluate(g, order, r * w), evaluate(f, order, w), tol);
  }
}

void check_rotations(const shtool::Mat3<double>& r) {
  const std::filesystem::path helpers_path = shtool::default_rotation_helpers_path();
  require(!helpers_path.empty(), "rotation-helpers.shtb not found through SHTOOL_TABLES");
  if (helpers_path.empty()) return;
  shtool::Result<shtool::RotationHelpers> helpers = shtool::RotationHelpers::load(helpers_path);
  require(helpers.ok(), "cannot load the rotation helpers:", helpers.ok() ? "" : helpers.error().message.c_str());
  if (!helpers) return;
  require(helpers.value().order >= 8, "the rotation helpers cover fewer than 8 bands");
  const auto shared = std::make_shared<const shtool::RotationHelpers>(std::move(helpers).value());
  for (int order : {3, 8}) {
    const std::vector<double> f = test_vector(order);
    std::vector<double> g(f.size());
    shtool::ShRotation<double> rotation(order, shared);
    require(rotation.set(r, shtool::RotationMethod::zxzxz), "zxzxz rotation refused a rotation matrix");
    rotation.apply(f, g);
    check_rotated(order == 3 ? "zxzxz N=3" : "zxzxz N=8", f, g, order, r, 1e-12);
    // Float, through the same tables.
    std::vector<float> ff(f.begin(), f.end()), gf(f.size());
    shtool::ShRotation<float> rotf(order, shared);
    require(rotf.set(r.cast<float>()), "float rotation refused a rotation matrix");
    rotf.apply(ff, gf);
    check_rotated("float N=8", f, std::vector<double>(gf.begin(), gf.end()), order, r, 1e-5);
  }

  // ZHF with the shipped shared-lobe table ([1] Eq. 10).
  const std::filesystem::path lobes_path = shtool::default_zhf_lobes_path(4);
  require(!lobes_path.empty(), "no zhf-shared table found through SHTOOL_TABLES");
  if (lobes_path.empty()) return;
  shtool::Result<shtool::ZhfLobes> lobes = shtool::ZhfLobes::load(lobes_path);
  require(lobes.ok(), "cannot load the ZHF lobes:", lobes.ok() ? "" : lobes.error().message.c_str());
  if (!lobes) return;
  const std::vector<double> f = test_vector(4);
  std::vector<double> g(f.size());
  shtool::ZhfRotation<double> zhf(4, std::make_shared<const shtool::ZhfLobes>(std::move(lobes).value()));
  require(zhf.set(r), "ZhfRotation refused a rotation matrix");
  zhf.apply(f, g);
  check_rotated("zhf N=4", f, g, 4, r, 1e-9);
}

// Orders <= 2 multiply into order 3 exactly: (f1 f2)(w) = f1(w) f2(w) pointwise.
void check_products() {
  const std::filesystem::path path = shtool::find_shipped_table("tripling-tensor.shtb");
  require(!path.empty(), "tripling-tensor.shtb not found through SHTOOL_TABLES");
  if (path.empty()) return;
  shtool::Result<shtool::TriplingTensor> tensor = shtool::TriplingTensor::load(path);
  require(tensor.ok(), "bad tripling tensor:", tensor.ok() ? "" : tensor.error().message.c_str());
  if (!tensor) return;
  std::vector<double> f1(9, 0.0), f2(9, 0.0), g(9);
  for (int i = 0; i < 4; ++i) {
    f1[i] = 0.5 + 0.25 * i;
    f2[i] = 1.0 - 0.3 * i;
  }
  for (shtool::ProductMethod method :
       {shtool::ProductMethod::tripling, shtool::ProductMethod::fourier, shtool::ProductMethod::grid}) {
    shtool::ShProduct<double> product(3, method, &tensor.value());
    product.triple(f1, f2, g);
    for (shtool::Vec3<double> w : kDirections) {
      w.normalize();
      check("triple product", evaluate(g, 3, w), evaluate(f1, 3, w) * evaluate(f2, 3, w), 1e-13);
    }
  }
}

// A fit-zh table shaded by [4] Eq. 13 equals the lobes summed into SH, dotted with the
// light; the light-specialised table of Eq. 24-25 agrees within its documented bound.
void check_zh_fit(const char* path) {
  shtool::Result<shtool::ZhFitTable<double>> fit = shtool::ZhFitTable<double>::load(path);
  require(fit.ok(), "cannot load the zh-fit table:", fit.ok() ? "" : fit.error().message.c_str());
  if (!fit) return;
  const shtool::ZhFitTable<double>& z = fit.value();
  require(z.vertices > 0 && z.lobes > 0 && z.order > 0, "empty zh-fit table");
  const std::vector<double> light = test_vector(z.order);
  const shtool::ZhLightTable<double> light_table(z.order, light);
  double scale = 0;
  for (double c : light) scale += c * c;
  // Band l's look-up error is relative to sqrt((2l+1)/(4 pi)) |e_l| <= that factor at
  // l = n-1 times |light|.
  scale = std::sqrt(scale) * std::max(1.0, std::sqrt((2.0 * z.order - 1.0) / (4 * std::numbers::pi)));
  for (std::size_t v = 0; v < std::min<std::size_t>(z.vertices, 50); ++v) {
    std::vector<double> sh(shtool::sh_count(z.order), 0.0);
    for (int k = 0; k < z.lobes; ++k)
      shtool::add_zh_lobe_to_sh(z.axes_of(v)[k], z.coeffs_of(v).subspan(k * z.order, z.order), sh);
    double want = 0;
    for (std::size_t i = 0; i < sh.size(); ++i) want += sh[i] * light[i];
    const double exact = shtool::zh_shade_exact<double>(light, z.axes_of(v), z.coeffs_of(v));
    check("zh_shade_exact", exact, want, 1e-12);
    double coeff_sum = 0;
    for (double c : z.coeffs_of(v)) coeff_sum += std::abs(c);
    const double bound = shtool::zh_light_table_error_bound(z.order - 1, light_table.resolution()) * scale * coeff_sum;
    const double tabled = light_table.shade(z.axes_of(v), z.coeffs_of(v));
    require(std::abs(tabled - want) <= bound + 1e-12, "ZhLightTable::shade is outside its error bound");
  }
  shtool::Result<shtool::ZhFitTable<float>> fitf = shtool::ZhFitTable<float>::load(path);
  require(fitf.ok() && fitf.value().vertices == z.vertices, "the float load of the zh-fit table differs");
  std::printf("consumer: shaded %zu vertices of %s (%d lobes, order %d)\n", z.vertices, path, z.lobes, z.order);
}

// Every kind through X::load and, from the same bytes, X::from_table; T = float and
// double where the type is a parameter.
template <class X>
void check_loads(const std::filesystem::path& path, const char* what) {
  const shtool::Result<X> loaded = X::load(path);
  require(loaded.ok(), what, loaded.ok() ? "" : loaded.error().message.c_str());
  const shtool::Result<shtool::Table> table = shtool::read_table(path);
  require(table.ok() && X::from_table(table.value()).ok(), what, "from_table refused what load accepts");
}

template <class T>
void check_every_kind(const char* fit, const char* lighting, const char* probes) {
  check_loads<shtool::RotationHelpers>(shtool::default_rotation_helpers_path(), "rotation-helpers:");
  check_loads<shtool::ZhfLobes>(shtool::default_zhf_lobes_path(4), "zhf-lobes:");
  check_loads<shtool::TriplingTensor>(shtool::find_shipped_table("tripling-tensor.shtb"), "tripling-tensor:");
  check_loads<shtool::ShFourierTensors>(shtool::find_shipped_table("sh-fourier-tensors.shtb"), "sh-fourier-tensors:");
  if (fit) check_loads<shtool::ZhFitTable<T>>(fit, "zh-fit:");
  if (lighting) check_loads<shtool::ShLighting<T>>(lighting, "env-sh:");
  if (probes) check_loads<shtool::ProbeGrid<T>>(probes, "probe-grid:");
}

// The program of docs/engine.md against the same shading of the lighting turned in double
// by the reference method (no tables), and a product by 1 against its input.
void check_engine_example(const char* fit, const char* lighting, const char* low_lighting,
                          const shtool::Mat3<double>& r) {
  float rgb[3];
  require(shade_vertex(fit, lighting, r.cast<float>(), rgb), "engine_example: shade_vertex failed");
  const auto z = shtool::ZhFitTable<double>::load(fit);
  const auto l = shtool::ShLighting<double>::load(lighting);
  if (!z || !l) return;
  shtool::ShRotation<double> reference(l.value().order, nullptr);
  require(reference.set(r.transpose(), shtool::RotationMethod::reference), "the reference rotation refused");
  std::vector<double> channel(shtool::sh_count(l.value().order)), turned(channel.size());
  for (int c = 0; c < 3; ++c) {
    l.value().channel(c, channel);
    reference.apply(channel, turned);
    const std::span<const double> bands = std::span<const double>(turned).first(shtool::sh_count(z.value().order));
    double want = shtool::zh_shade_exact<double>(bands, z.value().axes_of(0), z.value().coeffs_of(0));
    for (int k = 0; k < z.value().direct_count; ++k) want += z.value().direct_of(0)[k] * turned[k];
    check("engine_example vertex 0", rgb[c], want, 1e-4);
  }
  std::vector<float> f(channel.begin(), channel.end());
  const float worst = multiply_by_one(f);
  // Lighting of a lower order than the fit is refused, not read past its end.
  if (low_lighting)
    require(!shade_vertex(fit, low_lighting, r.cast<float>(), rgb),
            "engine_example: shaded a fit with lower-order lighting");
  require(worst >= 0, "engine_example: the tripling tensor did not load");
  check("engine_example f * 1 - f", worst, 0.0, 1e-5);
}

// The glossy view map: a texel centre's direction maps back to its square point, and the
// wrinkle blend's weights sum to 1 (the headers an engine includes for glossy and
// wrinkle shading, compiled without exceptions).
void check_view_map_and_wrinkle_weights() {
  for (const double a : {0.05, 0.3, 0.5, 0.93})
    for (const double b : {0.1, 0.5, 0.71}) {
      const shtool::Vec3<double> v = shtool::glossy_view_direction(a, b);
      check("glossy view direction |v|", v.norm(), 1.0, 1e-14);
      const std::array<double, 2> back = shtool::glossy_view_square(v);
      check("glossy view square a", back[0], a, 1e-12);
      check("glossy view square b", back[1], b, 1e-12);
    }
  const shtool::WrinkleWeights<double> w = shtool::wrinkle_weights<double>(8, 1.0, 1.37, 0.4);
  check("wrinkle weights sum", w.weight[0] + w.weight[1] + w.weight[2] + w.weight[3], 1.0, 1e-15);
}

}  // namespace

int main(int argc, char** argv) {
  if (std::strcmp(shtool::kVersion, SHTOOL_PACKAGE_VERSION) != 0) {
    std::fprintf(stderr, "consumer: package version %s but shtool/version.h says %s\n", SHTOOL_PACKAGE_VERSION,
                 shtool::kVersion);
    ++failures;
  }
  check_sh_closed_forms();
  const shtool::Mat3<double> r = shtool::matrix_from_zyz<double>({0.7, 1.1, -0.4});
  check_rotations(r);
  check_products();
  check_view_map_and_wrinkle_weights();
  if (argc > 1) check_zh_fit(argv[1]);
  const char* fit = argc > 1 ? argv[1] : nullptr;
  const char* lighting = argc > 2 ? argv[2] : nullptr;
  const char* probes = argc > 3 ? argv[3] : nullptr;
  const char* low_lighting = argc > 4 ? argv[4] : nullptr;
  check_every_kind<float>(fit, lighting, probes);
  check_every_kind<double>(fit, lighting, probes);
  if (fit && lighting) check_engine_example(fit, lighting, low_lighting, r);

  if (failures != 0) {
    std::fprintf(stderr, "consumer: %d check(s) failed\n", failures);
    return 1;
  }
  std::printf("consumer: shtool %s runtime OK (tables, rotations, products%s; -fno-exceptions -fno-rtti)\n",
              shtool::kVersion, argc > 1 ? ", zh-fit shading" : "");
  return 0;
}
