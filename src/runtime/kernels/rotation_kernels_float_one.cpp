// The generated rotation kernels (rotation_kernels_generated.inc) for float, one vector
// at a time (split as rotation_kernels_float_batch.cpp says).
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template RotationKernel<float, 1> rotation_kernel<float, 1>(int, int, bool);
template RotationKernel<float, 1> band_kernel<float, 1>(int, int, bool);

}  // namespace shtool::detail
