// gen-shader as a library job: checks a request, generates the GLSL or HLSL include and
// writes it in full or not at all.
#pragma once

#include <filesystem>
#include <string>

#include "shaders/shader_source.h"

namespace shtool {

struct GenShaderRequest {
  ShaderRequest shader;        // shader.command is filled in by the job
  std::filesystem::path out;   // the include file to write
  // zhf-rotate: a zhf-lobes table (search-lobes --shared); empty: the shipped one for the order.
  std::filesystem::path lobes_table;
};

// The canonical command line of a request (options in a fixed order, the output by its
// file name only), recorded in the file so that equal requests give equal bytes.
std::string gen_shader_command(const GenShaderRequest& request);

// Throws InputError naming the option when the order is outside the operation's range,
// --zh-lobes is outside 1..16, the lobe table is unreadable, invalid or short of the
// order, or --out is empty or a folder. Returns what was written.
ShaderSource run_gen_shader(const GenShaderRequest& request);

}  // namespace shtool
