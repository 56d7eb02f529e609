// Diffuse transfer simulation: a plane with nothing above gives the analytic
// clamped-cosine transfer; on a convex mesh shadowing changes nothing; a vertex under a
// huge roof sees almost nothing; results are deterministic and thread-count independent;
// interreflected ranges that gather each bounce give the whole mesh's rows; Embree ray
// streams and single rays give the same bytes.
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "fit/mesh.h"
#include "fit/transfer.h"
#include "shtool/sh.h"

namespace {

using namespace shtool;
using namespace shtool::fit;

fit::Mesh from_obj(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "shtool_test_transfer";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / name) << text;
  return load_obj(dir / name, NormalSource::automatic, UpAxis::z);  // written in shtool's frame
}

// 3x3 grid in z = 0 (centre vertex 5 has triangles all around it), normal +z.
const std::string kPlane =
    "v -1 -1 0\nv 0 -1 0\nv 1 -1 0\nv -1 0 0\nv 0 0 0\nv 1 0 0\nv -1 1 0\nv 0 1 0\nv 1 1 0\n"
    "f 1 2 5\nf 1 5 4\nf 2 3 6\nf 2 6 5\nf 4 5 8\nf 4 8 7\nf 5 6 9\nf 5 9 8\n";

const std::string kCube =
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
    "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

// (1/pi) integral of max(cos t, 0) y_l^0 = 2 K_l integral_0^1 x P_l(x) dx, with
// K_l = sqrt((2l+1)/(4 pi)) and integral_0^1 x P_l = 1/2, 1/3, 1/8, 0, -1/48, 0 for
// l = 0..5 (the clamped-cosine zonal coefficients). Bands m != 0 vanish.
double clamped_cosine_transfer(int l) {
  static const double moment[] = {1.0 / 2, 1.0 / 3, 1.0 / 8, 0.0, -1.0 / 48, 0.0};
  return 2.0 * std::sqrt((2 * l + 1) / (4 * std::numbers::pi)) * moment[l];
}

TEST(Transfer, ClampedCosineConstants) {
  // Band 0 is sqrt(pi)/2 / pi = 1/(2 sqrt(pi)); band 1 is 2/3 sqrt(3/(4 pi)) = 1/sqrt(3 pi).
  EXPECT_DOUBLE_EQ(clamped_cosine_transfer(0), std::sqrt(std::numbers::pi) / 2 / std::numbers::pi);
  EXPECT_DOUBLE_EQ(clamped_cosine_transfer(1), 1.0 / std::sqrt(3 * std::numbers::pi));
}

TEST(Transfer, OpenPlaneGivesClampedCosine) {
  const fit::Mesh plane = from_obj("plane.obj", kPlane);
  for (TransferMode mode : {TransferMode::unshadowed, TransferMode::shadowed}) {
    TransferOptions o{.order = 6, .rays = 4096, .mode = mode, .threads = 1};
    const std::vector<double> t = compute_transfer(plane, o);
    const int n2 = 36;
    for (int v : {0, 4, 8}) {
      // Band 0 is exact up to summation: every cosine-weighted ray contributes the
      // constant y_0^0, and summing `rays` equal values errs by at most rays * eps * t.
      EXPECT_NEAR(t[v * n2], clamped_cosine_transfer(0), o.rays * 0x1.0p-52 * clamped_cosine_transfer(0))
          << "vertex " << v;
      for (int l = 1; l < 6; ++l)
        for (int m = -l; m <= l; ++m) {
          const double expected = m == 0 ? clamped_cosine_transfer(l) : 0.0;
          // Stratified 4096-ray estimate of a smooth integrand: the error is O(1/rays)
          // times the basis scale (|y| <= 1.5 here); 2e-3 leaves a margin of ~3x over
          // the largest error measured, and a wrong constant or sign is off by > 0.02.
          EXPECT_NEAR(t[v * n2 + sh_index(l, m)], expected, 2e-3)
              << "vertex " << v << " l " << l << " m " << m << " mode " << static_cast<int>(mode);
        }
    }
  }
}

TEST(Transfer, ConvexMeshShadowedEqualsUnshadowed) {
  // From a vertex of a convex mesh the vertex normal spans a supporting plane: no ray
  // of the upper hemisphere can hit the mesh, so shadowing and bounces change nothing.
  const fit::Mesh cube = from_obj("cube.obj", kCube);
  TransferOptions o{.order = 4, .rays = 256, .mode = TransferMode::unshadowed};
  const std::vector<double> free = compute_transfer(cube, o);
  o.mode = TransferMode::shadowed;
  EXPECT_EQ(compute_transfer(cube, o), free);
  o.mode = TransferMode::interreflected;
  EXPECT_EQ(compute_transfer(cube, o), free);
}

