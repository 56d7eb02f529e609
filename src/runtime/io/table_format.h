// Internal to shtool: the pieces of the table container that the reader (here) and the
// offline writer (src/offline/common/table_writer.cpp) must agree on. Not installed;
// the byte layout itself is specified in docs/table-format.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "shtool/table.h"

namespace shtool::table_format {

// A header this large is a corrupted length field, not a table: refuse it before
// allocating (the file-size check alone would still allow gigabytes for a large file).
inline constexpr std::uint64_t kMaxHeaderBytes = std::uint64_t{64} << 20;
// Bounds that keep every size computation far from overflow.
inline constexpr std::uint64_t kMaxArrayBytes = std::uint64_t{1} << 60;
inline constexpr std::int64_t kMaxOrderInHeader = 1 << 20;

// Where one array sits in the data section.
struct Layout {
  std::uint64_t offset = 0;  // relative to the start of the data section
  std::uint64_t nbytes = 0;
  std::uint32_t crc = 0;
};

constexpr std::uint64_t align_up(std::uint64_t x) {
  return (x + (kTableAlignment - 1)) / kTableAlignment * kTableAlignment;
}

// Product of the dims times the element size, or nullopt on a negative dim or a size
// beyond kMaxArrayBytes (which also rules out overflow).
std::optional<std::uint64_t> checked_nbytes(const std::vector<std::int64_t>& shape, DType dtype);

struct Version {
  int major = 0;
  int minor = 0;
};
// "major.minor", both decimal without sign or leading zeros.
std::optional<Version> parse_version(std::string_view s);

// 1-64 characters of [a-z0-9-], not starting with '-'.
bool valid_kind_name(std::string_view k);

// "[2, 3]"
std::string shape_text(const std::vector<std::int64_t>& shape);

// The generator record's required fields; a message when one is missing.
std::optional<std::string> check_generator(const nlohmann::json& g);

// JSON nested deeper than this is not a table; refusing it up front keeps every later
// step (the parser, dump(), a consumer's recursion) far from the stack's limit.
inline constexpr int kMaxJsonDepth = 64;

// Nesting depth of the brackets outside strings, scanned without parsing; a message
// ("nested more than N levels deep at byte k") when it exceeds `limit`.
std::optional<std::string> check_json_depth(std::string_view text, int limit);

Error error_at(const std::filesystem::path& path, const std::string& problem);

}  // namespace shtool::table_format
