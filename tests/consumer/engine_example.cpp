// What an engine does with shtool's runtime: load a fit-zh table and the lighting, turn
// the lighting with the object, shade a vertex; load the tripling tensor and multiply.
// Every table kind loads the same way, X::load(path) or X::from_table(table), returning
// Result<X>; nothing here throws. Built with -fno-exceptions -fno-rtti.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <span>
#include <vector>

#include <shtool/euler.h>
#include <shtool/lighting.h>
#include <shtool/rotation.h>
#include <shtool/sh.h>
#include <shtool/table.h>
#include <shtool/tripling_product.h>
#include <shtool/zh_fit_table.h>
#include <shtool/zh_shading.h>

using T = float;  // or double: every type below takes either

// Prints a failed load and tells the caller to stop.
template <class X>
bool loaded(const shtool::Result<X>& x) {
  if (!x) std::fprintf(stderr, "%s\n", x.error().message.c_str());
  return x.ok();
}

// Exit radiance of vertex 0 of `fit_path` (a `shtool fit-zh` table) under the lighting of
// `lighting_path` (a `shtool light` or `project-env` table) turned by `object`: rgb[c].
// Returns false when a table does not load or the lighting has fewer bands than the fit.
bool shade_vertex(const char* fit_path, const char* lighting_path, const shtool::Mat3<T>& object, T rgb[3]) {
  const auto fit = shtool::ZhFitTable<T>::load(fit_path);
  const auto light = shtool::ShLighting<T>::load(lighting_path);
  const auto helpers = shtool::RotationHelpers::load(shtool::default_rotation_helpers_path());
  if (!loaded(fit) || !loaded(light) || !loaded(helpers)) return false;
  const shtool::ZhFitTable<T>& z = fit.value();
  // Each band of the fit is shaded by the same band of the lighting.
  if (light.value().order < z.order) {
    std::fprintf(stderr, "%s: order %d lighting, the fit needs %d\n", lighting_path, light.value().order, z.order);
    return false;
  }

  // The lobes live in the object's frame: turn the lighting by the inverse of the object's
  // rotation (g(w) = f(R^-1 w), docs/conventions.md), its three channels in one call.
  shtool::ShRotation<T> rotation(light.value().order,
                                 std::make_shared<const shtool::RotationHelpers>(helpers.value()));
  if (!rotation.set(object.transpose())) return false;
  const std::size_t n2 = shtool::sh_count(light.value().order);
  std::vector<T> turned_rgb(3 * n2), turned(n2);
  if (!rotation.apply(light.value().coefficients, turned_rgb, 3)) return false;
  for (int c = 0; c < 3; ++c) {
    for (std::size_t i = 0; i < n2; ++i) turned[i] = turned_rgb[i * 3 + c];  // interleaved [i * 3 + c]
    // [4] Eq. 13 with the fit's bands (the lighting may have more), plus the coefficients
    // the fit stores directly (DC, then the linear band).
    const std::span<const T> bands = std::span<const T>(turned).first(shtool::sh_count(z.order));
    rgb[c] = shtool::zh_shade_exact<T>(bands, z.axes_of(0), z.coeffs_of(0));
    for (int k = 0; k < z.direct_count; ++k) rgb[c] += z.direct_of(0)[k] * turned[k];
  }
  return true;
}

// The SH product of `f` and the constant function 1 by the shipped tripling tensor: f
// again (truncated to the tensor's order). Returns the largest difference, or -1 when the
// tensor does not load.
T multiply_by_one(std::span<const T> f) {
  const auto tensor = shtool::TriplingTensor::load(shtool::find_shipped_table("tripling-tensor.shtb"));
  if (!loaded(tensor)) return -1;
  const shtool::TriplingProduct<T> product(tensor.value());
  const std::size_t n2 = shtool::sh_count(product.order());
  std::vector<T> a(n2, T(0)), one(n2, T(0)), g(n2);
  for (std::size_t i = 0; i < n2 && i < f.size(); ++i) a[i] = f[i];
  one[0] = T(3.5449077018110318);  // sqrt(4 pi): 1 = sqrt(4 pi) y_0^0
  product.multiply(a, one, g);
  T worst = 0;
  for (std::size_t i = 0; i < n2; ++i) worst = std::max(worst, std::abs(g[i] - a[i]));
  return worst;
}
