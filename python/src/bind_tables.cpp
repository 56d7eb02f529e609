// load_table and the typed loaders. The engine API's loaders are used here only, so that
// a change of their names touches one file.
#include <memory>
#include <string>

#include "py_arrays.h"
#include "shtool/env_projection.h"
#include "shtool/fourier_tensors.h"
#include "shtool/glossy.h"
#include "shtool/rotation_helpers.h"
#include "shtool/table.h"
#include "shtool/tripling_product.h"
#include "shtool/wrinkle_map.h"
#include "shtool/zh_fit_table.h"
#include "shtool/zhf_rotation.h"

namespace shtool::python {
namespace {

py::dtype numpy_dtype(DType t) {
  switch (t) {
    case DType::f64: return py::dtype("<f8");
    case DType::f32: return py::dtype("<f4");
    case DType::i32: return py::dtype("<i4");
    case DType::u32: return py::dtype("<u4");
    case DType::i64: return py::dtype("<i8");
    case DType::u64: return py::dtype("<u8");
    case DType::u8: return py::dtype("u1");
  }
  throw py::value_error("unknown table dtype");
}

// What the engine API's typed loader of `kind` checks beyond read_table (shapes against
// each other, finiteness, unit axes, ...), or an error naming the problem.
std::optional<std::string> typed_problem(const Table& t, const std::string& path) {
  auto problem = [&](const auto& r) -> std::optional<std::string> {
    if (r) return std::nullopt;
    return path + ": " + r.error().message;
  };
  if (t.kind == kZhFitKind) return problem(ZhFitTable<double>::from_table(t));
  if (t.kind == kGlossyZhKind) return problem(GlossyFit<double>::from_table(t));
  if (t.kind == kWrinkleZhKind) return problem(WrinkleMap<double>::from_table(t));
  if (t.kind == kRotationHelpersKind) return problem(RotationHelpers::from_table(t));
  if (t.kind == kTriplingTensorKind) return problem(TriplingTensor::from_table(t));
  if (t.kind == kShFourierTensorsKind) return problem(ShFourierTensors::from_table(t));
  if (t.kind == kZhfLobesKind) return problem(ZhfLobes::from_table(t));
  return std::nullopt;  // env-sh and the rest: read_table's checks are the loader's
}

// (kind, order, header JSON text, {name: read-only array viewing the loaded bytes}); the
// arrays keep the loaded table alive. With `kind`, the table must be of that kind and
// pass its typed loader's checks.
py::tuple load_table(const std::string& path, const std::string& kind) {
  TableFileInfo info;
  TableExpectation expect;
  expect.kind = kind;
  Result<Table> loaded = [&] {
    py::gil_scoped_release release;
    return read_table(path, expect, &info);
  }();
  auto table = std::make_shared<Table>(value_or_raise(std::move(loaded)));
  if (!kind.empty()) {
    std::optional<std::string> problem;
    {
      py::gil_scoped_release release;  // the typed loader's checks go over every value
      problem = typed_problem(*table, path);
    }
    if (problem) throw py::value_error(*problem);
  }
  py::capsule owner(new std::shared_ptr<Table>(table),
                    [](void* p) { delete static_cast<std::shared_ptr<Table>*>(p); });
  py::dict arrays;
  for (TableArray& a : table->arrays) {
    std::vector<py::ssize_t> shape(a.shape.begin(), a.shape.end());
    py::array view(numpy_dtype(a.dtype), shape, static_cast<const void*>(a.data.data()), owner);
    py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    arrays[py::str(a.name)] = view;
  }
  return py::make_tuple(table->kind, table->order, info.header_json, arrays);
}

py::tuple load_zh_fit_table(const std::string& path) {
  Result<ZhFitTable<double>> loaded = [&] {
    py::gil_scoped_release release;
    return ZhFitTable<double>::load(path);
  }();
  ZhFitTable<double> t = value_or_raise(std::move(loaded));
  const py::ssize_t v = static_cast<py::ssize_t>(t.vertices), n = t.lobes;
  auto copy = [](const double* p, std::vector<py::ssize_t> shape) {
    py::array_t<double> out(shape);
    std::copy(p, p + out.size(), out.mutable_data());
    return out;
  };
  return py::make_tuple(copy(t.axes.data()->data(), {v, n, 3}), copy(t.coeffs.data(), {v, n, py::ssize_t(t.order)}),
                        copy(t.residual.data(), {v}), copy(t.norm.data(), {v}),
                        copy(t.direct.data(), {v, py::ssize_t(t.direct_count)}));
}

}  // namespace

void bind_tables(py::module_& m) {
  m.def("_load_table", &load_table, py::arg("path"), py::arg("kind") = "");
  m.def("_load_zh_fit", &load_zh_fit_table, py::arg("path"));
}

}  // namespace shtool::python
