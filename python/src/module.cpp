// The extension module shtool._shtool and the helpers every binding shares.
#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/sh_inputs.h"
#include "py_arrays.h"
#include "shtool/table.h"
#include "shtool/version.h"

namespace shtool::python {

Precision precision_of(const py::array& a, const std::string& what) {
  if (a.dtype().equal(py::dtype::of<float>())) return Precision::f32;
  if (a.dtype().equal(py::dtype::of<double>())) return Precision::f64;
  throw py::type_error(what + " must be float32 or float64, got " + std::string(py::str(a.dtype())));
}

py::array_t<double, py::array::c_style> as_f64(const py::handle& obj, const std::string& what) {
  // Real numbers only: numpy would take a complex array's real part (with a warning), a
  // bool as 0 or 1, and fail on strings with its own message.
  const std::string type_name = py::str(obj.get_type().attr("__name__"));
  py::array a = py::array::ensure(obj);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(what + " must be an array of numbers, got " + type_name);
  }
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(what + " must be an array of real numbers, got " +
                         (kind == 'O' || kind == 'U' || kind == 'S' ? type_name
                                                                    : "dtype " + std::string(py::str(a.dtype()))));
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
}

std::vector<py::ssize_t> shape_of(const py::array& a) { return {a.shape(), a.shape() + a.ndim()}; }

bool overlaps(const py::array& a, const py::array& b) {
  const auto* a0 = static_cast<const char*>(a.data());
  const auto* b0 = static_cast<const char*>(b.data());
  return a.nbytes() > 0 && b.nbytes() > 0 && a0 < b0 + b.nbytes() && b0 < a0 + a.nbytes();
}

void for_chunks(std::size_t count, int threads, const std::function<void(std::size_t, std::size_t)>& body) {
  const std::size_t chunks = (count + kChunk - 1) / kChunk;
  if (chunks <= 1) {
    body(0, count);
    return;
  }
  if (threads == 1) {  // still in chunks: each chunk's scratch stays in cache
    for (std::size_t c = 0; c < chunks; ++c) body(c * kChunk, std::min(count, (c + 1) * kChunk));
    return;
  }
  parallel_for(chunks, resolve_threads(threads),
               [&](std::size_t c) { body(c * kChunk, std::min(count, (c + 1) * kChunk)); });
}

void check_threads(int threads) {
  // Asked once: the system's core count is read from a file, which would be most of a
  // one-vector call.
  static const int most = max_threads();
  if (threads < 0) throw py::value_error("threads=" + std::to_string(threads) + ": must be 0 (every core) or more");
  if (threads > most)
    throw py::value_error("threads=" + std::to_string(threads) + " is more than this machine can use (at most " +
                          std::to_string(most) + ")");
}

namespace {
std::mutex package_tables_mutex;
std::filesystem::path package_tables;
}  // namespace

void set_package_tables(const std::string& dir) {
  std::lock_guard<std::mutex> lock(package_tables_mutex);
  package_tables = dir;
}

std::filesystem::path find_module_table(const std::string& file_name) {
  std::vector<std::filesystem::path> dirs;
  if (const char* env = std::getenv("SHTOOL_TABLES"); env && *env) dirs.emplace_back(env);
  {
    std::lock_guard<std::mutex> lock(package_tables_mutex);
    if (!package_tables.empty()) dirs.push_back(package_tables);
  }
  for (const std::filesystem::path& dir : dirs) {
    std::error_code ec;
    const std::filesystem::path p = dir / file_name;
    if (std::filesystem::is_regular_file(p, ec)) return p;
  }
  return find_shipped_table(file_name);
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
      PyErr_SetObject(PyExc_ValueError, sp::message_text(e.what()).ptr());
    } catch (const std::invalid_argument& e) {
      PyErr_SetObject(PyExc_ValueError, sp::message_text(e.what()).ptr());
    }
  });
  m.def("_set_package_tables", &sp::set_package_tables, pybind11::arg("dir"));
  sp::bind_sh(m);
  sp::bind_lighting(m);
  sp::bind_jobs(m);
  sp::bind_tables(m);
}
