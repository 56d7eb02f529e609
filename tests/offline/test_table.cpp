// Tables: write/read round trips in both encodings, determinism, the byte layout of
// docs/table-format.md checked by an independent parser, every corruption the loader
// must reject, atomic writes, the JSON Schemas, the numpy reader of the docs and
// `shtool inspect` end to end.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shtool/table.h"
#include "table_test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;
using shtool::test::expect_same_table;
using shtool::test::try_write;
using namespace shtool;

namespace {

// ---------------------------------------------------------------------------
// Helpers.

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_file(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Independent reference CRC: bit by bit, straight from the definition (reflected
// polynomial 0xEDB88320, init and final xor all ones), no table.
std::uint32_t crc_bitwise(std::string_view s) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : s) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::uint64_t get_u64_le(const std::string& s, std::size_t at) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(s[at + i]);
  return v;
}
std::uint32_t get_u32_le(const std::string& s, std::size_t at) {
  return static_cast<std::uint32_t>(get_u64_le(s + std::string(4, '\0'), at) & 0xFFFFFFFFu);
}
void put_le(std::string& s, std::size_t at, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) s[at + i] = static_cast<char>((v >> (8 * i)) & 0xFF);
}

// A binary table split into its parts by the layout of docs/table-format.md.
struct Parsed {
  std::string header_text;
  std::string data;  // the data section (from the 64-aligned start to the end)
};
Parsed split_binary(const std::string& file) {
  const std::uint64_t len = get_u64_le(file, 8);
  const std::uint64_t data_start = (24 + len + 63) / 64 * 64;
  return {file.substr(24, len), file.substr(data_start)};
}
// Reassembles a binary table around a (modified) header, with a correct header CRC, so a
// test reaches the check after the CRC.
std::string rebuild_binary(const std::string& header_text, const std::string& data) {
  std::string out(24, '\0');
  std::memcpy(out.data(), "\x89SHT\r\n\x1a\n", 8);
  put_le(out, 8, header_text.size(), 8);
  put_le(out, 16, crc_bitwise(header_text), 4);
  out += header_text;
  out.resize((out.size() + 63) / 64 * 64, '\0');
  return out + data;
}
std::string with_header(const std::string& file, const json& header) {
  return rebuild_binary(header.dump(), split_binary(file).data);
}

template <class T>
std::uint64_t bits_of(T v) {
  if constexpr (sizeof(T) == 8) return std::bit_cast<std::uint64_t>(v);
  else return std::bit_cast<std::uint32_t>(v);
}

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};
// Runs a shell command, capturing stdout and stderr in files next to `scratch`.
RunResult run(const std::string& command, const fs::path& scratch) {
  const fs::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string full = command + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(full.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

const std::string kSource = SHTOOL_SOURCE_DIR;
const std::string kPython = SHTOOL_PYTHON;

// Values that stress exact round trips: signed zeros, denormals, extremes, values with
// long shortest representations.
const std::vector<double> kSpecialDoubles = {
    0.0, -0.0, 1.0, -1.0, 1.0 / 3.0, std::numbers::pi, 0.1, -2.5e-300,
    std::numeric_limits<double>::denorm_min(), -std::numeric_limits<double>::denorm_min(),
    std::numeric_limits<double>::min(), std::nextafter(std::numeric_limits<double>::min(), 0.0),
    std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
    std::numeric_limits<double>::epsilon(), 123456789.123456789};
const std::vector<float> kSpecialFloats = {
    0.0f, -0.0f, 1.0f, 0.1f, 1.0f / 3.0f, -3.14159274f,
    std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min(),
    std::numeric_limits<float>::min(), std::nextafter(std::numeric_limits<float>::min(), 0.0f),
    std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest()};

Table make_table() {
  Table t;
  t.kind = "test-kind";
  t.kind_version = "1.2";
  t.order = 3;
  t.generator = json{{"tool", "shtool"}, {"version", "0.1.0"}, {"command", "test"},
                 {"parameters", {{"seed", 42}, {"samples", 1000}}}}.dump();
  t.meta = json{{"note", "round trip"}, {"max_error", 1.5e-17}}.dump();
  t.arrays.push_back(TableArray::from<double>("f64_specials", {2, 8}, kSpecialDoubles));
  t.arrays.push_back(TableArray::from<float>("f32_specials", {3, 2, 2}, kSpecialFloats));
  t.arrays.push_back(TableArray::from<std::int32_t>(
      "i32", {3}, std::vector<std::int32_t>{std::numeric_limits<std::int32_t>::min(), -1,
                                            std::numeric_limits<std::int32_t>::max()}));
  t.arrays.push_back(TableArray::from<std::uint32_t>(
      "u32", {2}, std::vector<std::uint32_t>{0, std::numeric_limits<std::uint32_t>::max()}));
  t.arrays.push_back(TableArray::from<std::int64_t>(
      "i64", {1, 3}, std::vector<std::int64_t>{std::numeric_limits<std::int64_t>::min(), 0,
                                               std::numeric_limits<std::int64_t>::max()}));
  t.arrays.push_back(TableArray::from<std::uint64_t>(
      "u64", {2}, std::vector<std::uint64_t>{1, std::numeric_limits<std::uint64_t>::max()}));
  t.arrays.push_back(TableArray::from<std::uint8_t>("u8", {5}, std::vector<std::uint8_t>{0, 1, 127, 128, 255}));
  t.arrays.push_back(TableArray::from<double>("empty", {0}, std::vector<double>{}));
  t.arrays.push_back(TableArray::from<float>("empty_2d", {3, 0}, std::vector<float>{}));
  t.arrays.push_back(TableArray::from<double>("scalar", {}, std::vector<double>{-0.0}));
  return t;
}

class TableTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("shtool-test-table-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;

  // Writes the standard table and returns its path (binary unless told).
  fs::path written(const std::string& name = "t.shtbl", TableEncoding enc = TableEncoding::binary) {
    const fs::path p = dir_ / name;
    auto r = shtool::test::try_write(make_table(), p, enc);
    EXPECT_TRUE(r.ok()) << r.error().message;
    return p;
  }
  // Loads `bytes` from a file and expects an error containing each of `needles`.
  void expect_rejected(const std::string& bytes, std::initializer_list<std::string> needles,
                       const TableExpectation& expect = {}) {
    const fs::path p = dir_ / "corrupt.shtbl";
    write_file(p, bytes);
    auto r = read_table(p, expect);
    ASSERT_FALSE(r.ok()) << "corrupted table was accepted; expected an error with '" << *needles.begin() << "'";
    const std::string& msg = r.error().message;
    EXPECT_EQ(msg.rfind(p.string() + ": ", 0), 0u) << "message does not start with the path: " << msg;
    for (const std::string& n : needles) EXPECT_NE(msg.find(n), std::string::npos) << "'" << n << "' not in: " << msg;
  }
};

// ---------------------------------------------------------------------------
// CRC and dtypes.

TEST(TableCrc, MatchesReferenceValues) {
  // The standard CRC-32 check value (zlib, PNG, Ethernet): crc32("123456789").
  const std::string check = "123456789";
  EXPECT_EQ(table_crc32(std::as_bytes(std::span(check.data(), check.size()))), 0xCBF43926u);
  EXPECT_EQ(table_crc32({}), 0u);
  // Against the bitwise definition on every byte value, and continuation.
  std::string all;
  for (int i = 0; i < 256 * 3; ++i) all += static_cast<char>((i * 37 + 11) & 0xFF);
  const auto bytes = std::as_bytes(std::span(all.data(), all.size()));
  EXPECT_EQ(table_crc32(bytes), crc_bitwise(all));
  EXPECT_EQ(table_crc32(bytes.subspan(100), table_crc32(bytes.first(100))), crc_bitwise(all));
}

TEST(TableDType, NamesSizesRoundTrip) {
  const std::pair<DType, std::size_t> all[] = {{DType::f64, 8}, {DType::f32, 4}, {DType::i32, 4}, {DType::u32, 4},
                                               {DType::i64, 8}, {DType::u64, 8}, {DType::u8, 1}};
  for (auto [t, size] : all) {
    EXPECT_EQ(dtype_size(t), size) << dtype_name(t);
    EXPECT_EQ(dtype_from_name(dtype_name(t)), t) << dtype_name(t);
  }
  EXPECT_FALSE(dtype_from_name("f16"));
  EXPECT_FALSE(dtype_from_name(""));
  static_assert(dtype_of<double>() == DType::f64 && dtype_of<std::uint8_t>() == DType::u8);
}

TEST(TableArrayTest, ValuesAndGet) {
  const Table t = make_table();
  EXPECT_EQ(t.find("i64")->values<std::int64_t>()[0], std::numeric_limits<std::int64_t>::min());
  auto f = t.get<float>("f32_specials");
  ASSERT_TRUE(f.ok()) << f.error().message;
  ASSERT_EQ(f.value().size(), kSpecialFloats.size());
  for (std::size_t i = 0; i < kSpecialFloats.size(); ++i) EXPECT_EQ(bits_of(f.value()[i]), bits_of(kSpecialFloats[i]));
  auto wrong = t.get<double>("f32_specials");
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().message.find("dtype f32, expected f64"), std::string::npos) << wrong.error().message;
  auto missing = t.get<double>("nope");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("no array 'nope'"), std::string::npos) << missing.error().message;
  EXPECT_EQ(t.find("scalar")->element_count(), 1u);
  EXPECT_EQ(t.find("empty_2d")->element_count(), 0u);
}

