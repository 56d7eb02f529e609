// gen-tensors: the source of the fixed-order rotation kernels
// (src/runtime/kernels/rotation_kernels_generated.inc, see src/runtime/kernels/rotation_kernels.h).
#pragma once

#include <string>

namespace shtool {

// File name the kernels are written to, and the complete C++ source: straight-line
// zxzxz band kernels for bands 2..kBandKernelMaxBand (X90 as literals, exact zeros and
// unit entries skipped), Taylor band kernels for bands 1..kBandKernelMaxBand (D1 and D2
// entries as literals), one function per whole order up to kKernelMaxOrder and one per
// band above it, float and double, one vector and three (src/runtime/kernels/rotation_kernels.h). The constants come from compute_rotation_helpers; the text
// depends on nothing else, so it is byte-identical on every run.
inline constexpr const char* kRotationKernelsFile = "rotation_kernels_generated.inc";
std::string rotation_kernels_source();

}  // namespace shtool