// More rays than one chunk (the simulation makes and traces 4096 at a time, so any
// --rays fits in memory): the sum is still every direction once, in order.
TEST(Transfer, RaysBeyondOneChunkAreEachSummedOnce) {
  const fit::Mesh plane = from_obj("plane.obj", kPlane);
  const int rays = 2 * 4096 + 123;
  TransferOptions o{.order = 3, .rays = rays, .seed = 3, .mode = TransferMode::unshadowed, .threads = 1};
  const std::vector<double> free = compute_transfer(plane, o);
  // The reference: the same directions summed in one loop.
  const VertexRays cast(plane, 4, o.seed, rays, 0.0);
  std::vector<double> sum(9, 0.0), y(9);
  for (int k = 0; k < rays; ++k) {
    eval_sh<double>(3, cast.direction(k), y);
    for (int i = 0; i < 9; ++i) sum[i] += y[i];
  }
  for (int i = 0; i < 9; ++i) EXPECT_EQ(free[4 * 9 + i], sum[i] / rays) << i;
  // Nothing above the plane: no ray of any chunk is blocked.
  o.mode = TransferMode::shadowed;
  EXPECT_EQ(compute_transfer(plane, o), free);
  // Under a roof every ray of every chunk is.
  const fit::Mesh roofed = from_obj("roof.obj", kPlane +
                                                    "v -1000 -1000 1\nv 1000 -1000 1\nv 1000 1000 1\nv -1000 1000 1\n"
                                                    "f 10 12 11\nf 10 13 12\n");
  const std::vector<double> blocked = compute_transfer(roofed, o);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(blocked[4 * 9 + i], 0.0) << i;
}

TEST(Transfer, RoofBlocksAlmostEverything) {
  // A plane under a square roof of half-width 1000 at height 1: only directions with
  // tan(theta) > ~1000 escape, a cosine-weighted fraction cos^2 ~ 1e-6.
  const fit::Mesh m = from_obj("roof.obj", kPlane +
                                               "v -1000 -1000 1\nv 1000 -1000 1\nv 1000 1000 1\nv -1000 1000 1\n"
                                               "f 10 12 11\nf 10 13 12\n");
  TransferOptions o{.order = 3, .rays = 1024};
  const std::vector<double> shadowed = compute_transfer(m, o);
  // Centre vertex of the plane (index 4): no sample direction escapes.
  for (int i = 0; i < 9; ++i) EXPECT_EQ(shadowed[4 * 9 + i], 0.0) << "coefficient " << i;
  o.mode = TransferMode::interreflected;
  o.albedo = 0.5;
  o.bounces = 1;
  const std::vector<double> bounced = compute_transfer(m, o);
  // The roof faces down; its vertices (1000 away from the small plane) see the open
  // lower hemisphere, so their direct transfer is the clamped cosine, constant over the
  // roof. Every ray from the centre hits the roof: one bounce gives exactly
  // albedo * 1/(2 sqrt(pi)) in band 0, up to summation (1e-12 >> 1024 eps).
  EXPECT_NEAR(bounced[4 * 9], 0.5 * clamped_cosine_transfer(0), 1e-12);
}

TEST(Transfer, InterreflectionAddsLightInAnOpenCorner) {
  // A floor and a wall meeting at a right angle: the floor vertex in front of the
  // wall loses light to the wall (shadowed < unshadowed) and gets some back from it.
  const fit::Mesh m = from_obj("corner.obj", kPlane +
                                                 "v -1 1 2\nv 0 1 2\nv 1 1 2\nf 7 9 12\nf 7 12 10\n");
  TransferOptions o{.order = 3, .rays = 1024, .mode = TransferMode::unshadowed};
  const double free = compute_transfer(m, o)[4 * 9];
  o.mode = TransferMode::shadowed;
  const double shadowed = compute_transfer(m, o)[4 * 9];
  o.mode = TransferMode::interreflected;
  o.albedo = 0.5;
  const double bounced = compute_transfer(m, o)[4 * 9];
  EXPECT_LT(shadowed, free);
  EXPECT_GT(bounced, shadowed);
}

