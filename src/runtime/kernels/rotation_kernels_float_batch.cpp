// The generated rotation kernels (rotation_kernels_generated.inc): the batch kernels for
// float. The kernels are the longest compile of the build; each precision's three kinds
// (batch, one vector, RGB) are instantiated in translation units of their own, so that
// the cores share them.
#include "rotation_kernels_generated.inc"

namespace shtool::detail {

template BatchKernel<float> batch_kernel<float>(int, int, bool);
template BatchKernel<float> batch_band_kernel<float>(int, int, bool);

}  // namespace shtool::detail
