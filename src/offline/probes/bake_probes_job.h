// bake-probes as a library job: read a scene (and an environment), bake the probe grid
// (probes/probe_bake.h), write the "probe-grid" table and, optionally, its JSON
// (docs/probes.md).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "common/mesh_frame.h"
#include "probes/probe_bake.h"
#include "probes/probe_grid_table.h"
#include "shtool/table.h"

namespace shtool::probes {

// Limits of the options (docs/probes.md): order 1..8 (the runtime loader's bound), up to
// 1024 probes along an axis and 2^24 in all, 1..2^20 samples, 0..64 bounces.
inline constexpr int kMaxOrder = 8;
inline constexpr int kMaxAxisProbes = 1024;
inline constexpr std::size_t kMaxProbes = std::size_t(1) << 24;
inline constexpr int kMaxSamples = 1 << 20;
inline constexpr int kMaxBounces = 64;

struct BakeProbesRequest {
  std::filesystem::path scene;
  UpAxis up = UpAxis::y;                      // OBJ only
  std::string grid;                           // "NX,NY,NZ"
  std::string bounds;                         // "X0,Y0,Z0,X1,Y1,Z1"; empty: the scene's box
  std::filesystem::path env;                  // lighting JSON (radiance); empty: none
  int order = 3;
  int samples = 1024;
  int bounces = 3;
  std::uint64_t seed = 1;
  int threads = 0;
  std::string encoding = "l2";                // l2, l1 or zh3 (docs/probe-encodings.md)
  std::string zh3_fit;                        // zh3: explicit (empty: explicit) or hallucinated
  std::string zh3_axis;                       // zh3: luminance (empty: luminance) or per-channel
  std::filesystem::path out;                  // the probe-grid table
  std::filesystem::path json;                 // optional
  std::filesystem::path threejs;              // optional: a folder for probes.json and probes.bin
  std::string shard;                          // "K/N": a partial table of probes; empty: all
  bool mpi = false;                           // ranks split the probes, rank 0 writes
};

struct BakeProbesReport {
  std::size_t probes = 0, invalid = 0, unfilled = 0;
  std::array<int, 3> resolution{0, 0, 0};
  Eigen::Vector3d lower, upper;
  std::size_t triangles = 0, lights = 0;
  std::size_t unsupported_lights = 0;  // KHR_lights_punctual lights of a type the bake does not know, left out
  std::uint64_t rays = 0;
  double seconds = 0;
  bool sharded = false;
  int mpi_rank = 0, mpi_ranks = 0;            // ranks: 0 without --mpi
  std::size_t first_probe = 0, end_probe = 0;
  std::string encoding;  // as stored: "l2", "l1", "zh3 explicit, luminance axis", ...
};

// "NX,NY,NZ" and "X0,Y0,Z0,X1,Y1,Z1" parsed and checked; InputError naming the option.
std::array<int, 3> parse_grid(const std::string& text);
std::pair<Eigen::Vector3d, Eigen::Vector3d> parse_bounds(const std::string& text);

// Checks every option before reading anything large, bakes, writes both outputs or none.
BakeProbesReport run_bake_probes(const BakeProbesRequest& request);


}  // namespace shtool::probes
