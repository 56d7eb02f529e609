// Versioned, self-describing tables: the one format every shtool job writes and the
// runtime loads. The byte layout, header fields and versioning policy are documented in
// docs/table-format.md; the header schemas are in schemas/.
//
// Two encodings of the same content:
//   binary  - 8-byte magic, header length, header CRC, JSON header, then little-endian
//             arrays at 64-byte-aligned offsets, each with its own CRC-32 (the default;
//             exact bits of every value);
//   json    - one JSON document: the identical header plus "data" with every array as a
//             flat list of JSON numbers written with round-trip precision (small tables,
//             people). The CRCs in its header are those of the binary bytes, and the
//             loader checks them against the parsed numbers.
// The loader detects the encoding from the first byte (0x89 binary, '{' JSON).
//
// Nothing here throws; errors come back as Result. This is the header an engine includes
// to load tables: JSON is parsed inside the library, never in a header.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "shtool/result.h"

namespace shtool {

// Format of the container itself (magic, header fields, array layout). A minor bump
// only adds optional header fields older readers may ignore; a major bump changes
// something an older reader would misread, and the loader rejects unknown majors.
inline constexpr int kTableFormatMajor = 1;
inline constexpr int kTableFormatMinor = 0;
// Identifier of the conventions of docs/conventions.md, stored in every header. The
// loader rejects tables made under other conventions.
inline constexpr std::string_view kConventionsId = "shtool-sh-v1";
// Value of the header's "format" field; identifies the JSON encoding.
inline constexpr std::string_view kTableFormatName = "shtool-table";
// First 8 bytes of a binary table, PNG-style: 0x89 (a non-ASCII byte: catches 7-bit
// transfers), "SHT", CR LF (catches CRLF -> LF), 0x1A (stops `type` on DOS), LF
// (catches LF -> CRLF).
inline constexpr unsigned char kTableMagic[8] = {0x89, 'S', 'H', 'T', '\r', '\n', 0x1A, '\n'};
// Magic (8) + header length (u64) + header CRC (u32) + reserved (u32).
inline constexpr std::size_t kTablePrefixSize = 24;
// Alignment of the data section and of every array in it (a cache line; enough for
// any SIMD load).
inline constexpr std::size_t kTableAlignment = 64;

enum class DType { f64, f32, i32, u32, i64, u64, u8 };
std::string_view dtype_name(DType type);  // "f64", "f32", "i32", "u32", "i64", "u64", "u8"
std::size_t dtype_size(DType type);
std::optional<DType> dtype_from_name(std::string_view name);

template <class T>
constexpr DType dtype_of() {
  if constexpr (std::is_same_v<T, double>) return DType::f64;
  else if constexpr (std::is_same_v<T, float>) return DType::f32;
  else if constexpr (std::is_same_v<T, std::int32_t>) return DType::i32;
  else if constexpr (std::is_same_v<T, std::uint32_t>) return DType::u32;
  else if constexpr (std::is_same_v<T, std::int64_t>) return DType::i64;
  else if constexpr (std::is_same_v<T, std::uint64_t>) return DType::u64;
  else if constexpr (std::is_same_v<T, std::uint8_t>) return DType::u8;
  else static_assert(!sizeof(T), "unsupported table element type");
}

// CRC-32 as zlib computes it (reflected polynomial 0xEDB88320, init and final xor
// 0xFFFFFFFF), so Python's zlib.crc32 checks a table. `crc` continues a running value.
std::uint32_t table_crc32(std::span<const std::byte> bytes, std::uint32_t crc = 0);

// One named n-dimensional array, row-major, stored as little-endian bytes.
// shape {} is a scalar (one element), a 0 anywhere in the shape an empty array.
struct TableArray {
  std::string name;
  DType dtype = DType::f64;
  std::vector<std::int64_t> shape;
  std::vector<std::byte> data;

  // Product of the shape. Precondition: dims >= 0 and no overflow (the loader and the
  // writer check this before anything calls it).
  std::size_t element_count() const;

  // The writer checks that the shape matches the number of values.
  template <class T>
  static TableArray from(std::string name, std::vector<std::int64_t> shape,
                         std::span<const T> values);
  template <class T>
  static TableArray from(std::string name, std::vector<std::int64_t> shape,
                         const std::vector<T>& values) {
    return from<T>(std::move(name), std::move(shape), std::span<const T>(values));
  }
  // Copies the values out. Precondition: dtype == dtype_of<T>() (otherwise the result is
  // empty); Table::get checks this and reports a clear error instead.
  template <class T>
  std::vector<T> values() const;
};

struct Table {
  std::string kind;                  // e.g. "rotation-helpers"; schemas/<kind>.schema.json
  std::string kind_version = "1.0";  // version of that kind's layout, "major.minor"
  int order = 0;                     // SH order N the table is for (0: not order-specific)
  // How it was made, as compact JSON text: {"tool": "shtool", "version": ..., "command":
  // ..., "parameters": {...}} (seed included in parameters when there is one). No
  // timestamps or hostnames: the same inputs must give byte-identical tables. Required
  // by the writer.
  std::string generator = "{}";
  std::string meta = "{}";  // kind-specific summary values, compact JSON text
  std::vector<TableArray> arrays;

