// What the two FFT-based products, FourierProduct and GridProduct, share: the check of
// their sizes, and the inner loop of their projection of a half spectrum back onto SH.
#pragma once

#include <string>

#include "precondition.h"
#include "shtool/fourier_product.h"  // kMaxFourierProductOrder, kMaxProductInputs

namespace shtool::detail {

// The constructors' preconditions; `product` names the class in the message.
inline void check_product_sizes(const char* product, int order, int inputs) {
  if (order < 1 || order > kMaxFourierProductOrder)
    precondition_failed(std::string(product) + ": order " + std::to_string(order) + " outside 1.." +
                        std::to_string(kMaxFourierProductOrder));
  if (inputs < 1 || inputs > kMaxProductInputs)
    precondition_failed(std::string(product) + ": " + std::to_string(inputs) + " inputs (1.." +
                        std::to_string(kMaxProductInputs) + ")");
}

// One complex Fourier coefficient scaled by a real row of projection weights, added into
// split accumulators: acc_re[j] += w[j] re, acc_im[j] += w[j] im for j < count.
template <class T>
inline void accumulate_scaled_complex(const T* w, int count, T re, T im, T* acc_re, T* acc_im) {
  for (int j = 0; j < count; ++j) {
    acc_re[j] += w[j] * re;
    acc_im[j] += w[j] * im;
  }
}

}  // namespace shtool::detail
