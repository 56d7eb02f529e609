// gen-tensors: the source of the runtime's straight-line tripling kernels
// (src/runtime/tripling_kernels_generated.cpp, declared in src/runtime/tripling_kernels.h).
#pragma once

#include <string>

namespace shtool {

// File name the kernels are written to, and the complete C++ source: for orders
// 2..detail::kTriplingKernelMaxOrder, the triple product g = f1 (x) f2 as straight-line
// code over the canonical entries of the exact tripling tensor (compute_tripling_tensor_exact),
// in outer-product form (the pair products as vectors, tripling_kernels_gen.cpp), the values as
// literals, plus the list of entries each kernel was built from. The text depends on
// nothing else, so it is byte-identical on every run.
inline constexpr const char* kTriplingKernelsFile = "tripling_kernels_generated.cpp";
std::string tripling_kernels_source();

}  // namespace shtool
