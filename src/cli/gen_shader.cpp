// shtool gen-shader: writes one GLSL or HLSL include with an SH operation (docs/shaders.md).
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "shaders/gen_shader_job.h"

namespace shtool::cli {

void setup_gen_shader(CLI::App* sub) {
  auto req = std::make_shared<GenShaderRequest>();
  auto lobes_given = std::make_shared<bool>(false);
  add_enum_option(sub, "--lang", req->shader.language,
                  {{"glsl", ShaderLanguage::glsl}, {"hlsl", ShaderLanguage::hlsl}}, "shader language", "")
      ->required();
  EnumNames<ShaderOperation> names;
  for (ShaderOperation op : shader_operations()) names.emplace_back(std::string(shader_operation_name(op)), op);
  add_enum_option(sub, "--what", req->shader.operation, names,
                  "operation: sh-eval, sh-irradiance, zxzxz-rotate, zhf-rotate, zhf-tailored-rotate, triple-product, "
                  "zh-shade, l1-irradiance, zh3-irradiance",
                  "")
      ->required();
  sub->add_option("--order", req->shader.order, "SH order N (bands 0..N-1)")->required();
  add_enum_option(sub, "--precision", req->shader.precision,
                  {{"float", ShaderPrecision::float32}, {"half", ShaderPrecision::half}},
                  "float, or half (relaxed: GLSL mediump, HLSL min16float)", "float");
  sub->add_option_function<int>(
      "--zh-lobes",
      [req, lobes_given](int k) {
        req->shader.zh_lobes = k;
        *lobes_given = true;
      },
      "zh-shade: ZH lobes per point (default 4)");
  sub->add_option("--lobes", req->lobes_table,
                  "zhf-rotate, zhf-tailored-rotate: zhf-lobes table of shared lobes (default: the shipped one for "
                  "the order)");
  sub->add_option("--out", req->out, "output include file")->required();
  sub->callback([req, lobes_given]() {
    if (*lobes_given && req->shader.operation != ShaderOperation::zh_shade)
      throw InputError("--zh-lobes applies to --what zh-shade only");
    if (!req->lobes_table.empty() && req->shader.operation != ShaderOperation::zhf_rotate &&
        req->shader.operation != ShaderOperation::zhf_tailored_rotate)
      throw InputError("--lobes applies to --what zhf-rotate and zhf-tailored-rotate only");
    const ShaderSource s = run_gen_shader(*req);
    std::cerr << "gen-shader: wrote " << req->out.string() << " (" << s.multiplications << " multiplications, "
              << s.additions << " additions";
    if (s.texture_fetches) std::cerr << ", " << s.texture_fetches << " texture fetches";
    std::cerr << ")\n";
  });
}

}  // namespace shtool::cli
