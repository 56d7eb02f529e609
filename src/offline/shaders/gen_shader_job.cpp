#include "shaders/gen_shader_job.h"

#include <system_error>

#include "common/atomic_file.h"
#include "common/input_error.h"

namespace shtool {

std::string gen_shader_command(const GenShaderRequest& r) {
  const ShaderRequest& s = r.shader;
  std::string c = "shtool gen-shader --lang ";
  c += s.language == ShaderLanguage::glsl ? "glsl" : "hlsl";
  c += " --what " + std::string(shader_operation_name(s.operation)) + " --order " + std::to_string(s.order);
  if (s.operation == ShaderOperation::zh_shade) c += " --zh-lobes " + std::to_string(s.zh_lobes);
  c += " --precision ";
  c += s.precision == ShaderPrecision::half ? "half" : "float";
  c += " --out " + r.out.filename().string();
  return c;
}

ShaderSource run_gen_shader(const GenShaderRequest& r) {
  const ShaderOperation op = r.shader.operation;
  const std::string what(shader_operation_name(op));
  if (r.shader.order < shader_min_order(op) || r.shader.order > shader_max_order(op))
    throw InputError("--order " + std::to_string(r.shader.order) + " is not supported for --what " + what + " (" +
                     std::to_string(shader_min_order(op)) + ".." + std::to_string(shader_max_order(op)) + ")");
  if (r.shader.zh_lobes < 1 || r.shader.zh_lobes > 16)
    throw InputError("--zh-lobes must be between 1 and 16, got " + std::to_string(r.shader.zh_lobes));
  if (r.out.empty()) throw InputError("--out: an output file is required");
  std::error_code ec;
  if (std::filesystem::is_directory(r.out, ec))
    throw InputError("--out " + r.out.string() + " is a folder, not a file");
  ShaderRequest request = r.shader;
  request.command = gen_shader_command(r);
  ShaderSource source = shader_source(request);
  write_file_atomically(r.out, source.text);
  return source;
}

}  // namespace shtool
