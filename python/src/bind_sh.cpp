// eval_sh, rotate, quat_to_matrix, product: the runtime's basis, rotations and products
// over batches of coefficient vectors (the last axis; the Python layer moves `axis=`).
#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/sh_inputs.h"
#include "lobes/lobes.h"
#include "py_arrays.h"
#include "shtool/product.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "shtool/zhf_rotation.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool::python {
namespace {

void check_order(int order) {
  if (!is_supported_order(order))
    throw py::value_error("order " + std::to_string(order) + " is not supported (1.." + std::to_string(kMaxOrder) + ")");
}

template <class T>
py::array eval_sh_t(int order, const py::array& dirs_in, const py::object& out_arg, int threads) {
  const auto dirs = contiguous<T>(dirs_in);
  if (dirs.ndim() < 1 || dirs.shape(dirs.ndim() - 1) != 3) throw py::value_error("dirs must have shape (..., 3)");
  std::vector<py::ssize_t> shape = shape_of(dirs);
  shape.back() = sh_count(order);
  auto out = output<T>(shape, out_arg);
  if (overlaps(out, dirs)) throw py::value_error("out must not overlap dirs");
  const std::size_t count = static_cast<std::size_t>(dirs.size() / 3), n2 = sh_count(order);
  const T* d = dirs.data();
  T* o = out.mutable_data();
  std::size_t bad = count;  // first zero or non-finite direction
  {
    py::gil_scoped_release release;
    std::vector<std::size_t> first_bad((count + kChunk - 1) / kChunk, count);
    for_chunks(count, threads, [&](std::size_t begin, std::size_t end) {
      std::vector<T> unit(3 * (end - begin));
      for (std::size_t k = begin; k < end; ++k) {
        Vec3<T> w(d[3 * k], d[3 * k + 1], d[3 * k + 2]);
        if (!normalize_direction(w)) {
          first_bad[begin / kChunk] = k;
          return;
        }
        for (int c = 0; c < 3; ++c) unit[3 * (k - begin) + c] = w[c];
      }
      eval_sh_batch<T>(order, unit, std::span<T>(o + begin * n2, (end - begin) * n2));
    });
    for (std::size_t b : first_bad) bad = std::min(bad, b);
  }
  if (bad < count) throw py::value_error("dirs[" + std::to_string(bad) + "] is zero or not finite");
  return out;
}

// One V per key, made by make() once per process. Callers on several threads, with the
// GIL released: a slow make (helpers for a high order take seconds) holds only its own
// key, and a make that throws is tried again by the next call.
template <class V, class Make>
std::shared_ptr<const V> once_per_key(const std::string& key, Make make) {
  struct Slot {
    std::mutex mutex;
    std::shared_ptr<const V> value;
  };
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<Slot>> slots;
  std::shared_ptr<Slot> slot;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto& s = slots[key];
    if (!s) s = std::make_shared<Slot>();
    slot = s;
  }
  std::lock_guard<std::mutex> lock(slot->mutex);
  if (!slot->value) slot->value = make();
  return slot->value;
}

// The key of a table given by path: the file as it is now (a rewritten file is read again).
std::string file_key(int order, const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  const auto time = std::filesystem::last_write_time(path, ec);
  return std::to_string(order) + "\n" + path + "\n" + std::to_string(ec ? 0 : size) + "\n" +
         std::to_string(ec ? 0 : time.time_since_epoch().count());
}

// The helpers of the fast methods: from `tables` when given (covering the order), else
// the shipped table when it covers the order, else computed (seconds from order 40 on).
// Called with the GIL released.
std::shared_ptr<const RotationHelpers> helpers_for(int order, const std::string& tables) {
  if (!tables.empty())
    return once_per_key<RotationHelpers>(file_key(order, tables), [&] { return rotation_helpers_for(order, tables); });
  return once_per_key<RotationHelpers>(std::to_string(order), [&] {
    return shipped_rotation_helpers_for(order, find_module_table("rotation-helpers.shtb"));
  });
}