// ---------------------------------------------------------------------------
// Round trips and determinism.

TEST_F(TableTest, BinaryRoundTripExactBits) {
  Table t = make_table();
  // Binary stores exact bits, NaN payloads and infinities included.
  t.arrays.push_back(TableArray::from<double>(
      "nonfinite", {3},
      std::vector<double>{std::bit_cast<double>(std::uint64_t{0x7FF8000000000123}),
                          std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}));
  const fs::path p = dir_ / "t.shtbl";
  auto w = shtool::test::try_write(t, p);
  ASSERT_TRUE(w.ok()) << w.error().message;
  TableFileInfo info;
  auto r = read_table(p, {}, &info);
  ASSERT_TRUE(r.ok()) << r.error().message;
  expect_same_table(t, r.value());
  EXPECT_EQ(info.encoding, TableEncoding::binary);
  EXPECT_EQ(info.file_size, fs::file_size(p));
  EXPECT_EQ(json::parse(info.header_json), table_header(t));
  auto d = r.value().get<double>("f64_specials");
  ASSERT_TRUE(d.ok());
  for (std::size_t i = 0; i < kSpecialDoubles.size(); ++i)
    EXPECT_EQ(bits_of(d.value()[i]), bits_of(kSpecialDoubles[i])) << "index " << i << " value " << kSpecialDoubles[i];
}

