// The table reader and the loaders on hostile bytes, through read_table_bytes: inputs
// that once crashed or misled shtool (deep JSON, bad sparse rows, oversized counts,
// truncations) must come back as an Error naming the problem.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/lighting.h"
#include "shtool/rotation_helpers.h"
#include "shtool/table.h"
#include "shtool/tripling_product.h"
#include "shtool/zhf_rotation.h"

namespace shtool {
namespace {

std::span<const std::byte> as_bytes(const std::string& s) {
  return {reinterpret_cast<const std::byte*>(s.data()), s.size()};
}

std::uint32_t crc(const std::string& s) { return table_crc32(as_bytes(s)); }

void put_le(std::string& out, std::size_t at, std::uint64_t v, int n) {
  for (int i = 0; i < n; ++i) out[at + i] = static_cast<char>((v >> (8 * i)) & 0xFF);
}

// A binary table with this header text and no data, with a valid header CRC.
std::string binary_with_header(const std::string& header) {
  std::string out(kTablePrefixSize, '\0');
  std::memcpy(out.data(), kTableMagic, 8);
  put_le(out, 8, header.size(), 8);
  put_le(out, 16, crc(header), 4);
  out += header;
  out.resize((out.size() + 63) / 64 * 64, '\0');
  return out;
}

std::string message_of(const std::string& bytes, const TableReadOptions& o = {}) {
  const Result<Table> t = read_table_bytes(as_bytes(bytes), "hostile", {}, nullptr, o);
  return t ? std::string() : t.error().message;
}

// One value of array `name` replaced, the table otherwise as it was.
void set_value(Table& t, const char* name, std::size_t i, double v) {
  for (TableArray& a : t.arrays)
    if (a.name == name) {
      std::vector<double> values = a.values<double>();
      values.at(i) = v;
      a = TableArray::from<double>(a.name, a.shape, values);
    }
}

// An env-sh table of order 2 (shape [4, 3]) built in memory with these values.
Table order2_lighting(const std::vector<double>& values) {
  Table light;
  light.kind = std::string(kEnvShKind);
  light.order = 2;
  light.meta = R"({"quantity": "radiance"})";
  light.arrays.push_back(TableArray::from<double>("coefficients", {4, 3}, values));
  return light;
}

// The shipped table `file` loads as X; with element i of `array` set to v it is refused,
// the message holding `fragment`.
template <class X>
void expect_one_value_refused(const char* file, const char* array, std::size_t i, double v,
                              const std::string& fragment) {
  Result<Table> table = read_table(find_shipped_table(file));
  ASSERT_TRUE(table.ok()) << table.error().message;
  ASSERT_TRUE(X::from_table(table.value()).ok()) << file;
  set_value(table.value(), array, i, v);
  const Result<X> x = X::from_table(table.value());
  ASSERT_FALSE(x.ok()) << file;
  EXPECT_NE(x.error().message.find(fragment), std::string::npos) << x.error().message;
}

TEST(UntrustedTables, FiniteValuesTooLargeToComputeWithAreRefused) {
  // Finite values a table of that kind cannot hold: taken, they turned a float lighting
  // into infinities (1e300 cast to float) and products and rotations into inf or NaN.
  Table light = order2_lighting(std::vector<double>(12, 0.5));
  ASSERT_TRUE(ShLighting<float>::from_table(light).ok());
  set_value(light, "coefficients", 5, 1e30);
  EXPECT_FALSE(ShLighting<float>::from_table(light).ok());
  EXPECT_TRUE(ShLighting<double>::from_table(light).ok());
  set_value(light, "coefficients", 5, 1e300);
  const Result<ShLighting<double>> huge = ShLighting<double>::from_table(light);
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.error().message.find("too large for the requested precision"), std::string::npos)
      << huge.error().message;

