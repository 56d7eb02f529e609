// What every binding shares: the dtype rule (float32 and float64 kept, anything else a
// TypeError), C-contiguous views without copies, output arrays (allocated or the
// caller's `out=`), and errors as Python exceptions (ValueError for bad input).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "shtool/euler.h"
#include "shtool/result.h"

namespace shtool::python {

namespace py = pybind11;

enum class Precision { f32, f64 };

// float32 or float64; TypeError naming `what` for any other dtype.
Precision precision_of(const py::array& a, const std::string& what);

// `obj` as a C-contiguous array of T: the same memory when it already is one (numpy makes
// no copy then), a contiguous copy otherwise. The dtype must already be T.
template <class T>
py::array_t<T, py::array::c_style> contiguous(const py::handle& obj) {
  return py::array_t<T, py::array::c_style>::ensure(obj);
}

// Any array-like as float64, C-contiguous (matrices, directions, colours, quaternions).
py::array_t<double, py::array::c_style> as_f64(const py::handle& obj, const std::string& what);

// The output of a call: a new array of `shape`, or the caller's `out`, which must then be
// a writeable C-contiguous array of T and exactly that shape (ValueError otherwise).
template <class T>
py::array_t<T, py::array::c_style> output(const std::vector<py::ssize_t>& shape, const py::object& out) {
  if (out.is_none()) return py::array_t<T, py::array::c_style>(shape);
  if (!py::isinstance<py::array>(out)) throw py::type_error("out must be a numpy array");
  py::array a = py::reinterpret_borrow<py::array>(out);
  if (!a.dtype().equal(py::dtype::of<T>()))
    throw py::type_error(std::string("out must have dtype ") + (sizeof(T) == 4 ? "float32" : "float64"));
  if (!(a.flags() & py::array::c_style)) throw py::value_error("out must be C-contiguous");
  if (!a.writeable()) throw py::value_error("out is read-only");
  if (std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()) != shape)
    throw py::value_error("out has the wrong shape");
  return py::reinterpret_borrow<py::array_t<T, py::array::c_style>>(a);
}

template <class T>
std::span<const T> span_of(const py::array_t<T, py::array::c_style>& a) {
  return {a.data(), static_cast<std::size_t>(a.size())};
}
template <class T>
std::span<T> mutable_span_of(py::array_t<T, py::array::c_style>& a) {
  return {a.mutable_data(), static_cast<std::size_t>(a.size())};
}

std::vector<py::ssize_t> shape_of(const py::array& a);

// Whether two arrays' bytes overlap (kernels that read and write must not alias).
bool overlaps(const py::array& a, const py::array& b);

// Batches below this many vectors run on the calling thread: starting workers costs
// more than the work.
constexpr std::size_t kChunk = 4096;

// body(begin, end) over [0, count) in chunks of kChunk, on `threads` workers (0: every
// core) when there is more than one chunk. The caller has checked `threads`
// (check_threads) and released the GIL.
void for_chunks(std::size_t count, int threads, const std::function<void(std::size_t, std::size_t)>& body);

// threads= as every call checks it, whatever the batch size: 0 (every core) up to the
// most the jobs allow (common/parallel_for.h); ValueError naming threads= otherwise.
void check_threads(int threads);

// A shipped table the module reads (rotation helpers, zhf lobes), looked for in
// $SHTOOL_TABLES, then the package's own tables/ folder (set_package_tables, at import:
// a wheel and the build tree's package carry the tables the module needs), then
// <prefix>/share/shtool/tables (find_shipped_table). Empty if none has it.
std::filesystem::path find_module_table(const std::string& file_name);
void set_package_tables(const std::string& dir);

// The order N of a last axis of N^2 coefficients; ValueError otherwise.
int order_of_count(py::ssize_t count, const std::string& what);

// A 3x3 rotation, checked as the CLI checks --matrix.
Mat3<double> rotation_from(const py::handle& matrix);

// The value of a runtime Result, or ValueError with its message.
template <class T>
T value_or_raise(Result<T> r) {
  if (!r) throw py::value_error(r.error().message);
  return std::move(r).value();
}

// The value named `name` in one of the jobs' (name, value) lists; ValueError listing the
// names otherwise.
template <class E>
E choice(const std::string& name, const std::vector<std::pair<std::string, E>>& names, const std::string& what) {
  std::string known;
  for (const auto& [n, v] : names) {
    if (n == name) return v;
    known += (known.empty() ? "" : ", ") + n;
  }
  throw py::value_error(what + ": unknown value '" + name + "' (" + known + ")");
}

// A finite vector that an operation took past T's range (values near its largest) is
// refused, as the CLI refuses it, not handed back as inf or NaN; a vector whose inputs
// hold NaN or inf comes back non-finite, as numpy's arithmetic would. `inputs_finite(k)`
// says whether the inputs of output vector k are finite; `what` names the operation
// ("rotate: the rotation").
template <class T, class InputsFinite>
void refuse_overflow(const std::string& what, const T* out, std::size_t count, std::size_t n2,
                     InputsFinite inputs_finite) {
  for (std::size_t k = 0; k < count; ++k) {
    if (std::all_of(out + k * n2, out + (k + 1) * n2, [](T v) { return std::isfinite(v); })) continue;
    if (inputs_finite(k))
      throw py::value_error(what + " of vector " + std::to_string(k) + " overflows " +
                            (sizeof(T) == 4 ? "float32" : "float64") + " (coefficients too large)");
  }
}

template <class T>
bool all_finite(const T* values, std::size_t count) {
  return std::all_of(values, values + count, [](T v) { return std::isfinite(v); });
}

// The binding groups (one translation unit each).
// A path the library returns, as os.fsdecode gives it (a name that is not UTF-8 keeps its
// bytes as surrogates, so that it names the same file when passed back).
inline py::str path_text(const std::string& path) {
  PyObject* s = PyUnicode_DecodeFSDefaultAndSize(path.data(), static_cast<Py_ssize_t>(path.size()));
  if (!s) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(s);
}

// A message of the library, which may quote a path that is not UTF-8: its bytes shown as
// \xNN (printing surrogates would fail).
inline py::str message_text(const std::string& message) {
  PyObject* s = PyUnicode_DecodeUTF8(message.data(), static_cast<Py_ssize_t>(message.size()), "backslashreplace");
  if (!s) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(s);
}

void bind_sh(py::module_& m);
void bind_lighting(py::module_& m);
void bind_jobs(py::module_& m);
void bind_tables(py::module_& m);

}  // namespace shtool::python