TEST(Transfer, DeterministicAndIndependentOfThreads) {
  const fit::Mesh plane = from_obj("plane.obj", kPlane +
                                                    "v 0 0 3\nv 1 0 3\nv 0 1 3\nf 10 12 11\n");
  TransferOptions o{.order = 4, .rays = 64, .seed = 7, .threads = 1};
  const std::vector<double> one = compute_transfer(plane, o);
  o.threads = 2;
  EXPECT_EQ(compute_transfer(plane, o), one);
  o.threads = 5;
  EXPECT_EQ(compute_transfer(plane, o), one);
  o.seed = 8;
  EXPECT_NE(compute_transfer(plane, o), one);
}

TEST(Transfer, RayStreamsGiveTheBytesOfSingleRays) {
  // data/spot.obj shadows itself (ears, legs): thousands of rays blocked, many grazing.
  const fit::Mesh spot = load_obj(std::string(SHTOOL_SOURCE_DIR) + "/data/spot.obj");
  TransferOptions o{.order = 4, .rays = 64, .ray_streams = false};
  const std::vector<double> single = compute_transfer(spot, o);
  o.ray_streams = true;
  EXPECT_EQ(compute_transfer(spot, o), single);
  o.mode = TransferMode::unshadowed;
  EXPECT_NE(compute_transfer(spot, o), single);  // the occlusion does change the vectors
  // The bounces' closest hits (barycentric weights included) through rtcIntersect1M.
  o.mode = TransferMode::interreflected;
  o.bounces = 2;
  o.ray_streams = false;
  const std::vector<double> bounced = compute_transfer(spot, o);
  EXPECT_NE(bounced, single);
  o.ray_streams = true;
  EXPECT_EQ(compute_transfer(spot, o), bounced);
}

TEST(Transfer, InterreflectedRangesWithAGatherMatchTheWholeMesh) {
  // Two ranges simulated side by side, as two MPI ranks would: the gather step waits for
  // both ranges' rows of a bounce and hands each the whole mesh's rows in vertex order.
  const fit::Mesh m = from_obj("corner.obj", kPlane + "v -1 1 2\nv 0 1 2\nv 1 1 2\nf 7 9 12\nf 7 12 10\n");
  TransferOptions o{.order = 3, .rays = 64, .mode = TransferMode::interreflected, .albedo = 0.7};
  o.bounces = 3;
  const std::vector<double> whole = compute_transfer(m, o);
  const std::size_t split = 5;
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<double> parts[2];
  int arrived = 0, collected = 0;
  long long round = 0;
  int gathers[2] = {0, 0};
  auto range = [&](int part) {
    TransferOptions ro = o;
    ro.first_vertex = part == 0 ? 0 : split;
    ro.end_vertex = part == 0 ? split : m.positions.size();
    ro.gather_bounce = [&, part](std::vector<double> rows) {
      std::unique_lock lock(mutex);
      ++gathers[part];
      changed.wait(lock, [&] { return arrived < 2; });  // the previous round is collected
      parts[part] = std::move(rows);
      const long long mine = round;
      if (++arrived == 2) changed.notify_all();
      changed.wait(lock, [&] { return arrived == 2 || round != mine; });
      std::vector<double> all = parts[0];
      all.insert(all.end(), parts[1].begin(), parts[1].end());
      if (++collected == 2) {
        arrived = collected = 0;
        ++round;
        changed.notify_all();
      }
      return all;
    };
    return compute_transfer(m, ro);
  };
  std::vector<double> first_rows, second_rows;
  std::thread other([&] { second_rows = range(1); });
  first_rows = range(0);
  other.join();
  // Gathered after the direct pass and after every bounce but the last.
  EXPECT_EQ(gathers[0], o.bounces);
  EXPECT_EQ(gathers[1], o.bounces);
  first_rows.insert(first_rows.end(), second_rows.begin(), second_rows.end());
  EXPECT_EQ(first_rows, whole);
  // Without the gather step a range has no previous bounce to read.
  TransferOptions alone = o;
  alone.end_vertex = split;
  EXPECT_THROW(compute_transfer(m, alone), shtool::InputError);
}

TEST(Transfer, RejectsBadOptions) {
  const fit::Mesh plane = from_obj("plane.obj", kPlane);
  TransferOptions o;
  o.rays = 0;
  EXPECT_THROW(compute_transfer(plane, o), shtool::InputError);
  o.rays = 4;
  o.order = 0;
  EXPECT_THROW(compute_transfer(plane, o), shtool::InputError);
}

}  // namespace
