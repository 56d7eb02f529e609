#include "shtool/product.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "shtool/sh.h"
#include "precondition.h"

namespace shtool {

template <class T>
ShProduct<T>::ShProduct(int order, ProductMethod method, const TriplingTensor* tensor)
    : order_(order), fourier_(kMaxProductInputs + 1), grid_(kMaxProductInputs + 1) {
  if (order < 1 || order > kMaxFourierProductOrder)
    detail::precondition_failed("ShProduct: order " + std::to_string(order) + " outside 1.." +
                                std::to_string(kMaxFourierProductOrder));
  multiple_fourier_ = method == ProductMethod::fourier;
  if (method == ProductMethod::automatic)
    method = (order >= kGridTripleFromOrder || order > kMaxTriplingOrder) ? ProductMethod::grid
                                                                          : ProductMethod::tripling;
  triple_method_ = method;
  if (method == ProductMethod::tripling && order > kMaxTriplingOrder)
    detail::precondition_failed("ShProduct: the tripling tensor is limited to order " +
                                std::to_string(kMaxTriplingOrder));
  if (tensor) {
    if (tensor->order < order)
      detail::precondition_failed("ShProduct: tripling tensor of order " +
                                  std::to_string(tensor->order) + " for products of order " +
                                  std::to_string(order));
    if (tensor->order == order) {
      tripling_ = std::make_unique<TriplingProduct<T>>(*tensor);
    } else {  // keep the entries inside the smaller order
      TriplingTensor cut;
      cut.order = order;
      const std::uint32_t count = static_cast<std::uint32_t>(sh_count(order));
      for (std::size_t e = 0; e < tensor->size(); ++e)
        if (tensor->index[3 * e + 2] < count) {
          cut.index.insert(cut.index.end(), tensor->index.begin() + 3 * e,
                           tensor->index.begin() + 3 * e + 3);
          cut.value.push_back(tensor->value[e]);
        }
      tripling_ = std::make_unique<TriplingProduct<T>>(cut);
    }
  }
  scratch_a_.assign(sh_count(order), T(0));
  scratch_b_.assign(sh_count(order), T(0));
  // The generated kernels' orders: build the (small) tensor now so triple() can call the
  // kernel directly.
  if (triple_method_ == ProductMethod::tripling && order <= kUnrolledTriplingOrder)
    triple_kernel_ = tripling().kernel();
}

template <class T>
ShProduct<T>::~ShProduct() = default;

template <class T>
const TriplingProduct<T>& ShProduct<T>::tripling() {
  if (!tripling_) tripling_ = std::make_unique<TriplingProduct<T>>(TriplingTensor::compute(order_));
  return *tripling_;
}

namespace {

// The product of `inputs` inputs from its slot, built on first use.
template <class P>
P& product_for(std::vector<std::unique_ptr<P>>& slots, int order, int inputs) {
  if (inputs < 1 || inputs > kMaxProductInputs)
    detail::precondition_failed("ShProduct: " + std::to_string(inputs) + " inputs (1.." +
                                std::to_string(kMaxProductInputs) + ")");
  if (!slots[inputs]) slots[inputs] = std::make_unique<P>(order, inputs);
  return *slots[inputs];
}

}  // namespace

template <class T>
FourierProduct<T>& ShProduct<T>::fourier(int inputs) {
  return product_for(fourier_, order_, inputs);
}

template <class T>
GridProduct<T>& ShProduct<T>::grid(int inputs) {
  return product_for(grid_, order_, inputs);
}

template <class T>
void ShProduct<T>::prepare(int inputs) {
  if (inputs == 2 && triple_method_ == ProductMethod::tripling)
    tripling();
  else if (inputs == 2 && triple_method_ == ProductMethod::grid)
    grid(2);
  else if (inputs == 2 || multiple_fourier_)
    fourier(inputs);
  else
    grid(inputs);
}

template <class T>
void ShProduct<T>::triple_general(std::span<const T> f1, std::span<const T> f2, std::span<T> g) {
  if (triple_method_ == ProductMethod::tripling) {
    // The tensor loop reads the inputs while writing g, so an aliased output goes
    // through scratch.
    const bool alias = g.data() == f1.data() || g.data() == f2.data();
    T* out = alias ? scratch_a_.data() : g.data();
    tripling().multiply(f1, f2, std::span<T>(out, sh_count(order_)));
    if (alias) std::copy(scratch_a_.begin(), scratch_a_.end(), g.begin());
  } else if (triple_method_ == ProductMethod::grid) {
    grid(2).multiply(f1, f2, g);
  } else {
    fourier(2).multiply(f1, f2, g);
  }
}

template <class T>
T ShProduct<T>::triple_integral(std::span<const T> f1, std::span<const T> f2,
                                std::span<const T> f3) {
  if (triple_method_ == ProductMethod::tripling) return tripling().integral(f1, f2, f3);
  if (triple_method_ == ProductMethod::grid) {
    const std::span<const T> f[3] = {f1, f2, f3};
    return grid(2).integral(std::span<const std::span<const T>>(f, 3));
  }
  fourier(2).multiply(f1, f2, scratch_a_);
  T sum = 0;
  for (int i = 0; i < sh_count(order_); ++i) sum += scratch_a_[i] * f3[i];
  return sum;
}

template <class T>
void ShProduct<T>::multiple(std::span<const std::span<const T>> f, std::span<T> g) {
  const int inputs = static_cast<int>(f.size());
  if (inputs == 2) {
    triple(f[0], f[1], g);
    return;
  }
  if (multiple_fourier_)
    fourier(inputs).multiply(f, g);
  else
    grid(inputs).multiply(f, g);
}

template <class T>
void ShProduct<T>::recursive(std::span<const std::span<const T>> f, std::span<T> g) {
  const int inputs = static_cast<int>(f.size());
  if (inputs < 1 || inputs > kMaxProductInputs)
    detail::precondition_failed("ShProduct: " + std::to_string(inputs) + " inputs (1.." +
                                std::to_string(kMaxProductInputs) + ")");
  if (inputs == 1) {
    std::copy(f[0].begin(), f[0].begin() + sh_count(order_), g.begin());
    return;
  }
  // Eq. 11, alternating between two scratch vectors; truncation to order N after each
  // triple product is what makes it an approximation.
  std::span<T> a(scratch_a_), b(scratch_b_);
  triple(f[0], f[1], a);
  for (int i = 2; i < inputs; ++i) {
    triple(a, f[i], b);
    std::swap(a, b);
  }
  std::copy(a.begin(), a.end(), g.begin());
}

template class ShProduct<float>;
template class ShProduct<double>;

int tripling_order_needed(int order, int inputs) {
  // The order of each step is the larger of the bands kept before and after it; the
  // largest over all steps is the peak of the kept orders.
  int needed = order;
  for (int j = 2; j <= inputs; ++j)
    needed = std::max(needed, std::min(j * (order - 1) + 1, order + (inputs - j) * (order - 1)));
  return needed;
}

template <class T>
int tripling_multiple_product(int order, std::span<const std::span<const T>> f, std::span<T> g) {
  const int k = static_cast<int>(f.size());
  const int needed = tripling_order_needed(order, k);
  if (needed > kMaxTriplingOrder || k < 1) return needed;
  const int n = sh_count(order);
  std::vector<T> running(f[0].begin(), f[0].begin() + n);
  int running_order = order;
  for (int j = 2; j <= k; ++j) {
    // Bands kept after this step, and the order the step runs at: every band of the
    // running product still matters (its high bands times the new input reach down).
    const int keep = std::min(j * (order - 1) + 1, order + (k - j) * (order - 1));
    const int m = std::max(keep, running_order);
    std::vector<T> a(sh_count(m), T(0)), b(sh_count(m), T(0)), c(sh_count(m));
    std::copy(running.begin(), running.end(), a.begin());
    std::copy_n(f[j - 1].begin(), n, b.begin());
    ShProduct<T>(m, ProductMethod::tripling).triple(a, b, c);
    c.resize(sh_count(keep));
    running = std::move(c);
    running_order = keep;
  }
  std::copy_n(running.begin(), n, g.begin());
  return needed;
}

template int tripling_multiple_product<float>(int, std::span<const std::span<const float>>, std::span<float>);
template int tripling_multiple_product<double>(int, std::span<const std::span<const double>>,
                                               std::span<double>);

}  // namespace shtool
