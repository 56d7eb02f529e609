// The table reader and the loaders on hostile bytes, through read_table_bytes: inputs
// that once crashed or misled shtool (deep JSON, bad sparse rows, oversized counts,
// truncations) must come back as an Error naming the problem.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/rotation_helpers.h"
#include "shtool/table.h"
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
