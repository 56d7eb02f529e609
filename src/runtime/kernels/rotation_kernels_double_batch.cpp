// The generated rotation kernels (rotation_kernels_generated.inc): the batch kernels for
// double. The kernels are the longest compile of the build; each precision's three kinds
// (batch, one vector, RGB) are instantiated in translation units of their own, so that
// the cores share them.
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template BatchKernel<double> batch_kernel<double>(int, int, bool);
template BatchKernel<double> batch_band_kernel<double>(int, int, bool);

}  // namespace shtool::detail
