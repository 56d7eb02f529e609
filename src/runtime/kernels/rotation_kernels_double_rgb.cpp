// The generated rotation kernels (rotation_kernels_generated.inc) for double, three
// channels (RGB) interleaved (split as rotation_kernels_double_batch.cpp says).
// The FMA copies run the three lanes as four doubles, one AVX register (run_lanes' Avx);
// the baseline code they are inlined from is compiled without AVX, so GCC notes that
// such a vector would be passed differently: every function here is internal and
// inlined, so no ABI is involved (as in rotation_kernels.h).
#pragma GCC diagnostic ignored "-Wpsabi"
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template RotationKernel<double, 3> rotation_kernel<double, 3>(int, int, bool);
template RotationKernel<double, 3> band_kernel<double, 3>(int, int, bool);

}  // namespace shtool::detail