// The shared lobes of the zhf methods: from `tables` when given, else the shipped
// zhf-shared-N<n>.shtb of the smallest n >= order. Called with the GIL released.
std::shared_ptr<const ZhfLobes> zhf_lobes(int order, const std::string& tables) {
  if (!tables.empty())
    return once_per_key<ZhfLobes>(file_key(order, tables), [&] { return lobes::zhf_lobes_for(order, tables); });
  return once_per_key<ZhfLobes>(std::to_string(order), [&] {
    for (int n = order; n <= kMaxOrder; ++n)
      if (const std::filesystem::path p = find_module_table("zhf-shared-N" + std::to_string(n) + ".shtb"); !p.empty())
        return lobes::zhf_lobes_for(order, p);
    int highest = 0;
    for (int n = order - 1; n >= 1 && !highest; --n)
      if (!find_module_table("zhf-shared-N" + std::to_string(n) + ".shtb").empty()) highest = n;
    const std::string make =
        " (made by `shtool search-lobes --shared --order " + std::to_string(order) + " --out FILE`)";
    if (highest)
      throw InputError("no shipped zhf-lobes table covers order " + std::to_string(order) +
                       " (the shipped ones cover orders 1 to " + std::to_string(highest) +
                       "): give one with tables=" + make);
    throw InputError("no zhf-lobes table found for order " + std::to_string(order) +
                     " in $SHTOOL_TABLES, the package's tables folder or the install prefix: set SHTOOL_TABLES to "
                     "shtool's tables folder, or give one with tables=" +
                     make);
  });
}

// Zonal-harmonic factorisation with the shipped shared lobes, as `shtool rotate --method
// zhf | zhf-tailored`: one matrix for every vector.
template <class T>
void rotate_zhf(bool tailored, int order, const std::shared_ptr<const ZhfLobes>& lobes, const Mat3<T>& r, const T* in,
                T* out, std::size_t count, int threads) {
  const std::size_t n2 = sh_count(order);
  for_chunks(count, threads, [&](std::size_t begin, std::size_t end) {
    if (tailored) {
      for (std::size_t k = begin; k < end; ++k) {
        ZhfTailoredSignal<T> signal(lobes, std::span<const T>(in + k * n2, n2));
        signal.set(r);
        signal.apply(std::span<T>(out + k * n2, n2));
      }
      return;
    }
    ZhfRotation<T> rotation(order, lobes);  // scratch inside: one per chunk
    rotation.set(r);
    for (std::size_t k = begin; k < end; ++k)
      rotation.apply(std::span<const T>(in + k * n2, n2), std::span<T>(out + k * n2, n2));
  });
}

RotationMethod method_from(const std::string& name) {
  const std::optional<RotationMethod> m = rotation_method_from_name(name);
  if (!m)
    throw py::value_error("method: unknown rotation method '" + name +
                          "' (auto, reference, zxzxz, taylor1, taylor1.5, taylor2, zhf, zhf-tailored)");
  return *m;
}

// Rotations refuse overflow per vector (refuse_overflow), given the vectors they rotated.
template <class T>
void refuse_rotation_overflow(const T* in, const T* out, std::size_t count, std::size_t n2) {
  refuse_overflow("rotate: the rotation", out, count, n2, [&](std::size_t k) { return all_finite(in + k * n2, n2); });
}

