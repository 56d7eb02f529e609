// Writes the data of docs/rotation-error.png ([2] Fig. 3: error of the Taylor
// y-rotations against the tilt, orders 5 and 8) as CSV to the file given, or to stdout.
// Built as the target rotation_error_csv; scripts/plot_rotation_error.sh runs it and
// plots the result.
#include <cstdio>
#include <string>

#include "rotation_error_curve.h"

int main(int argc, char** argv) {
  using namespace shtool;
  using namespace shtool::error_curve;
  std::FILE* out = argc > 1 ? std::fopen(argv[1], "w") : stdout;
  if (!out) {
    std::fprintf(stderr, "rotation_error_csv: cannot write '%s'\n", argv[1]);
    return 1;
  }
  std::fprintf(out, "order,method,beta_deg,max_error,mean_error,phong7_error\n");
  for (const auto& [key, curve] : curves()) {
    const auto [order, method] = key;
    for (int k = 0; k <= kSteps; ++k)
      std::fprintf(out, "%d,%s,%.17g,%.17g,%.17g,%.17g\n", order, std::string(rotation_method_name(method)).c_str(),
                   k * kMaxDegrees / kSteps, curve[k].max_error, curve[k].mean_error, curve[k].lobe_error);
  }
  const bool ok = std::ferror(out) == 0;
  if (out != stdout && std::fclose(out) != 0) return 1;
  return ok ? 0 : 1;
}
