// gen-shader: GLSL and HLSL source of the runtime's SH operations, generated from the
// same closed forms and tables as the C++ kernels (docs/shaders.md).
//
// Every file is an include: no #version line, no main, no resource bindings. It defines
// SHTOOL_ORDER (a macro, usable as an array size) and one documented function per
// operation, with constants rounded once from long double to the shader's float and
// written with 9 significant digits (which read back to the same float), exact zeros
// and unit factors left out.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "shtool/zhf_rotation.h"

namespace shtool {

enum class ShaderLanguage { glsl, hlsl };
// float: 32-bit throughout. half: locals and arguments declared relaxed (GLSL `mediump
// float`, RelaxedPrecision in SPIR-V; HLSL `min16float`), which a GPU may evaluate in 16
// bits; the constants are the same.
enum class ShaderPrecision { float32, half };
enum class ShaderOperation {
  sh_eval,
  sh_irradiance,
  zxzxz_rotate,
  zhf_rotate,
  zhf_tailored_rotate,
  triple_product,
  zh_shade,
  l1_irradiance,   // Geomerics' non-linear L1 of a probe's 4 RGB coefficients
  zh3_irradiance   // ZH3: 4 RGB coefficients and a zonal coefficient per channel
};

struct ShaderRequest {
  ShaderLanguage language = ShaderLanguage::glsl;
  ShaderOperation operation = ShaderOperation::sh_eval;
  int order = 3;                                    // SH order N (bands 0..N-1)
  ShaderPrecision precision = ShaderPrecision::float32;
  int zh_lobes = 4;                                 // zh-shade: lobes per point
  std::string command{};                            // recorded in the provenance header
  // zhf-rotate, zhf-tailored-rotate: the lobe table (covering the order) and the CRC-32 of its file.
  std::shared_ptr<const ZhfLobes> lobes{};
  std::uint32_t lobes_crc = 0;
};

struct ShaderSource {
  std::string text;
  std::string signature;  // the function(s) the file defines, one per line
  // Arithmetic of the generated function bodies as written (binary * and +/-, before
  // the compiler's own folding; loops counted per iteration they run).
  long multiplications = 0;
  long additions = 0;
  long texture_fetches = 0;  // zhf-tailored-rotate's texture form
};

// Largest order each operation is generated for (sh-eval, sh-irradiance, zh-shade,
// zhf-rotate, zhf-tailored-rotate, l1-irradiance, zh3-irradiance 10; zxzxz-rotate 8;
// triple-product 6). Orders start at 1 (triple-product, the rotations and the probe
// encodings 2). The probe encodings' functions read 4 RGB coefficients (and 3 zonal ones)
// whatever the order, which only sets SHTOOL_ORDER so that the file is included beside the
// other operations' files of that order.
int shader_min_order(ShaderOperation operation);
int shader_max_order(ShaderOperation operation);

// Names used on the command line ("sh-eval", ...), in the order of ShaderOperation.
std::string_view shader_operation_name(ShaderOperation operation);
const std::vector<ShaderOperation>& shader_operations();

// The complete file. Precondition: the order is inside the operation's range and
// zh_lobes is 1..16 (the job checks both and names the option).
ShaderSource shader_source(const ShaderRequest& request);

}  // namespace shtool
