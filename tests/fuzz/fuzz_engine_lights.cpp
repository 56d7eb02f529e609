// import-light's readers on arbitrary bytes, for every engine format in its default frame
// and both quantities: a light it returns has the stated order and finite coefficients;
// export-light of that light in the same format succeeds or refuses with InputError, and
// what it writes imports back to the same coefficients (bands 0..2, the ones every format
// holds). Anything but InputError escaping is a finding.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/input_error.h"
#include "interop/engine_light.h"
#include "shtool/sh.h"

namespace {

using shtool::interop::LightFormat;
using shtool::lighting::Lighting;
using shtool::lighting::Quantity;

void check_light(const Lighting& l) {
  if (l.order < 1 || l.order > 32) __builtin_trap();
  if (l.coefficients.size() != static_cast<std::size_t>(shtool::sh_count(l.order)) * 3) __builtin_trap();
  for (double c : l.coefficients)
    if (!std::isfinite(c)) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (const auto& [name, format] : shtool::interop::light_format_names()) {
    const shtool::interop::FrameMap frame = shtool::interop::default_frame(format);
    for (Quantity quantity : {Quantity::radiance, Quantity::irradiance}) {
      std::optional<Lighting> light;
      try {
        light = shtool::interop::import_light(text, "fuzz.light", format, frame, quantity);
      } catch (const shtool::InputError&) {
        continue;
      }
      check_light(*light);
      if (light->quantity != quantity) __builtin_trap();
      std::optional<shtool::interop::ExportedLight> file;
      try {
        file = shtool::interop::export_light(*light, format, frame, 1.0, shtool::interop::RawOptions{});
      } catch (const shtool::InputError&) {
        continue;
      }
      // What export-light wrote imports back: refusing it (InputError included) is a finding.
      std::optional<Lighting> back;
      try {
        back = shtool::interop::import_light(file->text, "fuzz-exported.light", format, frame, quantity);
      } catch (const shtool::InputError&) {
        __builtin_trap();
      }
      check_light(*back);
      // The raw format keeps every band; the engine formats hold bands 0..2.
      if (format == LightFormat::raw ? back->order != light->order : back->order != 3) __builtin_trap();
      // The same light within rounding: the conversions are a few multiplications by
      // constants and a signed permutation (band 2's frame change sums a few terms), each
      // exact to a few ulps, and the files hold 17 significant digits. 1e-12 of the
      // largest coefficient is far above that and far below any wrong constant or sign;
      // 1e-300 absolute allows for subnormals, which carry only a few bits.
      const std::size_t n = 3 * static_cast<std::size_t>(std::min(shtool::sh_count(light->order),
                                                                   format == LightFormat::raw ? 32 * 32 : 9));
      double largest = 0;
      for (std::size_t k = 0; k < n; ++k) largest = std::max(largest, std::abs(light->coefficients[k]));
      for (std::size_t k = 0; k < n; ++k)
        if (!(std::abs(light->coefficients[k] - back->coefficients[k]) <= 1e-12 * largest + 1e-300)) __builtin_trap();
      for (std::size_t k = n; k < back->coefficients.size(); ++k)
        if (back->coefficients[k] != 0) __builtin_trap();
    }
  }
  return 0;
}
