// Every table shipped in tables/ loads through the runtime the way an engine finds it
// (SHTOOL_TABLES, set by the test harness to the source tree's tables/): a table that is
// missing, unreadable or fails its kind's checks is a failure, never a skip.
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/fourier_tensors.h"
#include "shtool/rotation_helpers.h"
#include "shtool/table.h"
#include "shtool/tripling_product.h"
#include "shtool/zhf_rotation.h"

namespace shtool {
namespace {

std::filesystem::path shipped(const std::string& name) {
  const std::filesystem::path p = find_shipped_table(name);
  EXPECT_FALSE(p.empty()) << name << " not found (SHTOOL_TABLES=" << (std::getenv("SHTOOL_TABLES") ? std::getenv("SHTOOL_TABLES") : "")
                          << ")";
  return p;
}

TEST(ShippedTables, LookupHonoursShtoolTablesAndReportsAbsence) {
  ASSERT_NE(std::getenv("SHTOOL_TABLES"), nullptr) << "the test harness sets SHTOOL_TABLES";
  EXPECT_EQ(find_shipped_table("rotation-helpers.shtb"),
            std::filesystem::path(std::getenv("SHTOOL_TABLES")) / "rotation-helpers.shtb");
  EXPECT_TRUE(find_shipped_table("no-such-table.shtb").empty());
}

TEST(ShippedTables, RotationHelpersCoverOrder30) {
  const auto h = RotationHelpers::load(shipped("rotation-helpers.shtb"));
  ASSERT_TRUE(h.ok()) << h.error().message;
  EXPECT_EQ(h.value().order, 30);
  EXPECT_EQ(default_rotation_helpers_path(), shipped("rotation-helpers.shtb"));
}

TEST(ShippedTables, TriplingAndFourierTensorsOfOrder16) {
  auto tensor = TriplingTensor::load(shipped("tripling-tensor.shtb"));
  ASSERT_TRUE(tensor.ok()) << tensor.error().message;
  EXPECT_EQ(tensor.value().order, 16);
  auto fourier = ShFourierTensors::load(shipped("sh-fourier-tensors.shtb"));
  ASSERT_TRUE(fourier.ok()) << fourier.error().message;
  EXPECT_EQ(fourier.value().order, 16);
}

TEST(ShippedTables, SharedLobesForOrders4To10) {
  for (int n = 4; n <= 10; ++n) {
    const std::string name = "zhf-shared-N" + std::to_string(n) + ".shtb";
    const auto z = ZhfLobes::load(shipped(name));
    ASSERT_TRUE(z.ok()) << z.error().message;
    EXPECT_EQ(z.value().order, n) << name;
    // The default look-up picks the table of that order.
    EXPECT_EQ(default_zhf_lobes_path(n), shipped(name));
  }
  EXPECT_TRUE(default_zhf_lobes_path(11).empty()) << "no shipped shared table covers order 11";
}

TEST(ShippedTables, PerBandLobeTables) {
  for (const char* name : {"zhf-bands-l2-10.shtb", "zhf-bands-l11-12.shtb", "zhf-bands-l13-18.shtb"}) {
    const auto t = read_table(shipped(name), {std::string(kZhfLobesKind), 1, 0});
    EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
  }
}

}  // namespace
}  // namespace shtool