template <class T>
py::array rotate_t(const py::array& coeffs_in, const py::object& matrix, const std::string& method_name,
                   std::optional<double> tol, const py::object& out_arg, int threads, const std::string& tables) {
  const auto coeffs = contiguous<T>(coeffs_in);
  if (coeffs.ndim() < 1) throw py::value_error("coeffs must have at least one axis");
  const int order = order_of_count(coeffs.shape(coeffs.ndim() - 1), "coeffs");
  // Checked for every method, those that do not use it included.
  if (tol && (!(*tol > 0) || !std::isfinite(*tol))) throw py::value_error("tol must be a positive number");
  if (method_name == "zhf" || method_name == "zhf-tailored") {
    auto out = output<T>(shape_of(coeffs), out_arg);
    if (overlaps(out, coeffs)) throw py::value_error("out must not overlap coeffs");
    const auto m = as_f64(matrix, "matrix");
    if (m.ndim() != 2) throw py::value_error("the zhf methods take one matrix (3, 3)");
    const Mat3<T> r = rotation_from(m).template cast<T>();
    const T* in = coeffs.data();
    T* o = out.mutable_data();
    py::gil_scoped_release release;
    const auto lobes = zhf_lobes(order, tables);
    rotate_zhf<T>(method_name == "zhf-tailored", order, lobes, r, in, o, coeffs.size() / sh_count(order), threads);
    refuse_rotation_overflow(in, static_cast<const T*>(o), coeffs.size() / sh_count(order), sh_count(order));
    return out;
  }
  const RotationMethod method = method_from(method_name);
  const double tolerance = tol ? *tol : default_rotation_tolerance<T>();
  auto out = output<T>(shape_of(coeffs), out_arg);
  if (overlaps(out, coeffs)) throw py::value_error("out must not overlap coeffs");
  const std::size_t n2 = sh_count(order), count = coeffs.size() / n2;
  std::shared_ptr<const RotationHelpers> helpers;
  if (method != RotationMethod::reference) {
    py::gil_scoped_release release;  // reading the table, or computing the helpers
    helpers = helpers_for(order, tables);
  }

  // One matrix for every vector, or one per leading index of coeffs (shape (..., 3, 3)
  // with the leading axes of coeffs' first axes).
  // float32 matrices are read as they are (a float64 copy of a million would cost more
  // than rotating with them); anything else as float64.
  const bool f32 = py::isinstance<py::array>(matrix) &&
                   py::reinterpret_borrow<py::array>(matrix).dtype().equal(py::dtype::of<float>());
  const py::array m = f32 ? py::array(contiguous<float>(matrix)) : py::array(as_f64(matrix, "matrix"));
  if (m.ndim() == 2) {
    ShRotation<T> rotation(order, helpers);
    if (!rotation.set(rotation_from(m).template cast<T>(), method, tolerance))
      throw py::value_error("rotation method unavailable for this order");
    const T* in = coeffs.data();
    T* o = out.mutable_data();
    py::gil_scoped_release release;
    for_chunks(count, threads, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k)
        rotation.apply(std::span<const T>(in + k * n2, n2), std::span<T>(o + k * n2, n2));
    });
    refuse_rotation_overflow(in, static_cast<const T*>(o), count, n2);
    return out;
  }
  if (m.ndim() < 2 || m.shape(m.ndim() - 1) != 3 || m.shape(m.ndim() - 2) != 3 || m.ndim() - 2 > coeffs.ndim() - 1 ||
      !std::equal(m.shape(), m.shape() + m.ndim() - 2, coeffs.shape()))
    throw py::value_error("matrix must have shape (3, 3) or (..., 3, 3) with the leading axes of coeffs");
  if (count == 0) return out;
  const std::size_t matrices = m.size() / 9, per_matrix = count / matrices;
  if (per_matrix > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw py::value_error("more than 2^31 - 1 vectors per matrix: pass one matrix (3, 3) instead");
  const float* rm32 = f32 ? static_cast<const float*>(m.data()) : nullptr;
  const double* rm64 = f32 ? nullptr : static_cast<const double*>(m.data());
  const T* in = coeffs.data();
  T* o = out.mutable_data();
  bool ok = true;
  {
    py::gil_scoped_release release;
    // In chunks of matrices; each matrix turns its per_matrix consecutive vectors (a
    // splat's colour channels), and rotate_batch makes its setup once for them.
    std::vector<char> chunk_ok((matrices + kChunk - 1) / kChunk, 1);
    for_chunks(matrices, threads, [&](std::size_t begin, std::size_t end) {
      // The chunk's matrices, checked, in a buffer kept by the thread: a new one per chunk
      // would be mapped and zeroed by the kernel every time (it is above malloc's mmap
      // threshold).
      thread_local std::vector<Mat3<T>> r;
      r.resize(end - begin);
      for (std::size_t k = begin; k < end; ++k) {
        Mat3<T>& rk = r[k - begin];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) rk(i, j) = static_cast<T>(f32 ? rm32[9 * k + 3 * i + j] : rm64[9 * k + 3 * i + j]);
        // The message (a string per matrix) only for a matrix that fails, from the values given.
        if (!is_rotation_matrix<T>(rk)) {
          Mat3<double> given;
          for (int i = 0; i < 9; ++i) given(i / 3, i % 3) = f32 ? rm32[9 * k + i] : rm64[9 * k + i];
          checked_rotation_matrix(given, "matrix[" + std::to_string(k) + "]");
          throw InputError("matrix[" + std::to_string(k) + "] is not a rotation in " +
                           (sizeof(T) == 4 ? "float32" : "float64"));
        }
      }
      // One rotation object per thread and (order, helpers), kept across chunks and calls:
      // making one costs as much as rotating a few hundred vectors.
      thread_local std::unique_ptr<ShRotation<T>> rotation;
      thread_local std::pair<int, const RotationHelpers*> made_for{0, nullptr};
      if (!rotation || made_for != std::make_pair(order, helpers.get())) {
        rotation = std::make_unique<ShRotation<T>>(order, helpers);
        made_for = {order, helpers.get()};
      }
      const std::size_t first = begin * per_matrix * n2, size = (end - begin) * per_matrix * n2;
      chunk_ok[begin / kChunk] =
          rotate_batch<T>(*rotation, r, std::span<const T>(in + first, size), std::span<T>(o + first, size), method,
                          tolerance, static_cast<int>(per_matrix));
    });
    ok = std::all_of(chunk_ok.begin(), chunk_ok.end(), [](char c) { return c != 0; });
  }
  if (!ok) throw py::value_error("rotation method unavailable for this order");
  refuse_rotation_overflow(in, static_cast<const T*>(o), count, n2);
  return out;
}

