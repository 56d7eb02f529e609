#include "shaders/gen_shader_job.h"

#include <memory>
#include <span>
#include <system_error>

#include "common/job_outputs.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "shtool/table.h"

namespace shtool {

std::string gen_shader_command(const GenShaderRequest& r) {
  const ShaderRequest& s = r.shader;
  std::string c = "shtool gen-shader --lang ";
  c += s.language == ShaderLanguage::glsl ? "glsl" : "hlsl";
  c += " --what " + std::string(shader_operation_name(s.operation)) + " --order " + std::to_string(s.order);
  if (s.operation == ShaderOperation::zh_shade) c += " --zh-lobes " + std::to_string(s.zh_lobes);
  if ((s.operation == ShaderOperation::zhf_rotate || s.operation == ShaderOperation::zhf_tailored_rotate) &&
      !r.lobes_table.empty())
    c += " --lobes " + r.lobes_table.filename().string();
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
  JobOutputs io;
  ShaderRequest request = r.shader;
  request.command = gen_shader_command(r);
  if (op == ShaderOperation::zhf_rotate || op == ShaderOperation::zhf_tailored_rotate) {
    const std::filesystem::path path = r.lobes_table.empty() ? default_zhf_lobes_path(request.order) : r.lobes_table;
    if (path.empty())
      throw InputError("--lobes: no shipped zhf-lobes table covers order " + std::to_string(request.order) +
                       " (set SHTOOL_TABLES or give --lobes TABLE)");
    io.input(path, "the --lobes table");
    const std::string bytes = read_input_file(path, "--lobes");
    const Result<Table> table =
        read_table_bytes(std::as_bytes(std::span(bytes.data(), bytes.size())), path.string());
    if (!table) throw InputError("--lobes: " + table.error().message);
    Result<ZhfLobes> lobes = ZhfLobes::from_table(table.value());
    if (lobes) lobes = lobes.value().bands_below(request.order);
    if (!lobes) throw InputError("--lobes: " + lobes.error().message);
    request.lobes = std::make_shared<const ZhfLobes>(std::move(lobes).value());
    request.lobes_crc = input_crc32(bytes);
  }
  io.output(r.out, "--out");
  ShaderSource source = shader_source(request);
  io.set("--out", source.text);
  io.commit();
  return source;
}

}  // namespace shtool
