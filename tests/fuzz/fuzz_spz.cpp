// The spz reader of transform-splats on arbitrary bytes: a file it accepts decodes to
// finite values, and the writer encodes them again (versions 3 and 4; v4 may refuse a
// scene too compressible for readers' point-count bound) into files the
// reader accepts with the same splat count and SH degree, and the same SH bytes' values
// (an SH value decoded from a byte is a bucket centre at 8 bits); everything else is
// InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "common/input_error.h"
#include "interop/spz.h"

using shtool::interop::SplatScene;
using shtool::interop::SpzWriteOptions;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::optional<SplatScene> scene;
  try {
    scene.emplace(shtool::interop::read_spz(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.spz"));
  } catch (const shtool::InputError&) {
    return 0;
  }
  const SplatScene& s = *scene;
  for (const auto* v : {&s.position, &s.log_scale, &s.rotation, &s.opacity, &s.sh})
    for (float x : *v)
      if (!std::isfinite(x)) __builtin_trap();
  for (int version : {3, 4}) {
    SpzWriteOptions o;
    o.version = version;
    o.sh1_bits = o.sh_rest_bits = 8;
    std::string bytes;
    try {
      bytes = shtool::interop::write_spz(s, o);
    } catch (const shtool::InputError&) {
      // Every decoded scene can be written, as v3 always; as v4 unless it compresses past
      // what readers accept (file size x 1024 / 9 splats: a great many identical ones),
      // which no file of at most 12743 splats can (its header and table alone, 112 bytes,
      // allow that many).
      if (version == 4 && s.count > 112 * 1024 / 9) continue;
      __builtin_trap();
    }
    SplatScene again;
    try {
      again = shtool::interop::read_spz(bytes, "fuzz-again.spz");
    } catch (const shtool::InputError&) {
      __builtin_trap();  // the reader refusing what the writer wrote
    }
    if (again.count != s.count || again.degree != s.degree) __builtin_trap();
    const std::size_t stride = s.sh_stride();
    for (std::size_t i = 0; i < s.count; ++i)
      for (std::size_t k = 3; k < stride; ++k)
        if (again.sh[i * stride + k] != s.sh[i * stride + k]) __builtin_trap();
  }
  return 0;
}
