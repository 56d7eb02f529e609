// The extension module shtool._shtool and the helpers every binding shares.
#include <stdexcept>
#include <string>

#include "common/input_error.h"
#include "common/sh_inputs.h"
#include "py_arrays.h"
#include "shtool/version.h"

namespace shtool::python {

Precision precision_of(const py::array& a, const std::string& what) {
  if (a.dtype().is(py::dtype::of<float>())) return Precision::f32;
  if (a.dtype().is(py::dtype::of<double>())) return Precision::f64;
  throw py::type_error(what + " must be float32 or float64, got " + std::string(py::str(a.dtype())));
}

py::array_t<double, py::array::c_style> as_f64(const py::handle& obj, const std::string& what) {
  try {
    return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  } catch (const py::error_already_set&) {
  }
  throw py::value_error(what + " must be an array of numbers");
}

std::vector<py::ssize_t> shape_of(const py::array& a) { return {a.shape(), a.shape() + a.ndim()}; }

bool overlaps(const py::array& a, const py::array& b) {
  const auto* a0 = static_cast<const char*>(a.data());
  const auto* b0 = static_cast<const char*>(b.data());
  return a.nbytes() > 0 && b.nbytes() > 0 && a0 < b0 + b.nbytes() && b0 < a0 + a.nbytes();
}

int order_of_count(py::ssize_t count, const std::string& what) {
  int n = 0;
  while (static_cast<py::ssize_t>(n + 1) * (n + 1) <= count) ++n;
  if (n < 1 || static_cast<py::ssize_t>(n) * n != count)
    throw py::value_error(what + ": " + std::to_string(count) + " coefficients is not a square N^2 (order N >= 1)");
  if (n > kMaxOrder) throw py::value_error(what + ": order " + std::to_string(n) + " is above " + std::to_string(kMaxOrder));
  return n;
}

Mat3<double> rotation_from(const py::handle& matrix) {
  const auto m = as_f64(matrix, "matrix");
  if (m.ndim() != 2 || m.shape(0) != 3 || m.shape(1) != 3)
    throw py::value_error("matrix must have shape (3, 3)");
  Mat3<double> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m.at(i, j);
  return checked_rotation_matrix(r, "matrix");
}

}  // namespace shtool::python

PYBIND11_MODULE(_shtool, m) {
  namespace sp = shtool::python;
  m.doc() = "Spherical harmonics: the shtool runtime and offline jobs on numpy arrays (docs/python.md)";
  m.attr("__version__") = shtool::kVersion;
  // The library's one error type for bad input is the Python one for bad values.
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const shtool::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  sp::bind_sh(m);
  sp::bind_lighting(m);
  sp::bind_jobs(m);
  sp::bind_tables(m);
}
