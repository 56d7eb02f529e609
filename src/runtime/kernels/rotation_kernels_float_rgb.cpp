// The generated rotation kernels (rotation_kernels_generated.inc) for float, three
// channels (RGB) interleaved (split as rotation_kernels_float_batch.cpp says).
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template RotationKernel<float, 3> rotation_kernel<float, 3>(int, int, bool);
template RotationKernel<float, 3> band_kernel<float, 3>(int, int, bool);

}  // namespace shtool::detail
