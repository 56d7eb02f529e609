// The generated rotation kernels (rotation_kernels_generated.inc) for double, three
// channels (RGB) interleaved (split as rotation_kernels_double_batch.cpp says).
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template RotationKernel<double, 3> rotation_kernel<double, 3>(int, int, bool);
template RotationKernel<double, 3> band_kernel<double, 3>(int, int, bool);

}  // namespace shtool::detail
