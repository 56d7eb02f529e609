// Runs a test body with each copy of the rotation kernels this CPU can run: the baseline
// copy always, the FMA copy where the CPU has AVX2 and FMA (shtool/rotation.h,
// detail::use_fma_kernels). ShRotation objects pick their copy when constructed, so the
// body must construct its own.
#pragma once

#include <gtest/gtest.h>

#include "shtool/rotation.h"

namespace shtool::test {

template <class F>
void for_each_kernel_copy(F&& body) {
  for (bool fused : {false, true}) {
    shtool::detail::use_fma_kernels(fused);
    if (fused && !shtool::detail::fma_kernels_enabled()) continue;
    SCOPED_TRACE(fused ? "FMA kernels" : "baseline kernels");
    body();
  }
  shtool::detail::use_fma_kernels(true);
}

}  // namespace shtool::test
