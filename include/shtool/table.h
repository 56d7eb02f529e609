// Versioned, self-describing tables: the one format every shtool job writes and the
// runtime loads. The byte layout is documented in docs/table-format.md; the header
// schemas are in schemas/.
//
// Two encodings of the same content:
//   binary  - magic, header length, header CRC, JSON header, then little-endian arrays,
//             each with its own CRC-32 (the default; exact bits of every value);
//   json    - one JSON document, header plus the arrays as JSON numbers written with
//             round-trip precision (for small tables and for people).
// The loader detects the encoding from the first bytes.
//
// Runtime side: no exceptions cross this API; errors come back as TableResult.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

namespace shtool {

// Format of the container itself (magic, header fields, array layout).
inline constexpr int kTableFormatMajor = 1;
inline constexpr int kTableFormatMinor = 0;
// Identifier of the conventions of docs/conventions.md, stored in every header.
inline constexpr std::string_view kConventionsId = "shtool-sh-v1";

enum class DType { f64, f32, i32, u32, i64, u64, u8 };
std::string_view dtype_name(DType type);
std::size_t dtype_size(DType type);
std::optional<DType> dtype_from_name(std::string_view name);

template <class T>
constexpr DType dtype_of();

// One named n-dimensional array, row-major, stored as little-endian bytes.
struct TableArray {
  std::string name;
  DType dtype = DType::f64;
  std::vector<std::int64_t> shape;
  std::vector<std::byte> data;

  std::size_t element_count() const;

  template <class T>
  static TableArray from(std::string name, std::vector<std::int64_t> shape,
                         std::span<const T> values);
  // Copies the values out; dtype must match T exactly (checked by the loader's users
  // through Table::get, which reports a clear error).
  template <class T>
  std::vector<T> values() const;
};

struct Table {
  std::string kind;             // e.g. "rotation-helpers"; one schema per kind
  std::string kind_version = "1.0";  // version of that kind's schema, "major.minor"
  int order = 0;                // SH order N the table is for
  // How it was made: {"tool": "shtool", "version": ..., "command": ..., "parameters":
  // {...}} (seed included in parameters when there is one). No timestamps or hostnames:
  // the same inputs must give byte-identical tables.
  nlohmann::json generator = nlohmann::json::object();
  nlohmann::json meta = nlohmann::json::object();  // kind-specific summary values
  std::vector<TableArray> arrays;

  const TableArray* find(std::string_view name) const;
};

enum class TableEncoding { binary, json };

struct TableError {
  std::string message;  // names the file and the problem, e.g. "checksum mismatch in array 'x'"
};

// Expected-style result: either a value or an error message.
template <class T>
class TableResult {
 public:
  TableResult(T value) : v_(std::move(value)) {}
  TableResult(TableError error) : v_(std::move(error)) {}
  bool ok() const { return std::holds_alternative<T>(v_); }
  explicit operator bool() const { return ok(); }
  const T& value() const& { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  const TableError& error() const { return std::get<TableError>(v_); }

 private:
  std::variant<T, TableError> v_;
};

struct TableOk {};

// What a loader expects; empty fields are not checked.
struct TableExpectation {
  std::string kind;
  int kind_major = 0;  // 0: any; otherwise the kind's schema major version must match
  int order = 0;       // 0: any
};

// Header JSON exactly as written into the file (arrays with offsets and checksums).
nlohmann::json table_header(const Table& table);

// Writes atomically: a temporary file in the same folder, flushed, then renamed over
// `path`. On failure nothing is left at `path` (an old file there stays untouched).
TableResult<TableOk> write_table(const Table& table, const std::filesystem::path& path,
                                 TableEncoding encoding = TableEncoding::binary);

// Reads and validates: magic, format major version, header CRC, header fields, array
// bounds, array CRCs, then the expectation. Never throws, never returns partial data.
TableResult<Table> read_table(const std::filesystem::path& path,
                              const TableExpectation& expect = {});

}  // namespace shtool