TEST_F(TableTest, JsonRoundTripExactBits) {
  const Table t = make_table();
  const fs::path p = written("t.json", TableEncoding::json);
  TableFileInfo info;
  auto r = read_table(p, {}, &info);
  ASSERT_TRUE(r.ok()) << r.error().message;
  expect_same_table(t, r.value());
  EXPECT_EQ(info.encoding, TableEncoding::json);
  // Same header as the binary encoding (the CRCs are those of the binary bytes).
  EXPECT_EQ(json::parse(info.header_json), table_header(t));

  // The document read by a plain JSON parser holds the numbers themselves.
  const json doc = json::parse(read_file(p));
  const json& d = doc.at("data").at("f64_specials");
  ASSERT_EQ(d.size(), kSpecialDoubles.size());
  for (std::size_t i = 0; i < kSpecialDoubles.size(); ++i)
    EXPECT_EQ(bits_of(d[i].get<double>()), bits_of(kSpecialDoubles[i])) << "index " << i << " text " << d[i].dump();
  const json& f = doc.at("data").at("f32_specials");
  for (std::size_t i = 0; i < kSpecialFloats.size(); ++i)
    EXPECT_EQ(bits_of(static_cast<float>(f[i].get<double>())), bits_of(kSpecialFloats[i])) << "text " << f[i].dump();
  EXPECT_EQ(doc["data"]["u64"][1].get<std::uint64_t>(), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(doc["data"]["i64"][0].get<std::int64_t>(), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(doc["data"]["scalar"].dump(), "[-0.0]");
}

TEST_F(TableTest, EncodingsConvertIntoEachOther) {
  // binary -> load -> json -> load -> binary gives the original bytes.
  const fs::path b1 = written("a.shtbl");
  auto t1 = read_table(b1);
  ASSERT_TRUE(t1.ok()) << t1.error().message;
  ASSERT_TRUE(shtool::test::try_write(t1.value(), dir_ / "b.json", TableEncoding::json).ok());
  auto t2 = read_table(dir_ / "b.json");
  ASSERT_TRUE(t2.ok()) << t2.error().message;
  ASSERT_TRUE(shtool::test::try_write(t2.value(), dir_ / "c.shtbl").ok());
  EXPECT_EQ(read_file(b1), read_file(dir_ / "c.shtbl"));
}

TEST_F(TableTest, DeterministicBytes) {
  for (TableEncoding enc : {TableEncoding::binary, TableEncoding::json}) {
    const fs::path a = written("a", enc), b = written("b", enc);
    EXPECT_EQ(read_file(a), read_file(b));
    // Insertion order of meta and generator keys does not matter: keys are sorted.
    Table t = make_table();
    json meta = json::object();
    meta["max_error"] = 1.5e-17;
    meta["note"] = "round trip";
    t.meta = meta.dump();
    ASSERT_TRUE(shtool::test::try_write(t, dir_ / "c", enc).ok());
    EXPECT_EQ(read_file(a), read_file(dir_ / "c"));
  }
  // Content does matter (guards against the comparison above being vacuous).
  Table t = make_table();
  json meta = table_meta(t);
  meta["note"] = "other";
  t.meta = meta.dump();
  ASSERT_TRUE(shtool::test::try_write(t, dir_ / "d").ok());
  EXPECT_NE(read_file(dir_ / "a"), read_file(dir_ / "d"));
}

TEST_F(TableTest, EmptyTableRoundTrips) {
  Table t;
  t.kind = "nothing";
  t.generator = json{{"tool", "shtool"}, {"version", "0"}, {"command", "x"}, {"parameters", json::object()}}.dump();
  for (TableEncoding enc : {TableEncoding::binary, TableEncoding::json}) {
    const fs::path p = dir_ / (enc == TableEncoding::binary ? "e.shtbl" : "e.json");
    auto w = shtool::test::try_write(t, p, enc);
    ASSERT_TRUE(w.ok()) << w.error().message;
    auto r = read_table(p);
    ASSERT_TRUE(r.ok()) << r.error().message;
    expect_same_table(t, r.value());
  }
}

// The layout of docs/table-format.md, checked with an independent parser.
TEST_F(TableTest, BinaryLayoutMatchesDocs) {
  const Table t = make_table();
  const std::string file = read_file(written());
  ASSERT_GE(file.size(), 24u);
  EXPECT_EQ(file.substr(0, 8), std::string("\x89SHT\r\n\x1a\n", 8));
  const std::uint64_t len = get_u64_le(file, 8);
  const std::string header_text = file.substr(24, len);
  EXPECT_EQ(get_u32_le(file, 16), crc_bitwise(header_text));
  EXPECT_EQ(get_u32_le(file, 20), 0u);
  const json h = json::parse(header_text);
  EXPECT_EQ(h["format"], "shtool-table");
  EXPECT_EQ(h["format_version"], std::to_string(kTableFormatMajor) + "." + std::to_string(kTableFormatMinor));
  EXPECT_EQ(h["conventions"], std::string(kConventionsId));
  EXPECT_EQ(h["kind"], "test-kind");
  EXPECT_EQ(h["kind_version"], "1.2");
  EXPECT_EQ(h["order"], 3);
  EXPECT_EQ(h["generator"]["parameters"]["seed"], 42);
  const std::uint64_t data_start = (24 + len + 63) / 64 * 64;
  for (std::size_t i = 24 + len; i < data_start; ++i) EXPECT_EQ(file[i], '\0') << "header padding at " << i;
  ASSERT_EQ(h["arrays"].size(), t.arrays.size());
  std::uint64_t end = 0;
  for (std::size_t i = 0; i < t.arrays.size(); ++i) {
    const json& a = h["arrays"][i];
    const std::uint64_t off = a["offset"], n = a["nbytes"];
    EXPECT_EQ(a["name"], t.arrays[i].name);
    EXPECT_EQ(a["dtype"], std::string(dtype_name(t.arrays[i].dtype)));
    EXPECT_EQ(a["shape"], json(t.arrays[i].shape));
    EXPECT_EQ(off % 64, 0u) << t.arrays[i].name;
    EXPECT_EQ((data_start + off) % 64, 0u) << "absolute alignment of " << t.arrays[i].name;
    const std::string bytes = file.substr(data_start + off, n);
    EXPECT_EQ(a["crc32"].get<std::uint32_t>(), crc_bitwise(bytes)) << t.arrays[i].name;
    EXPECT_EQ(bytes, std::string(reinterpret_cast<const char*>(t.arrays[i].data.data()), t.arrays[i].data.size()));
    end = off + n;
  }
  EXPECT_EQ(file.size(), data_start + end);
  // Little-endian on disk, whatever the host: first f64 value is 0.0, the second -0.0.
  const std::uint64_t off1 = h["arrays"][0]["offset"];
  EXPECT_EQ(get_u64_le(file, data_start + off1 + 8), 0x8000000000000000u);
  const std::uint64_t off_i32 = h["arrays"][2]["offset"];
  EXPECT_EQ(get_u32_le(file, data_start + off_i32), 0x80000000u);  // INT32_MIN
}

// ---------------------------------------------------------------------------
// Corruption: every case is rejected with a message naming the file and the problem.

TEST_F(TableTest, RejectsBadMagic) {
  const std::string good = read_file(written());
  std::string s = good;
  s[0] = '\x88';
  expect_rejected(s, {"bad magic", "0x88"});
  s = good;
  s[2] ^= 0x01;
  expect_rejected(s, {"bad magic bytes", "89 53 49 54"});
  // What a CRLF -> LF text-mode transfer does to the magic.
  s = good;
  s.erase(4, 1);
  expect_rejected(s, {"bad magic", "text-mode"});
  expect_rejected("hello, world", {"bad magic", "0x68"});
  expect_rejected("", {"empty file"});
}

TEST_F(TableTest, RejectsUnknownMajorVersionAcceptsNewerMinor) {
  const std::string good = read_file(written());
  json h = json::parse(split_binary(good).header_text);
  h["format_version"] = std::to_string(kTableFormatMajor + 1) + ".0";
  expect_rejected(with_header(good, h), {"unsupported table format version 2.0"});
  h["format_version"] = "1.x";
  expect_rejected(with_header(good, h), {"format_version", "1.x"});
  // A newer minor version may add fields; this reader ignores them (docs: versioning).
  h["format_version"] = std::to_string(kTableFormatMajor) + ".7";
  h["added_in_1_7"] = {{"anything", true}};
  h["arrays"][0]["also_new"] = 1;
  const fs::path p = dir_ / "minor.shtbl";
  write_file(p, with_header(good, h));
  TableFileInfo info;
  auto r = read_table(p, {}, &info);
  ASSERT_TRUE(r.ok()) << r.error().message;
  expect_same_table(make_table(), r.value());
  EXPECT_TRUE(json::parse(info.header_json).contains("added_in_1_7"));
}

TEST_F(TableTest, RejectsHeaderCrcMismatch) {
  std::string s = read_file(written());
  const std::size_t at = 24 + 10;  // inside the header JSON
  s[at] = static_cast<char>(s[at] ^ 0x20);
  expect_rejected(s, {"header CRC-32 mismatch"});
  s = read_file(dir_ / "t.shtbl");
  s[17] ^= 0x01;  // the stored CRC itself
  expect_rejected(s, {"header CRC-32 mismatch"});
}

TEST_F(TableTest, RejectsBadHeaderContent) {
  const std::string good = read_file(written());
  const std::string data = split_binary(good).data;
  const json h0 = json::parse(split_binary(good).header_text);

  expect_rejected(rebuild_binary("{\"format\": ", data), {"malformed header JSON"});
  expect_rejected(rebuild_binary("[1, 2]", data), {"not a JSON object"});
  for (const char* field : {"kind", "kind_version", "order", "conventions", "generator", "meta", "arrays"}) {
    json h = h0;
    h.erase(field);
    expect_rejected(with_header(good, h), {std::string("'") + field + "'"});
  }
  json h = h0;
  h["format"] = "png";
  expect_rejected(with_header(good, h), {"not a shtool table"});
  h = h0;
  h["conventions"] = "other-conventions";
  expect_rejected(with_header(good, h), {"conventions 'other-conventions'"});
  h = h0;
  h["order"] = -1;
  expect_rejected(with_header(good, h), {"'order'"});
  h = h0;
  h["generator"].erase("parameters");
  expect_rejected(with_header(good, h), {"'parameters'"});
  h = h0;
  h["arrays"][1]["dtype"] = "f16";
  expect_rejected(with_header(good, h), {"array 'f32_specials' has unknown dtype 'f16'"});
  h = h0;
  h["arrays"][0]["shape"] = {2, 7};
  expect_rejected(with_header(good, h), {"array 'f64_specials'", "needs 112 bytes", "nbytes = 128"});
  h = h0;
  h["arrays"][0]["shape"] = {2, -8};
  expect_rejected(with_header(good, h), {"shape entry"});
  h = h0;
  h["arrays"][0]["nbytes"] = 136;
  expect_rejected(with_header(good, h), {"needs 128 bytes"});
  h = h0;
  h["arrays"][1]["name"] = "f64_specials";
  expect_rejected(with_header(good, h), {"two arrays are named 'f64_specials'"});
  h = h0;
  h["arrays"][1]["offset"] = 130;
  expect_rejected(with_header(good, h), {"not a multiple of 64"});
  h = h0;
  h["arrays"][1]["offset"] = 64;  // inside the first array's 128 bytes
  expect_rejected(with_header(good, h), {"overlaps"});
  h = h0;
  h["arrays"][1]["crc32"] = 4294967296ull;
  expect_rejected(with_header(good, h), {"crc32"});
  h = h0;
  h["arrays"][0]["offset"] = "0";
  expect_rejected(with_header(good, h), {"offset, nbytes and crc32"});
}

TEST_F(TableTest, RejectsTruncationAnywhere) {
  const std::string good = read_file(written());
  const std::uint64_t len = get_u64_le(good, 8);
  const std::uint64_t data_start = (24 + len + 63) / 64 * 64;
  const std::size_t cuts[] = {3, 8, 16, 23, 24, 25, static_cast<std::size_t>(24 + len / 2),
                              static_cast<std::size_t>(24 + len), static_cast<std::size_t>(data_start),
                              static_cast<std::size_t>(data_start + 100), good.size() - 1};
  for (std::size_t n : cuts) {
    SCOPED_TRACE("cut at " + std::to_string(n) + " of " + std::to_string(good.size()));
    expect_rejected(good.substr(0, n), {"truncated"});
  }
  // The message names the array that does not fit.
  // f64_specials fills data bytes [0, 128), f32_specials [128, 176).
  expect_rejected(good.substr(0, data_start + 150), {"truncated: array 'f32_specials'"});
  expect_rejected(good + std::string(5, '\0'), {"5 unexpected bytes"});
}

TEST_F(TableTest, RejectsHugeSizesWithoutAllocating) {
  const std::string good = read_file(written());
  std::string s = good;
  put_le(s, 8, std::uint64_t{1} << 62, 8);  // header length of 4 EiB
  expect_rejected(s, {"truncated", "header length 4611686018427387904"});
  put_le(s, 8, std::numeric_limits<std::uint64_t>::max(), 8);
  expect_rejected(s, {"truncated"});
  // Shapes whose byte size overflows 64 bits, with a valid header CRC.
  json h = json::parse(split_binary(good).header_text);
  h["arrays"][0]["shape"] = {std::uint64_t{1} << 40, std::uint64_t{1} << 40};
  expect_rejected(with_header(good, h), {"too large"});
  h["arrays"][0]["shape"] = {std::uint64_t{1} << 59};
  h["arrays"][0]["nbytes"] = std::uint64_t{1} << 62;
  expect_rejected(with_header(good, h), {"too large"});
  // A consistent but huge array: the file-size check fires before any allocation.
  h = json::parse(split_binary(good).header_text);
  json& last = h["arrays"].back();
  last["shape"] = json::array({std::uint64_t{1} << 55});
  last["nbytes"] = std::uint64_t{1} << 58;
  expect_rejected(with_header(good, h), {"truncated: array 'scalar'"});
  std::string r = good;
  put_le(r, 20, 7, 4);
  expect_rejected(r, {"reserved prefix field"});
}

TEST_F(TableTest, RejectsArrayAndPaddingCorruption) {
  const std::string good = read_file(written());
  const std::uint64_t len = get_u64_le(good, 8);
  const std::uint64_t data_start = (24 + len + 63) / 64 * 64;
  const json h = json::parse(split_binary(good).header_text);
  for (std::size_t i = 0; i < h["arrays"].size(); ++i) {
    const std::uint64_t off = h["arrays"][i]["offset"], n = h["arrays"][i]["nbytes"];
    if (n == 0) continue;
    std::string s = good;
    s[data_start + off + n / 2] ^= 0x04;
    const std::string name = h["arrays"][i]["name"];
    expect_rejected(s, {"CRC-32 mismatch in array '" + name + "'"});
  }
  // Padding between arrays and after the header carries no CRC but must stay zero.
  std::string s = good;
  const std::uint64_t f32_end = h["arrays"][1]["offset"].get<std::uint64_t>() + h["arrays"][1]["nbytes"].get<std::uint64_t>();
  const std::uint64_t i32_off = h["arrays"][2]["offset"];
  ASSERT_LT(f32_end, i32_off);
  s[data_start + f32_end] = 1;
  expect_rejected(s, {"padding byte at file offset " + std::to_string(data_start + f32_end)});
  if (24 + len < data_start) {
    s = good;
    s[24 + len] = ' ';
    expect_rejected(s, {"padding byte"});
  }
}

// Every byte of a binary table is covered by the magic, a CRC, a size check or the
// zero-padding check, so any single flipped bit or cut must be caught (and nothing may
// crash along the way).
TEST_F(TableTest, EveryByteFlipAndEveryCutIsRejected) {
  const std::string good = read_file(written());
  const fs::path p = dir_ / "x.shtbl";
  write_file(p, good);
  // Bytes are patched in place and cuts go to fresh files: truncating an existing file
  // costs milliseconds on some file systems, which would make this test slow.
  auto patch = [&](std::size_t at, char c) {
    std::fstream f(p, std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(static_cast<std::streamoff>(at));
    f.write(&c, 1);
  };
  std::size_t accepted_flips = 0, accepted_cuts = 0;
  for (std::size_t i = 0; i < good.size(); ++i) {
    for (unsigned char mask : {0x01, 0x80}) {
      patch(i, static_cast<char>(good[i] ^ mask));
      if (read_table(p).ok()) {
        ++accepted_flips;
        ADD_FAILURE() << "flip of bit mask " << int(mask) << " at byte " << i << " accepted";
      }
      patch(i, good[i]);
    }
    const fs::path cut = dir_ / ("cut" + std::to_string(i));
    write_file(cut, good.substr(0, i));
    if (read_table(cut).ok()) {
      ++accepted_cuts;
      ADD_FAILURE() << "cut at " << i << " of " << good.size() << " accepted";
    }
    fs::remove(cut);
  }
  EXPECT_EQ(accepted_flips, 0u);
  EXPECT_EQ(accepted_cuts, 0u);
  ASSERT_TRUE(read_table(p).ok()) << "the restored file must load (else the loop proved nothing)";
}

TEST_F(TableTest, ChecksExpectation) {
  const fs::path p = written();
  EXPECT_TRUE(read_table(p, {"test-kind", 1, 3}).ok());
  const std::string good = read_file(p);
  expect_rejected(good, {"table kind is 'test-kind', expected 'rotation-helpers'"}, {"rotation-helpers", 0, 0});
  expect_rejected(good, {"version 1.2", "major version 2"}, {"test-kind", 2, 0});
  expect_rejected(good, {"order 3, expected order 4"}, {"", 0, 4});
  // Same checks on the JSON encoding.
  const std::string js = read_file(written("t.json", TableEncoding::json));
  expect_rejected(js, {"expected order 5"}, {"", 0, 5});
}

TEST_F(TableTest, RejectsCorruptJsonTables) {
  const std::string good = read_file(written("t.json", TableEncoding::json));
  const json doc = json::parse(good);
  auto variant = [&](auto edit) {
    json d = doc;
    edit(d);
    return d.dump();
  };
  expect_rejected(good.substr(0, good.size() / 2), {"malformed JSON table"});
  // An edited or rounded value: the header CRC is of the binary bytes of the values.
  expect_rejected(variant([](json& d) { d["data"]["f64_specials"][4] = 0.333333333333333; }),
                  {"CRC-32 mismatch in array 'f64_specials'"});
  expect_rejected(variant([](json& d) { d["data"]["f32_specials"][3] = 0.2; }),
                  {"CRC-32 mismatch in array 'f32_specials'"});
  expect_rejected(variant([](json& d) { d["data"]["u8"].erase(0); }), {"has 4 values", "needs 5"});
  expect_rejected(variant([](json& d) { d["data"]["u8"][0] = 256; }), {"element 0", "out of range for u8"});
  expect_rejected(variant([](json& d) { d["data"]["i32"][0] = 1.5; }), {"element 0 is not an integer"});
  expect_rejected(variant([](json& d) { d["data"]["f64_specials"][0] = "zero"; }), {"is not a number"});
  expect_rejected(variant([](json& d) { d["data"]["f32_specials"][0] = 1e300; }), {"out of range for f32"});
  expect_rejected(variant([](json& d) { d["data"]["extra"] = {1}; }), {"'extra' that the header does not list"});
  expect_rejected(variant([](json& d) { d["data"].erase("u64"); }), {"no list for array 'u64'"});
  expect_rejected(variant([](json& d) { d.erase("data"); }), {"no \"data\" object"});
  expect_rejected(variant([](json& d) { d["format_version"] = "3.1"; }), {"unsupported table format version 3.1"});
}

// ---------------------------------------------------------------------------
// Writer checks and atomic writes.

TEST_F(TableTest, WriterRejectsInvalidTables) {
  // make_table() changed by `edit` must be refused with a message naming `needle`, and
  // leave nothing behind.
  auto expect_write_error = [&](const std::function<void(Table&)>& edit, const std::string& needle,
                                TableEncoding enc = TableEncoding::binary) {
    Table t = make_table();
    edit(t);
    const fs::path p = dir_ / "w.shtbl";
    auto r = shtool::test::try_write(t, p, enc);
    ASSERT_FALSE(r.ok()) << "invalid table written; expected '" << needle << "'";
    EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
    EXPECT_EQ(r.error().message.rfind(p.string(), 0), 0u) << r.error().message;
    EXPECT_FALSE(fs::exists(p));
  };
  expect_write_error([](Table& t) { t.kind = ""; }, "table kind ''");
  expect_write_error([](Table& t) { t.kind = "Bad Kind"; }, "table kind 'Bad Kind'");
  expect_write_error([](Table& t) { t.kind_version = "1"; }, "kind_version '1'");
  expect_write_error([](Table& t) { t.generator = "{}"; }, "'generator' needs a string field 'tool'");
  expect_write_error([](Table& t) { t.arrays.push_back(t.arrays[0]); }, "two arrays are named 'f64_specials'");
  expect_write_error(
      [](Table& t) {
        t.arrays[0].shape = {3, 8};
      },
      "array 'f64_specials' has 128 bytes but shape [3, 8] of f64 needs 192");
  expect_write_error([](Table& t) { t.arrays[0].shape = {-2, -8}; }, "invalid shape");
  // Not UTF-8: not JSON text.
  expect_write_error([](Table& t) { t.meta = std::string("{\"bad\": \"\xff\xfe\"}"); }, "cannot write table");
  expect_write_error(
      [](Table& t) { t.arrays.push_back(TableArray::from<float>("nan", {1}, std::vector<float>{std::nanf("")})); },
      "array 'nan' element 0 is not finite", TableEncoding::json);
}

TEST_F(TableTest, AtomicWriteLeavesNothingBehind) {
  // Into a folder that does not exist: a clean error, nothing created.
  const fs::path missing = dir_ / "no" / "such" / "dir" / "t.shtbl";
  auto r = shtool::test::try_write(make_table(), missing);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("does not exist"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find(missing.string()), std::string::npos) << r.error().message;
  EXPECT_FALSE(fs::exists(dir_ / "no"));

  // A successful write leaves exactly the table (no temporary file).
  const fs::path p = written();
  const std::string before = read_file(p);
  auto listing = [&] {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  };
  EXPECT_EQ(listing(), std::vector<std::string>{"t.shtbl"});

  // Failed writes do not clobber an existing table.
  Table bad = make_table();
  bad.arrays[0].data.pop_back();
  EXPECT_FALSE(shtool::test::try_write(bad, p).ok());
  Table nan = make_table();
  nan.arrays[0] = TableArray::from<double>("x", {1}, std::vector<double>{NAN});
  EXPECT_FALSE(shtool::test::try_write(nan, p, TableEncoding::json).ok());
  EXPECT_EQ(read_file(p), before);

  // A folder at the target is refused before anything is written (common/atomic_file.h;
  // test_atomic_file covers failures after the temporary file exists).
  fs::create_directories(dir_ / "occupied" / "child");
  auto r2 = shtool::test::try_write(make_table(), dir_ / "occupied");
  ASSERT_FALSE(r2.ok());
  EXPECT_NE(r2.error().message.find("is a folder"), std::string::npos) << r2.error().message;
  EXPECT_EQ(listing(), (std::vector<std::string>{"occupied", "t.shtbl"}));
  EXPECT_TRUE(fs::is_directory(dir_ / "occupied" / "child"));

  // Overwriting with a new table replaces it whole.
  Table other = make_table();
  other.order = 7;
  ASSERT_TRUE(shtool::test::try_write(other, p).ok());
  auto back = read_table(p);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value().order, 7);
  EXPECT_EQ(listing(), (std::vector<std::string>{"occupied", "t.shtbl"}));
}

TEST_F(TableTest, ReadErrorsForMissingOrOddFiles) {
  auto r = read_table(dir_ / "absent.shtbl");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("absent.shtbl: cannot open"), std::string::npos) << r.error().message;
  auto d = read_table(dir_);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.error().message.find("not a regular file"), std::string::npos) << d.error().message;
}

