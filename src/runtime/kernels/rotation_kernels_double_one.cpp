// The generated rotation kernels (rotation_kernels_generated.inc) for double, one vector
// at a time (split as rotation_kernels_double_batch.cpp says).
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template RotationKernel<double, 1> rotation_kernel<double, 1>(int, int, bool);
template RotationKernel<double, 1> band_kernel<double, 1>(int, int, bool);

}  // namespace shtool::detail