template <class T>
py::array quat_to_matrix_t(const py::array& q_in, int threads) {
  const auto q = contiguous<T>(q_in);
  if (q.ndim() < 1 || q.shape(q.ndim() - 1) != 4) throw py::value_error("q must have shape (..., 4): (w, x, y, z)");
  std::vector<py::ssize_t> shape = shape_of(q);
  shape.back() = 3;
  shape.push_back(3);
  py::array_t<T, py::array::c_style> out(shape);
  const T* s = q.data();
  T* o = out.mutable_data();
  const std::size_t count = static_cast<std::size_t>(q.size() / 4);
  auto quaternion = [&](std::size_t k) {
    return std::array<double, 4>{s[4 * k], s[4 * k + 1], s[4 * k + 2], s[4 * k + 3]};
  };
  std::size_t bad = count;  // the first quaternion that is not unit
  {
    py::gil_scoped_release release;
    std::vector<std::size_t> first_bad((count + kChunk - 1) / kChunk, count);
    for_chunks(count, threads, [&](std::size_t begin, std::size_t end) {
      const std::string what = "q";  // the message is made again, with the index, for the first bad one
      for (std::size_t k = begin; k < end; ++k) {
        Mat3<double> r;
        try {
          r = checked_quaternion_matrix(quaternion(k), what);
        } catch (const InputError&) {
          first_bad[begin / kChunk] = k;
          return;
        }
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) o[9 * k + 3 * i + j] = static_cast<T>(r(i, j));
      }
    });
    for (std::size_t b : first_bad) bad = std::min(bad, b);
  }
  if (bad < count) checked_quaternion_matrix(quaternion(bad), "q[" + std::to_string(bad) + "]");  // throws
  return out;
}

