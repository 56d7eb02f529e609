// Every table kind's loader on tables that passed the container's checks (checksums off,
// so mutations reach the kind validators), then the runtime code that consumes each kind:
// a loader that accepts a table must make every later call safe.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "shtool/euler.h"
#include "shtool/fourier_tensors.h"
#include "shtool/glossy.h"
#include "shtool/probe_grid.h"
#include "shtool/rotation.h"
#include "shtool/rotation_helpers.h"
#include "shtool/table.h"
#include "shtool/tripling_product.h"
#include "shtool/wrinkle_map.h"
#include "shtool/zh_fit_table.h"
#include "shtool/zh_shading.h"
#include "shtool/zhf_rotation.h"

namespace {

const shtool::Mat3<double> kRotation = shtool::matrix_from_zyz<double>({0.3, 0.9, -1.2});

void exercise_rotation(const shtool::RotationHelpers& h) {
  const int order = std::min(h.order, 8);
  auto shared = std::make_shared<const shtool::RotationHelpers>(h);
  std::vector<double> f(shtool::sh_count(order), 0.5), g(f.size());
  for (shtool::RotationMethod m : {shtool::RotationMethod::zxzxz, shtool::RotationMethod::taylor2}) {
    shtool::ShRotation<double> r(order, shared);
    if (r.set(kRotation, m)) r.apply(f, g);
  }
}

void exercise_zhf(const shtool::ZhfLobes& z) {
  const int order = std::min(z.order, 8);
  if (order < 1) return;
  auto shared = std::make_shared<const shtool::ZhfLobes>(z);
  std::vector<double> f(shtool::sh_count(order), 0.25), g(f.size());
  shtool::ZhfRotation<double> r(order, shared);
  r.set(kRotation);
  r.apply(f, g);
}

void exercise_tripling(const shtool::TriplingTensor& t) {
  const int order = std::min(t.order, 6);
  shtool::TriplingProduct<double> p(t);
  std::vector<double> a(shtool::sh_count(order), 0.5), b(a.size(), 0.25), c(a.size());
  if (p.order() == order) p.multiply(a, b, c);
}

void exercise_zh_fit(const shtool::ZhFitTable<double>& z) {
  std::vector<double> light(shtool::sh_count(z.order), 0.1);
  for (std::size_t v = 0; v < std::min<std::size_t>(z.vertices, 8); ++v)
    (void)shtool::zh_shade_exact<double>(light, z.axes_of(v), z.coeffs_of(v));
}

template <class T>
void exercise_wrinkle(const shtool::WrinkleMap<T>& m) {
  std::vector<T> light(shtool::sh_count(m.order), T(0.1));
  const Eigen::Matrix<T, 3, 3> frame = kRotation.cast<T>();
  const T inf = std::numeric_limits<T>::infinity(), nan = std::numeric_limits<T>::quiet_NaN();
  for (const T x : {T(-3.7), T(0), T(0.4999), T(1), inf, nan})
    for (const T d : {T(-1), T(0), T(0.5) * m.max_depth, std::numeric_limits<T>::max(), inf, nan})
      (void)m.shade(light, frame, x, d);
}

template <class T>
void exercise_glossy(const shtool::GlossyFit<T>& g) {
  using V = shtool::Vec3<T>;
  std::vector<T> light(shtool::sh_count(g.rows.order), T(0.1));
  const T inf = std::numeric_limits<T>::infinity(), nan = std::numeric_limits<T>::quiet_NaN();
  for (std::size_t v = 0; v < std::min<std::size_t>(g.vertices, 8); ++v)
    for (const V& view : {V(0, 0, 1), V(1, 0, 0), V(0.3, -0.4, -0.8), V(0, 0, 0), V(0.1, 0, inf), V(nan, 0, 1)})
      (void)g.shade(light, v, view);
}

template <class T>
void exercise_probe_grid(const shtool::ProbeGrid<T>& g) {
  using V = shtool::Vec3<T>;
  std::vector<T> out(g.values_per_probe());
  const T inf = std::numeric_limits<T>::infinity(), nan = std::numeric_limits<T>::quiet_NaN();
  for (const V& x : {V(0, 0, 0), g.min, g.max, V(-inf, 0, inf), V(nan, nan, nan), V(T(1e30), T(-1e30), 0)}) {
    g.sample(x, out);
    (void)g.irradiance_at(x, V(0, 0, 1));
  }
  for (std::size_t p = 0; p < std::min<std::size_t>(g.probe_count(), 8); ++p) {
    (void)g.position(p);
    (void)g.irradiance(p, V(0, 0, 1));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  const shtool::Result<shtool::Table> t = shtool::read_table_bytes(bytes, "fuzz", {}, nullptr, {false});
  if (!t) return 0;
  const shtool::Table& table = t.value();
  if (auto h = shtool::RotationHelpers::from_table(table)) exercise_rotation(h.value());
  if (auto z = shtool::ZhfLobes::from_table(table)) exercise_zhf(z.value());
  if (auto tr = shtool::TriplingTensor::from_table(table)) exercise_tripling(tr.value());
  (void)shtool::ShFourierTensors::from_table(table);
  if (auto z = shtool::ZhFitTable<double>::from_table(table)) exercise_zh_fit(z.value());
  (void)shtool::ZhFitTable<float>::from_table(table);
  if (auto w = shtool::WrinkleMap<double>::from_table(table)) exercise_wrinkle(w.value());
  if (auto w = shtool::WrinkleMap<float>::from_table(table)) exercise_wrinkle(w.value());
  if (auto g = shtool::GlossyFit<double>::from_table(table)) exercise_glossy(g.value());
  if (auto g = shtool::GlossyFit<float>::from_table(table)) exercise_glossy(g.value());
  if (auto g = shtool::ProbeGrid<double>::from_table(table)) exercise_probe_grid(g.value());
  if (auto g = shtool::ProbeGrid<float>::from_table(table)) exercise_probe_grid(g.value());
  return 0;
}