// ---------------------------------------------------------------------------
// JSON Schemas (checked with Debian's python3-jsonschema).

class SchemaTest : public TableTest {
 protected:
  // One Python run for many instances (each run costs about half a second).
  RunResult validate(const std::string& schema, const std::vector<fs::path>& instances) {
    std::string cmd = kPython + " " + q(kSource + "/tests/validate_json_schema.py") + " " + q(kSource + "/schemas/" + schema);
    for (const fs::path& p : instances) cmd += " " + q(p);
    return run(cmd, dir_);
  }
  // Each invalid instance must be reported, on a line naming it, with `needle` in it.
  void expect_each_invalid(const std::string& schema, const std::vector<std::pair<std::string, std::string>>& cases) {
    std::vector<fs::path> files;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      files.push_back(dir_ / ("bad" + std::to_string(i) + ".json"));
      write_file(files.back(), cases[i].first);
    }
    const RunResult r = validate(schema, files);
    EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const std::string prefix = files[i].string() + ": ";
      bool found = false;
      for (std::size_t at = r.out.find(prefix); at != std::string::npos && !found; at = r.out.find(prefix, at + 1)) {
        const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
        found = line.find(cases[i].second) != std::string::npos;
      }
      EXPECT_TRUE(found) << "schema " << schema << " did not reject " << cases[i].first << " with '"
                         << cases[i].second << "':\n" << r.out << r.err;
    }
  }
};