  // A triple integral of SH is at most max |y| = sqrt((2l + 1) / (4 pi)).
  expect_one_value_refused<TriplingTensor>("tripling-tensor.shtb", "value", 3, 1e300,
                                           "exceeds the bound of any SH triple integral");
  expect_one_value_refused<ZhfLobes>("zhf-shared-N4.shtb", "sparse_val", 2, 1e30, "A^ value too large");
}

TEST(UntrustedTables, AnInMemoryTableWhoseShapeOutrunsItsDataIsRefused) {
  // TableArray::from does not check the shape against the values; read_table always does.
  // A loader given such a table in memory once read past its data.
  const Table light = order2_lighting(std::vector<double>(1, 0.5));
  const Result<ShLighting<double>> l = ShLighting<double>::from_table(light);
  ASSERT_FALSE(l.ok());
  EXPECT_NE(l.error().message.find("array 'coefficients' holds 8 bytes, its dtype and shape need 96"),
            std::string::npos)
      << l.error().message;
  Result<Table> tripling = read_table(find_shipped_table("tripling-tensor.shtb"));
  ASSERT_TRUE(tripling.ok()) << tripling.error().message;
  for (TableArray& a : tripling.value().arrays) a.shape[0] *= 1000;
  const Result<TriplingTensor> t = TriplingTensor::from_table(tripling.value());
  ASSERT_FALSE(t.ok());
  EXPECT_NE(t.error().message.find("its dtype and shape need"), std::string::npos) << t.error().message;
}

// A header's order raised by hand over entries of a lower order (JSON headers carry no
// checksum): the products would drop every coupling of the missing bands.
TEST(UntrustedTables, ATriplingTensorMustCoverItsOrder) {
  Result<Table> tripling = read_table(find_shipped_table("tripling-tensor.shtb"));
  ASSERT_TRUE(tripling.ok()) << tripling.error().message;
  ASSERT_TRUE(TriplingTensor::from_table(tripling.value()).ok());
  tripling.value().order += 1;
  const Result<TriplingTensor> t = TriplingTensor::from_table(tripling.value());
  ASSERT_FALSE(t.ok());
  const int n2 = (tripling.value().order - 1) * (tripling.value().order - 1);
  EXPECT_NE(t.error().message.find("no entry (0, " + std::to_string(n2) + ", " + std::to_string(n2) +
                                   "): the entries do not cover order " + std::to_string(tripling.value().order)),
            std::string::npos)
      << t.error().message;
  // An edited value of such an entry is refused by name too.
  Table edited = read_table(find_shipped_table("tripling-tensor.shtb")).value();
  TableArray* value = nullptr;
  for (TableArray& a : edited.arrays)
    if (a.name == "value") value = &a;
  ASSERT_NE(value, nullptr);
  const double half = 0.25 / std::sqrt(std::numbers::pi);  // entry 0 is (0, 0, 0) = 1 / sqrt(4 pi)
  std::memcpy(value->data.data(), &half, sizeof half);
  const Result<TriplingTensor> e = TriplingTensor::from_table(edited);
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.error().message.find("is not 1/sqrt(4 pi)"), std::string::npos) << e.error().message;
}

TEST(UntrustedTables, ZhfLobesHeaderOrderMustMatchItsBands) {
  Result<Table> lobes = read_table(find_shipped_table("zhf-shared-N4.shtb"));
  ASSERT_TRUE(lobes.ok()) << lobes.error().message;
  ASSERT_TRUE(ZhfLobes::from_table(lobes.value()).ok());
  lobes.value().order = 1000;
  const Result<ZhfLobes> z = ZhfLobes::from_table(lobes.value());
  ASSERT_FALSE(z.ok());
  EXPECT_NE(z.error().message.find("the header says order 1000 but the table holds 4 bands"), std::string::npos)
      << z.error().message;
}

TEST(UntrustedTables, DeepJsonIsRefusedNotRecursedInto) {
  const std::string deep(60000, '[');
  // A JSON table, a header field, a shape entry nested ~60,000 deep.
  for (const std::string& doc : {"{\"format\": " + deep, "{\"meta\": " + deep + std::string(60000, ']') + "}",
                                 "{\"arrays\": [{\"shape\": [" + deep + "]}]}"}) {
    const std::string m = message_of(doc);
    EXPECT_NE(m.find("nested more than 64 levels"), std::string::npos) << m.substr(0, 200);
  }
  // The same inside a binary table whose CRCs are valid.
  const std::string m = message_of(binary_with_header("{\"generator\": " + deep + std::string(60000, ']') + "}"));
  EXPECT_NE(m.find("nested more than 64 levels"), std::string::npos) << m.substr(0, 200);
}

TEST(UntrustedTables, EveryTruncationOfAValidTableIsAnError) {
  const std::filesystem::path p = find_shipped_table("zhf-shared-N4.shtb");
  ASSERT_FALSE(p.empty());
  std::ifstream f(p, std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(f)), {});
  ASSERT_TRUE(message_of(good).empty()) << message_of(good);
  for (std::size_t n = 0; n < good.size(); n += 7) EXPECT_FALSE(message_of(good.substr(0, n)).empty()) << n;
}

TEST(UntrustedTables, ChecksumsOffStillValidateStructure) {
  // With CRCs off the reader still checks layout: a header promising more bytes than
  // the file holds is truncation, not a read past the end.
  const std::string header =
      "{\"format\":\"shtool-table\",\"format_version\":\"1.0\",\"kind\":\"k\",\"kind_version\":\"1.0\","
      "\"order\":1,\"conventions\":\"shtool-sh-v1\",\"generator\":{\"tool\":\"t\",\"version\":\"0\","
      "\"command\":\"c\",\"parameters\":{}},\"meta\":{},\"arrays\":[{\"name\":\"a\",\"dtype\":\"f64\","
      "\"shape\":[1000],\"offset\":0,\"nbytes\":8000,\"crc32\":0}]}";
  const std::string m = message_of(binary_with_header(header), {false});
  EXPECT_NE(m.find("truncated"), std::string::npos) << m;
}

}  // namespace
}  // namespace shtool
