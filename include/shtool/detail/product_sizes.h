// Private to FourierProduct and GridProduct (shtool/fourier_product.h, grid_product.h):
// what the two product objects report of themselves. Not an interface.
#pragma once

#include <memory>

namespace shtool::detail {

// The (order, inputs) of a product and its grid, fixed at construction.
class ProductSizes {
 public:
  int order() const { return order_; }
  int inputs() const { return inputs_; }
  // Grid sizes (theta x phi), for docs and benchmarks.
  int grid_theta() const { return grid_theta_; }
  int grid_phi() const { return grid_phi_; }

 protected:
  void set_sizes(int order, int inputs, int grid_theta, int grid_phi) {
    order_ = order;
    inputs_ = inputs;
    grid_theta_ = grid_theta;
    grid_phi_ = grid_phi;
  }

 private:
  int order_ = 0, inputs_ = 0, grid_theta_ = 0, grid_phi_ = 0;
};

// A product's implementation: the deleter is made in the product's .cpp, where Impl is
// complete, so the product needs no out-of-line destructor or moves (it is move-only
// through this pointer alone).
template <class Impl>
using ImplPtr = std::unique_ptr<Impl, void (*)(Impl*)>;

template <class Impl>
void delete_impl(Impl* impl) {
  delete impl;
}

}  // namespace shtool::detail