TEST_F(SchemaTest, TableHeadersValidate) {
  const fs::path bin = written("t.shtbl");
  const fs::path js = written("t.json", TableEncoding::json);
  Table empty;
  empty.kind = "nothing";
  empty.generator = json{{"tool", "shtool"}, {"version", "0"}, {"command", "x"}, {"parameters", json::object()}}.dump();
  ASSERT_TRUE(shtool::test::try_write(empty, dir_ / "e.shtbl").ok());
  const RunResult r = validate("table-header.schema.json", {bin, js, dir_ / "e.shtbl"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  // The schema is not vacuous: broken headers fail it, each for its reason.
  const json h = table_header(make_table());
  auto edited = [&](auto edit) {
    json b = h;
    edit(b);
    return b.dump();
  };
  expect_each_invalid("table-header.schema.json",
                      {{edited([](json& b) { b["arrays"][0]["dtype"] = "f16"; }), "arrays/0/dtype"},
                       {edited([](json& b) { b.erase("conventions"); }), "conventions"},
                       {edited([](json& b) { b["conventions"] = "other"; }), "conventions"},
                       {edited([](json& b) { b["format_version"] = "2.0"; }), "format_version"},
                       {edited([](json& b) { b["arrays"][1]["offset"] = 100; }), "arrays/1/offset"},
                       {edited([](json& b) { b["arrays"][1]["shape"] = {-1}; }), "arrays/1/shape/0"},
                       {edited([](json& b) { b["timestamp"] = "2024-01-01"; }), "timestamp"},
                       {edited([](json& b) { b["generator"].erase("parameters"); }), "generator"},
                       {edited([](json& b) { b["data"] = {{"x", {"one"}}}; }), "data/x/0"}});
}

TEST_F(SchemaTest, KindSchemaPatternWorks) {
  // The documented pattern for a kind: allOf [$ref to the generic header] + constraints.
  fs::create_directories(dir_ / "schemas");
  fs::copy_file(kSource + "/schemas/table-header.schema.json", dir_ / "schemas" / "table-header.schema.json");
  write_file(dir_ / "schemas" / "test-kind.schema.json", R"({
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "allOf": [{"$ref": "table-header.schema.json"}],
    "properties": {"kind": {"const": "test-kind"}, "kind_version": {"pattern": "^1\\."},
                   "meta": {"required": ["max_error"]}}
  })");
  json bad_dtype = table_header(make_table());
  bad_dtype["arrays"][0]["dtype"] = "f16";  // caught through the $ref
  write_file(dir_ / "h1.json", bad_dtype.dump());
  json bad_meta = table_header(make_table());
  bad_meta["meta"].erase("max_error");  // caught by the kind's own constraint
  write_file(dir_ / "h2.json", bad_meta.dump());
  const std::string cmd = kPython + " " + q(kSource + "/tests/validate_json_schema.py") + " " +
                          q(dir_ / "schemas" / "test-kind.schema.json");
  RunResult r = run(cmd + " " + q(written()), dir_);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  r = run(cmd + " " + q(dir_ / "h1.json") + " " + q(dir_ / "h2.json"), dir_);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find((dir_ / "h1.json").string() + ": arrays/0/dtype"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find((dir_ / "h2.json").string() + ": meta"), std::string::npos) << r.out;
}

TEST_F(SchemaTest, EvalOutputValidates) {
  std::vector<fs::path> outputs;
  for (int order : {1, 3, 9}) {
    RunResult e = run(std::string(SHTOOL_EXE) + " eval --order " + std::to_string(order) + " --dir 0.3,-0.2,0.9", dir_);
    ASSERT_EQ(e.exit_code, 0) << e.err;
    outputs.push_back(dir_ / ("eval" + std::to_string(order) + ".json"));
    write_file(outputs.back(), e.out);
  }
  const RunResult r = validate("eval-output.schema.json", outputs);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  // Length tied to the order, no extra fields, order in range.
  expect_each_invalid("eval-output.schema.json",
                      {{R"({"order": 3, "values": [1, 2, 3, 4, 5, 6, 7, 8]})", "values"},
                       {R"({"order": 2, "values": [1, 2, 3, 4, 5]})", "values"},
                       {R"({"order": 1, "values": [0.28], "extra": 1})", "extra"},
                       {R"({"order": 1, "values": ["0.28"]})", "values/0"},
                       {R"({"order": 0, "values": []})", "order"}});
}

// ---------------------------------------------------------------------------
// The numpy reader of docs/table-format.md.

std::string doc_example(const std::string& text) {
  const std::string begin = "# --- begin doc example ---\n", end = "# --- end doc example ---";
  const auto a = text.find(begin), b = text.find(end);
  if (a == std::string::npos || b == std::string::npos || b < a) return {};
  return text.substr(a + begin.size(), b - a - begin.size());
}

TEST_F(TableTest, DocExampleIsTheTestedReader) {
  const std::string script = read_file(kSource + "/tests/read_table_numpy.py");
  const std::string doc = read_file(kSource + "/docs/table-format.md");
  const std::string example = doc_example(script);
  ASSERT_GT(example.size(), 200u) << "markers missing in tests/read_table_numpy.py";
  EXPECT_NE(doc.find("```python\n" + example + "```"), std::string::npos)
      << "docs/table-format.md does not contain the reader of tests/read_table_numpy.py verbatim:\n"
      << example;
}

TEST_F(TableTest, NumpyReaderReadsCppTable) {
  const Table t = make_table();
  const fs::path p = written();
  const RunResult r = run(kPython + " " + q(kSource + "/tests/read_table_numpy.py") + " " + q(p), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json out = json::parse(r.out);
  EXPECT_EQ(out["header"], table_header(t));
  const char* numpy_dtype[] = {"float64", "float32", "int32", "uint32", "int64", "uint64", "uint8"};
  for (const TableArray& a : t.arrays) {
    SCOPED_TRACE(a.name);
    const json& got = out["arrays"].at(a.name);
    EXPECT_EQ(got["dtype"], numpy_dtype[static_cast<int>(a.dtype)]);
    EXPECT_EQ(got["shape"], json(a.shape));
    const json& v = got["values"];
    ASSERT_EQ(v.size(), a.element_count());
    for (std::size_t i = 0; i < v.size(); ++i) {
      switch (a.dtype) {
        case DType::f64:
          EXPECT_EQ(bits_of(v[i].get<double>()), bits_of(a.values<double>()[i])) << i << " " << v[i].dump();
          break;
        case DType::f32:
          EXPECT_EQ(bits_of(static_cast<float>(v[i].get<double>())), bits_of(a.values<float>()[i]))
              << i << " " << v[i].dump();
          EXPECT_EQ(static_cast<double>(static_cast<float>(v[i].get<double>())), v[i].get<double>());
          break;
        case DType::i32: EXPECT_EQ(v[i].get<std::int64_t>(), a.values<std::int32_t>()[i]); break;
        case DType::u32: EXPECT_EQ(v[i].get<std::uint64_t>(), a.values<std::uint32_t>()[i]); break;
        case DType::i64: EXPECT_EQ(v[i].get<std::int64_t>(), a.values<std::int64_t>()[i]); break;
        case DType::u64: EXPECT_EQ(v[i].get<std::uint64_t>(), a.values<std::uint64_t>()[i]); break;
        case DType::u8: EXPECT_EQ(v[i].get<std::uint64_t>(), a.values<std::uint8_t>()[i]); break;
      }
    }
  }
  // The Python reader checks CRCs too: a flipped data byte makes it fail.
  std::string s = read_file(p);
  s[s.size() - 1] ^= 0x10;
  write_file(dir_ / "bad.shtbl", s);
  const RunResult bad = run(kPython + " " + q(kSource + "/tests/read_table_numpy.py") + " " + q(dir_ / "bad.shtbl"), dir_);
  EXPECT_EQ(bad.exit_code, 1) << bad.out;
  EXPECT_NE(bad.err.find("truncated or corrupted"), std::string::npos) << bad.err;
}

// ---------------------------------------------------------------------------
// shtool inspect, end to end.

TEST_F(TableTest, InspectGoodTable) {
  const fs::path p = written();
  RunResult r = run(std::string(SHTOOL_EXE) + " inspect " + q(p), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("kind: test-kind (version 1.2), order 3"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("i32  i32  shape [3]  min -2147483648  max 2147483647"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("checksums: OK"), std::string::npos) << r.out;

  r = run(std::string(SHTOOL_EXE) + " inspect --json " + q(p), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["checksums_ok"], true);
  EXPECT_EQ(j["header"], table_header(make_table()));
  EXPECT_EQ(j["summary"]["kind"], "test-kind");
  EXPECT_EQ(j["summary"]["order"], 3);
  EXPECT_EQ(j["summary"]["encoding"], "binary");
  const json& arrays = j["summary"]["arrays"];
  ASSERT_EQ(arrays.size(), make_table().arrays.size());
  // min/max against the inputs themselves.
  const json& f64 = arrays[0];
  EXPECT_EQ(f64["name"], "f64_specials");
  EXPECT_EQ(f64["min"].get<double>(), std::numeric_limits<double>::lowest());
  EXPECT_EQ(f64["max"].get<double>(), std::numeric_limits<double>::max());
  EXPECT_EQ(f64["nonfinite"], 0);
  EXPECT_EQ(arrays[1]["min"].get<double>(), static_cast<double>(std::numeric_limits<float>::lowest()));
  EXPECT_EQ(arrays[5]["max"].get<std::uint64_t>(), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(arrays[6]["max"], 255);
  EXPECT_TRUE(arrays[7]["min"].is_null());  // empty array
  EXPECT_EQ(arrays[7]["elements"], 0);

  // The JSON encoding inspects the same.
  const fs::path pj = written("t.json", TableEncoding::json);
  r = run(std::string(SHTOOL_EXE) + " inspect --json " + q(pj), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json jj = json::parse(r.out);
  EXPECT_EQ(jj["summary"]["encoding"], "json");
  EXPECT_EQ(jj["summary"]["arrays"], arrays);
  // Only a binary header carries a checksum; the text says which was verified.
  EXPECT_EQ(j["header_checksummed"], true);
  EXPECT_EQ(jj["header_checksummed"], false);
  r = run(std::string(SHTOOL_EXE) + " inspect " + q(pj), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("a JSON table's header has no checksum"), std::string::npos) << r.out;
}

TEST_F(TableTest, InspectRejectsCorruptTable) {
  std::string s = read_file(written());
  s[s.size() - 3] ^= 0x01;  // last array ("scalar")
  write_file(dir_ / "bad.shtbl", s);
  for (const char* flag : {"", " --json"}) {
    const RunResult r = run(std::string(SHTOOL_EXE) + " inspect" + flag + " " + q(dir_ / "bad.shtbl"), dir_);
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err.rfind("shtool: error: " + (dir_ / "bad.shtbl").string() + ": CRC-32 mismatch in array 'scalar'", 0), 0u)
        << r.err;
  }
  const RunResult missing = run(std::string(SHTOOL_EXE) + " inspect " + q(dir_ / "absent"), dir_);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("shtool: error: "), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("cannot open"), std::string::npos) << missing.err;
}

}  // namespace