template <class T>
py::array product_t(const py::array& a_in, const py::array& b_in, std::optional<int> order_arg,
                    const std::string& method_name, int threads) {
  const auto a = contiguous<T>(a_in);
  const auto b = contiguous<T>(b_in);
  if (a.ndim() < 1 || b.ndim() < 1) throw py::value_error("a and b must have at least one axis");
  const int na = order_of_count(a.shape(a.ndim() - 1), "a"), nb = order_of_count(b.shape(b.ndim() - 1), "b");
  const int order = order_arg.value_or(na);
  const std::optional<ProductMethod> method = product_method_from_name(method_name);
  if (!method) throw py::value_error("method must be auto, tripling, fourier or grid, got '" + method_name + "'");
  // Inputs of lower order are padded with zeros and the product taken at the highest of
  // the three orders, then truncated: every band of the inputs reaches the result.
  const int work = std::max({order, na, nb});
  if (order < 1) throw py::value_error("order must be at least 1, got " + std::to_string(order));
  if (work > kMaxFourierProductOrder)
    throw py::value_error("order " + std::to_string(work) + " is not supported (1.." +
                          std::to_string(kMaxFourierProductOrder) + ")");
  if (*method == ProductMethod::tripling && work > kMaxTriplingOrder)
    throw py::value_error("method tripling supports orders up to " + std::to_string(kMaxTriplingOrder));
  const std::size_t ca = a.size() / sh_count(na), cb = b.size() / sh_count(nb);
  const bool same = std::equal(a.shape(), a.shape() + a.ndim() - 1, b.shape(), b.shape() + b.ndim() - 1);
  if (!same && a.ndim() > 1 && b.ndim() > 1)
    throw py::value_error("a and b must have the same leading axes (or one of them none)");
  const py::array& lead = a.ndim() >= b.ndim() ? static_cast<const py::array&>(a) : b;
  std::vector<py::ssize_t> shape(lead.shape(), lead.shape() + lead.ndim() - 1);
  shape.push_back(sh_count(order));
  auto out = py::array_t<T, py::array::c_style>(shape);
  const std::size_t count = out.size() / sh_count(order), w2 = sh_count(work), o2 = sh_count(order);
  const std::size_t a2 = sh_count(na), b2 = sh_count(nb);
  const T *pa = a.data(), *pb = b.data();
  T* po = out.mutable_data();
  py::gil_scoped_release release;
  for_chunks(count, threads, [&](std::size_t begin, std::size_t end) {
    ShProduct<T> product(work, *method);  // not thread-safe: one per chunk
    std::vector<T> fa(w2, T(0)), fb(w2, T(0)), g(w2);
    for (std::size_t k = begin; k < end; ++k) {
      const T* ra = pa + (ca == 1 ? 0 : k) * a2;
      const T* rb = pb + (cb == 1 ? 0 : k) * b2;
      std::copy(ra, ra + a2, fa.begin());
      std::copy(rb, rb + b2, fb.begin());
      product.triple(fa, fb, g);
      std::copy(g.begin(), g.begin() + o2, po + k * o2);
    }
  });
  refuse_overflow("product: the product", static_cast<const T*>(po), count, o2, [&](std::size_t k) {
    return all_finite(pa + (ca == 1 ? 0 : k) * a2, a2) && all_finite(pb + (cb == 1 ? 0 : k) * b2, b2);
  });
  return out;
}

}  // namespace

void bind_sh(py::module_& m) {
  m.def(
      "_eval_sh",
      [](int order, const py::array& dirs, const py::object& out, int threads) {
        check_order(order);
        check_threads(threads);
        return precision_of(dirs, "dirs") == Precision::f32 ? eval_sh_t<float>(order, dirs, out, threads)
                                                            : eval_sh_t<double>(order, dirs, out, threads);
      },
      py::arg("order"), py::arg("dirs").noconvert(), py::arg("out") = py::none(), py::arg("threads") = 0,
      "Real SH values (..., order**2) at dirs (..., 3), normalised inside; float32 or float64 as dirs.");
  m.def(
      "_rotate",
      [](const py::array& coeffs, const py::object& matrix, const std::string& method, std::optional<double> tol,
         const py::object& out, int threads, const std::string& tables) {
        check_threads(threads);
        return precision_of(coeffs, "coeffs") == Precision::f32
                   ? rotate_t<float>(coeffs, matrix, method, tol, out, threads, tables)
                   : rotate_t<double>(coeffs, matrix, method, tol, out, threads, tables);
      },
      py::arg("coeffs").noconvert(), py::arg("matrix"), py::arg("method"), py::arg("tol"), py::arg("out"),
      py::arg("threads"), py::arg("tables") = "");
  m.def(
      "_quat_to_matrix",
      [](const py::array& q, int threads) {
        check_threads(threads);
        return precision_of(q, "q") == Precision::f32 ? quat_to_matrix_t<float>(q, threads)
                                                      : quat_to_matrix_t<double>(q, threads);
      },
      py::arg("q").noconvert(), py::arg("threads") = 0);
  m.def(
      "_product",
      [](const py::array& a, const py::array& b, std::optional<int> order, const std::string& method, int threads) {
        const Precision p = precision_of(a, "a");
        if (precision_of(b, "b") != p) throw py::type_error("a and b must have the same dtype");
        check_threads(threads);
        return p == Precision::f32 ? product_t<float>(a, b, order, method, threads)
                                   : product_t<double>(a, b, order, method, threads);
      },
      py::arg("a").noconvert(), py::arg("b").noconvert(), py::arg("order"), py::arg("method"), py::arg("threads"));
}

}  // namespace shtool::python
