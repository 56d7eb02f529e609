// The image decoders (OpenEXR, Radiance HDR, PNG, JPEG) on arbitrary bytes under each
// extension, then the projection of what they return: an image is either refused with
// InputError or has its declared size, and projects without a crash (a non-finite
// texel is an error, never NaN coefficients).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "common/input_error.h"
#include "lighting/image_io.h"
#include "shtool/env_projection.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  for (const char* name : {"fuzz.exr", "fuzz.hdr", "fuzz.png", "fuzz.jpg", "fuzz.bin"}) {
    try {
      // 2^20 texels: the tool's own bound (2^28, 3 GiB of floats) is beyond the fuzzer's
      // memory limit, and what is checked before allocating is the same either way.
      const shtool::lighting::Image img = shtool::lighting::decode_image(bytes, name, std::int64_t(1) << 20);
      if (img.width < 1 || img.height < 1 || img.channels != 3 ||
          img.texels.size() != static_cast<std::size_t>(img.width) * img.height * 3)
        __builtin_trap();
      if (img.width == 2 * img.height && img.height <= 256) {
        const shtool::Result<shtool::EnvCoefficients> c = shtool::project_equirect(img.view(), 3);
        if (c)
          for (double v : c.value().coefficients)
            if (!std::isfinite(v)) __builtin_trap();
      }
    } catch (const shtool::InputError&) {
    }
  }
  return 0;
}
