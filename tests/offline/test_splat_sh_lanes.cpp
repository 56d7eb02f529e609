// SplatShLanes (src/offline/interop/splat_scene.h), the SIMD path of transform-splats,
// against its slow reference OrthogonalMap::apply(in, out, 3), bit for bit: rotations and
// reflections, orders 1..4 (degrees 0..3), PLY's channel-major f_rest layout.
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "interop/splat_scene.h"
#include "shtool/orthogonal_map.h"
#include "shtool/sh.h"

namespace {

using shtool::OrthogonalMap;
using shtool::interop::SplatShLanes;

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  const Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

TEST(SplatShLanes, EqualsTheOrthogonalMapBitForBit) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  constexpr int L = SplatShLanes::kLanes;
  for (int order = 1; order <= 4; ++order)
    for (const bool reflect : {false, true}) {
      Eigen::Matrix3d q = random_rotation(rng);
      if (reflect) q = q * Eigen::Vector3d(1, -1, 1).asDiagonal();
      const OrthogonalMap map = OrthogonalMap::make(q, order).value();
      ASSERT_EQ(map.reflects(), reflect);
      const SplatShLanes lanes(map);
      const int n2 = shtool::sh_count(order), rest = n2 - 1;
      // Per splat: interleaved RGB coefficients (the map's input), and the lanes' layout of
      // bands 1.. : value j = c * rest + k - 1 of lane s at [j * L + s].
      std::vector<std::vector<double>> splat(L, std::vector<double>(3 * n2));
      std::vector<double> in(3 * rest * L), out(3 * rest * L, 7.0);
      for (int s = 0; s < L; ++s)
        for (int k = 0; k < n2; ++k)
          for (int c = 0; c < 3; ++c) {
            splat[s][3 * k + c] = u(rng);
            if (k > 0) in[(c * rest + k - 1) * L + s] = splat[s][3 * k + c];
          }
      lanes.apply(in.data(), out.data());
      for (int s = 0; s < L; ++s) {
        std::vector<double> expect(3 * n2);
        ASSERT_TRUE(map.apply(splat[s], expect, 3));
        for (int k = 1; k < n2; ++k)
          for (int c = 0; c < 3; ++c) {
            const double got = out[(c * rest + k - 1) * L + s];
            EXPECT_EQ(std::memcmp(&got, &expect[3 * k + c], sizeof got), 0)
                << "order " << order << (reflect ? " reflected" : "") << " splat " << s << " k " << k << " c " << c
                << ": " << got << " vs " << expect[3 * k + c];
          }
      }
    }
}

}  // namespace