  const TableArray* find(std::string_view name) const;
  // Values of array `name`, or an error if it is missing or has another dtype.
  template <class T>
  auto get(std::string_view name) const;
};

enum class TableEncoding { binary, json };

// What a loader expects; empty fields are not checked.
struct TableExpectation {
  std::string kind;    // empty: any
  int kind_major = 0;  // 0: any; otherwise the kind's schema major version must match
  int order = 0;       // 0: any
};

// Facts about the file a table was read from (for `shtool inspect`).
struct TableFileInfo {
  TableEncoding encoding = TableEncoding::binary;
  std::uint64_t file_size = 0;
  // The header exactly as stored, as compact JSON text (JSON encoding: the document
  // without "data"), including any fields a newer minor version added that Table does
  // not carry.
  std::string header_json;
};

// Reads and validates: magic, format major version, header CRC, header fields and
// conventions id, the expectation (kind, kind major, order), array bounds, padding, array
// CRCs. Never throws, never returns partial data. Memory: the file read whole, its arrays
// copied out (about twice a binary file's size), plus the parsed JSON of its header (of
// the whole document for the JSON encoding), which takes up to about 30 bytes for each
// byte of JSON text: a binary table's header of a few kilobytes costs nothing, a 10 MB
// JSON table about 250 MB (the header is capped at 64 MiB).
// (The writer is offline: `shtool` writes tables, engines read them.)
Result<Table> read_table(const std::filesystem::path& path, const TableExpectation& expect = {},
                         TableFileInfo* info = nullptr);

// How read_table_bytes checks what it reads.
struct TableReadOptions {
  // CRC-32s of the header and of every array. Off only for tests and fuzzers that must
  // reach the kind validators with arbitrary bytes; every other check stays.
  bool verify_checksums = true;
};

// read_table for bytes already in memory (an asset archive, a network buffer); `name`
// stands for the path in messages. Same guarantees: never throws, never returns partial
// data, memory as read_table's.
Result<Table> read_table_bytes(std::span<const std::byte> bytes, std::string_view name,
                               const TableExpectation& expect = {}, TableFileInfo* info = nullptr,
                               const TableReadOptions& options = {});

// Where a shipped table named `file_name` (e.g. "rotation-helpers.shtb") is looked for
// when no path is given: the folder named by the environment variable SHTOOL_TABLES, then
// <prefix>/share/shtool/tables as `cmake --install` lays it out. Returns the first path
// that exists, or an empty path.
std::filesystem::path find_shipped_table(std::string_view file_name);

// ---------------------------------------------------------------------------
// Template definitions.

namespace table_detail {
template <class T>
void store_le(const T& value, std::byte* out) {
  std::memcpy(out, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(out[i], out[sizeof(T) - 1 - i]);
}
template <class T>
T load_le(const std::byte* in) {
  std::byte tmp[sizeof(T)];
  std::memcpy(tmp, in, sizeof(T));
  if constexpr (std::endian::native == std::endian::big)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(tmp[i], tmp[sizeof(T) - 1 - i]);
  T value;
  std::memcpy(&value, tmp, sizeof(T));
  return value;
}
}  // namespace table_detail

template <class T>
TableArray TableArray::from(std::string name, std::vector<std::int64_t> shape,
                            std::span<const T> values) {
  TableArray a;
  a.name = std::move(name);
  a.dtype = dtype_of<T>();
  a.shape = std::move(shape);
  a.data.resize(values.size() * sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i)
    table_detail::store_le(values[i], a.data.data() + i * sizeof(T));
  return a;
}

template <class T>
std::vector<T> TableArray::values() const {
  if (dtype != dtype_of<T>()) return {};
  std::vector<T> out(data.size() / sizeof(T));
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = table_detail::load_le<T>(data.data() + i * sizeof(T));
  return out;
}

template <class T>
auto Table::get(std::string_view name) const {
  using R = Result<std::vector<T>>;
  const TableArray* a = find(name);
  if (!a) return R(Error{"table of kind '" + kind + "' has no array '" + std::string(name) + "'"});
  if (a->dtype != dtype_of<T>())
    return R(Error{"array '" + std::string(name) + "' has dtype " + std::string(dtype_name(a->dtype)) +
                        ", expected " + std::string(dtype_name(dtype_of<T>()))});
  return R(a->values<T>());
}

}  // namespace shtool
