// A probe grid as three.js's LightProbeGridWebGL reads it (three@0.187.0): DIR/probes.json
// (resolution, bounds, atlas name, in three's y-up frame) and DIR/probes.bin (the RGBA32F
// atlas of its lightprobes_pars_fragment shader), for web/shtool-three.js's loadProbeGrid
// (docs/probe-encodings.md).
//
// three's frame is (x, z, -y) of shtool's, a signed permutation, so probe centres map onto
// probe centres: three's resolution is (NX, NZ, NY), its bounds ((x0, z0, -y1), (x1, z1, -y0)),
// and its probe (i, j, k) is shtool's (ix, iy, iz) = (i, NY - 1 - k, j). Each probe's
// radiance coefficients become the 27 numbers of three's SphericalHarmonics3 (its basis,
// no Condon-Shortley phase) by interop::threejs_sh3, the mapping export-light uses.
//
// Atlas: width NX3, height NY3, depth 7 (NZ3 + 2) texels of 4 float32 (little-endian),
// texel (x, y, s) at float ((s NY3 + y) NX3 + x) 4. Slot t = 0..6 of a probe holds floats
// 4t..4t+3 of its 27 numbers followed by one 0, at slice t (NZ3 + 2) + 1 + z; slices
// t (NZ3 + 2) and t (NZ3 + 2) + NZ3 + 1 repeat the slot's first and last data slices (the
// padding that keeps hardware filtering inside a slot).
#pragma once

#include <array>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/job_outputs.h"
#include "shtool/probe_encoding.h"

namespace shtool::interop {

inline constexpr const char* kThreeVersion = "0.187.0";

struct ThreeProbeGridInput {
  std::array<int, 3> resolution{};  // NX, NY, NZ in shtool's frame, each >= 1
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();  // shtool's frame, min < max
  int order = 3;                    // SH order of the coefficients (bands above 2 dropped, missing ones zero)
  // Radiance coefficients in shtool's basis, probe-major (ix fastest, then iy, then iz),
  // then [3 i + c] within a probe: NX NY NZ order^2 3 values.
  std::vector<double> coefficients;
};

struct ThreeProbeGridFiles {
  std::string json;   // probes.json
  std::string atlas;  // probes.bin
};

// Why three.js cannot show an l1 grid: LightProbeGridWebGL evaluates SH linearly, and
// Geomerics' L1 reconstruction is not linear.
inline constexpr const char* kThreeCannotShowL1 =
    "three.js's LightProbeGridWebGL evaluates order-3 SH linearly and cannot reconstruct non-linear L1; "
    "bake with --encoding zh3 or l2 for three.js";

// The order-3 radiance SH that three.js evaluates linearly for one ZH3 probe: its bands 0
// and 1 (l1, [3 k + c]) and the band 2 its zonal coefficients stand for along the axis
// (zh3_band2); `zonal` the stored r, g, b of the explicit fit, or null for the
// hallucinated fit (then from the L1 band, zh3_hallucinated_zonal). 27 values [3 k + c].
std::array<double, 27> zh3_as_order3_sh(std::span<const double, 12> l1, const double* zonal, Zh3Axis axis);

// InputError on a resolution below 1 or above 4096 per axis, bounds not finite or not
// min < max, a wrong coefficient count, or a value that is not finite as float32.
ThreeProbeGridFiles three_probe_grid_files(const ThreeProbeGridInput& grid);

// The two files as outputs of a job: declared (DIR must be an existing folder) under the
// option `option` ("--threejs"), then given their bytes. Committed with the job's others.
void declare_three_probe_grid(JobOutputs& io, const std::filesystem::path& dir, const std::string& option);
void set_three_probe_grid(JobOutputs& io, const std::string& option, ThreeProbeGridFiles files);

// Both steps and the commit, for a grid alone.
void write_three_probe_grid(const std::filesystem::path& dir, const ThreeProbeGridInput& grid);

}  // namespace shtool::interop
