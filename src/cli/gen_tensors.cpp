// shtool gen-tensors: writes the precomputed tables the runtime needs.
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "tensors/gen_tensors_job.h"

namespace shtool::cli {

void setup_gen_tensors(CLI::App* sub) {
  auto req = std::make_shared<GenTensorsRequest>();
  auto what = std::make_shared<std::string>("rotation,tripling,fourier");
  sub->add_option("--order", req->order, "SH order N (bands 0..N-1)")->capture_default_str();
  sub->add_option("--out", req->out, "output folder")->capture_default_str();
  sub->add_option("--what", *what,
                  "comma-separated tables: rotation (zxzxz/Taylor helpers), tripling (tripling "
                  "tensor), fourier (SH<->Fourier tensors); rotation-kernels and tripling-kernels "
                  "write the C++ source of the runtime's fixed-order rotation and tripling kernels "
                  "(for src/runtime/kernels)")
      ->capture_default_str();
  sub->add_option("--inputs", req->inputs, "fourier: largest number of product inputs covered (2..8)")
      ->capture_default_str();
  add_table_format_option(sub, req->encoding, "binary (.shtb) or json (.json)");
  sub->callback([req, what]() {
    GenTensorsRequest r = *req;
    r.what = split_list(*what);
    for (const GeneratedFile& f : run_gen_tensors(r))
      std::cerr << "gen-tensors: wrote " << f.path.string() << " (" << f.summary << ")\n";
  });
}

}  // namespace shtool::cli
