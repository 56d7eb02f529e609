// The generated rotation kernels (rotation_kernels_generated.inc) for double. Each precision
// is its own translation unit: the kernels are one of the longest compiles of the build,
// and split in two they compile on two cores.
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template BatchKernel<double> batch_kernel<double>(int, int, bool);
template BatchKernel<double> batch_band_kernel<double>(int, int, bool);
template RotationKernel<double, 1> rotation_kernel<double, 1>(int, int, bool);
template RotationKernel<double, 1> band_kernel<double, 1>(int, int, bool);
template RotationKernel<double, 3> rotation_kernel<double, 3>(int, int, bool);
template RotationKernel<double, 3> band_kernel<double, 3>(int, int, bool);

}  // namespace shtool::detail
