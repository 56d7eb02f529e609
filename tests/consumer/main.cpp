// Links the installed runtime and checks a few SH values against closed forms, so a
// package that installs headers but a broken or mismatched library fails here.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <vector>

#include <shtool/sh.h>
#include <shtool/version.h>

namespace {

int failures = 0;

// Closed forms are a handful of floating-point operations from eval_sh's recurrence;
// 4 ulp of slack covers that difference.
constexpr double kTol = 4 * 2.220446049250313e-16;

void check(const char* name, double got, double want) {
  if (!(std::abs(got - want) <= kTol * std::max(1.0, std::abs(want)))) {
    std::fprintf(stderr, "consumer: %s = %.17g, expected %.17g\n", name, got, want);
    ++failures;
  }
}

}  // namespace

int main() {
  if (std::strcmp(shtool::kVersion, SHTOOL_PACKAGE_VERSION) != 0) {
    std::fprintf(stderr, "consumer: package version %s but shtool/version.h says %s\n",
                 SHTOOL_PACKAGE_VERSION, shtool::kVersion);
    ++failures;
  }

  const double pi = std::numbers::pi;
  const double c = std::sqrt(3 / (4 * pi));  // band-1 constant (docs/conventions.md)
  // An unnormalised direction, normalised here: eval_sh expects a unit vector.
  shtool::Vec3<double> w(0.3, -0.5, 0.8);
  w.normalize();

  std::vector<double> y(shtool::sh_count(2));
  shtool::eval_sh<double>(2, w, y);
  check("y_0^0", y[shtool::sh_index(0, 0)], 0.28209479177387814);
  check("y_1^-1", y[shtool::sh_index(1, -1)], -c * w.y());
  check("y_1^0", y[shtool::sh_index(1, 0)], c * w.z());
  check("y_1^1", y[shtool::sh_index(1, 1)], -c * w.x());

  if (failures != 0) {
    std::fprintf(stderr, "consumer: %d check(s) failed\n", failures);
    return 1;
  }
  std::printf("consumer: shtool %s runtime OK\n", shtool::kVersion);
  return 0;
}
