// The generated rotation kernels (rotation_kernels_generated.inc) for float. Each precision
// is its own translation unit: the kernels are one of the longest compiles of the build,
// and split in two they compile on two cores.
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template BatchKernel<float> batch_kernel<float>(int, int, bool);
template BatchKernel<float> batch_band_kernel<float>(int, int, bool);
template RotationKernel<float, 1> rotation_kernel<float, 1>(int, int, bool);
template RotationKernel<float, 1> band_kernel<float, 1>(int, int, bool);
template RotationKernel<float, 3> rotation_kernel<float, 3>(int, int, bool);
template RotationKernel<float, 3> band_kernel<float, 3>(int, int, bool);

}  // namespace shtool::detail
