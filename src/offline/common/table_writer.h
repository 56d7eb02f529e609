// Writing tables: the offline half of the container shtool/table.h reads. Bytes are a
// function of the content alone (same inputs, same bytes, on every machine).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "common/finite.h"
#include "shtool/table.h"

namespace shtool {

// Header JSON exactly as written into the file: arrays with offsets (relative to the
// data section), sizes and CRCs of their little-endian bytes. Precondition: the table
// passes the writer's checks (encode_table reports them).
nlohmann::json table_header(const Table& table);

// The file's bytes. Checks first: kind, versions, generator record, array names
// (non-empty, unique), shapes against data sizes, float values finite (with
// NonFinite::keep, only for the JSON encoding, which has no NaN or infinity). Throws
// InputError naming the problem.
std::string encode_table(const Table& table, TableEncoding encoding = TableEncoding::binary,
                         NonFinite non_finite = NonFinite::refuse);

// encode_table, then written atomically (common/atomic_file.h): on failure nothing is
// left at `path` and an old file there stays untouched. Throws InputError.
void write_table(const Table& table, const std::filesystem::path& path,
                 TableEncoding encoding = TableEncoding::binary, NonFinite non_finite = NonFinite::refuse);

// A table of `kind` (kind_version 1.0) for SH order `order` with its generator record
// and kind-specific meta, arrays still to add: how every job starts its output.
Table new_table(std::string_view kind, int order, const nlohmann::json& generator, const nlohmann::json& meta);

// The generator record and meta of a table as JSON (they are stored as JSON text).
inline nlohmann::json table_generator(const Table& t) { return nlohmann::json::parse(t.generator); }
inline nlohmann::json table_meta(const Table& t) { return nlohmann::json::parse(t.meta); }

}  // namespace shtool
