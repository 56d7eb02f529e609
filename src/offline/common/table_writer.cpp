// The table writer: deterministic bytes (docs/table-format.md), written atomically.
#include "common/table_writer.h"

#include <cmath>
#include <cstring>
#include <set>

#include "common/atomic_file.h"
#include "common/input_error.h"
#include "io/table_format.h"

namespace shtool {
namespace {

using json = nlohmann::json;
using namespace table_format;

// Generator and meta as JSON objects; the writer's message when either is not JSON.
json parse_field(const std::string& text, const char* name) {
  json v = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (v.is_discarded()) throw InputError(std::string("'") + name + "' is not valid JSON text");
  return v;
}

std::optional<std::string> check_for_write(const Table& t, const json& generator, const json& meta,
                                           TableEncoding encoding, NonFinite non_finite) {
  if (!valid_kind_name(t.kind))
    return "table kind '" + t.kind + "' must be 1-64 characters of [a-z0-9-] not starting with '-'";
  if (!parse_version(t.kind_version))
    return "kind_version '" + t.kind_version + "' is not of the form major.minor";
  if (t.order < 0 || t.order > kMaxOrderInHeader) return "order " + std::to_string(t.order) + " is out of range";
  if (auto p = check_generator(generator)) return p;
  if (!meta.is_object()) return "'meta' must be a JSON object";
  std::set<std::string> names;
  for (const TableArray& a : t.arrays) {
    if (a.name.empty()) return "an array has an empty name";
    if (!names.insert(a.name).second) return "two arrays are named '" + a.name + "'";
    const auto nbytes = checked_nbytes(a.shape, a.dtype);
    if (!nbytes) return "array '" + a.name + "' has an invalid shape " + shape_text(a.shape);
    if (*nbytes != a.data.size())
      return "array '" + a.name + "' has " + std::to_string(a.data.size()) + " bytes but shape " +
             shape_text(a.shape) + " of " + std::string(dtype_name(a.dtype)) + " needs " +
             std::to_string(*nbytes);
    const bool refuse = encoding == TableEncoding::json || non_finite == NonFinite::refuse;
    if (refuse && (a.dtype == DType::f64 || a.dtype == DType::f32)) {
      const std::size_t n = a.element_count();
      for (std::size_t i = 0; i < n; ++i) {
        const double v = a.dtype == DType::f64
                             ? table_detail::load_le<double>(a.data.data() + 8 * i)
                             : table_detail::load_le<float>(a.data.data() + 4 * i);
        if (!std::isfinite(v))
          return "array '" + a.name + "' element " + std::to_string(i) + " is not finite" +
                 (non_finite == NonFinite::keep ? "; the JSON encoding cannot hold it (use the binary encoding)"
                                                : " (a computation overflowed: no output holds NaN or infinity)");
      }
    }
  }
  return std::nullopt;
}

std::vector<Layout> compute_layout(const Table& t) {
  std::vector<Layout> out;
  std::uint64_t cursor = 0;
  for (const TableArray& a : t.arrays) {
    Layout l;
    l.offset = align_up(cursor);
    l.nbytes = a.data.size();
    l.crc = table_crc32(a.data);
    cursor = l.offset + l.nbytes;
    out.push_back(l);
  }
  return out;
}

json header_from(const Table& t, const json& generator, const json& meta, const std::vector<Layout>& layout) {
  json arrays = json::array();
  for (std::size_t i = 0; i < t.arrays.size(); ++i) {
    const TableArray& a = t.arrays[i];
    arrays.push_back({{"name", a.name},
                      {"dtype", dtype_name(a.dtype)},
                      {"shape", a.shape},
                      {"offset", layout[i].offset},
                      {"nbytes", layout[i].nbytes},
                      {"crc32", layout[i].crc}});
  }
  return {{"format", kTableFormatName},
          {"format_version", std::to_string(kTableFormatMajor) + "." + std::to_string(kTableFormatMinor)},
          {"kind", t.kind},
          {"kind_version", t.kind_version},
          {"order", t.order},
          {"conventions", kConventionsId},
          {"generator", generator},
          {"meta", meta},
          {"arrays", std::move(arrays)}};
}

json values_as_json(const TableArray& a) {
  json out = json::array();
  const std::size_t n = a.element_count();
  const std::byte* p = a.data.data();
  for (std::size_t i = 0; i < n; ++i) {
    switch (a.dtype) {
      case DType::f64: out.push_back(table_detail::load_le<double>(p + 8 * i)); break;
      // float -> double is exact, and the shortest round-trip text of that double reads
      // back to the same float.
      case DType::f32: out.push_back(static_cast<double>(table_detail::load_le<float>(p + 4 * i))); break;
      case DType::i32: out.push_back(table_detail::load_le<std::int32_t>(p + 4 * i)); break;
      case DType::u32: out.push_back(table_detail::load_le<std::uint32_t>(p + 4 * i)); break;
      case DType::i64: out.push_back(table_detail::load_le<std::int64_t>(p + 8 * i)); break;
      case DType::u64: out.push_back(table_detail::load_le<std::uint64_t>(p + 8 * i)); break;
      case DType::u8: out.push_back(static_cast<std::uint32_t>(p[i])); break;
    }
  }
  return out;
}

// One top-level key per line and one array per line under "data": readable, and still
// fully determined by the content (nlohmann objects iterate in sorted key order).
std::string json_document(const json& header, const Table& t) {
  std::string s = "{\n";
  for (auto it = header.begin(); it != header.end(); ++it)
    s += "  " + json(it.key()).dump() + ": " + it.value().dump() + ",\n";
  s += "  \"data\": {";
  for (std::size_t i = 0; i < t.arrays.size(); ++i)
    s += std::string(i ? "," : "") + "\n    " + json(t.arrays[i].name).dump() + ": " +
         values_as_json(t.arrays[i]).dump();
  s += t.arrays.empty() ? "}\n}\n" : "\n  }\n}\n";
  return s;
}

std::string binary_document(const Table& t, const std::string& header_text, const std::vector<Layout>& layout) {
  std::string out;
  auto write = [&out](const void* p, std::size_t n) { out.append(static_cast<const char*>(p), n); };
  auto zeros = [&out](std::uint64_t n) { out.append(static_cast<std::size_t>(n), '\0'); };
  std::byte prefix[kTablePrefixSize] = {};
  std::memcpy(prefix, kTableMagic, 8);
  const std::span<const std::byte> hb(reinterpret_cast<const std::byte*>(header_text.data()),
                                      header_text.size());
  table_detail::store_le<std::uint64_t>(header_text.size(), prefix + 8);
  table_detail::store_le<std::uint32_t>(table_crc32(hb), prefix + 16);
  table_detail::store_le<std::uint32_t>(0, prefix + 20);
  write(prefix, sizeof prefix);
  write(header_text.data(), header_text.size());
  const std::uint64_t data_start = align_up(kTablePrefixSize + header_text.size());
  zeros(data_start - kTablePrefixSize - header_text.size());
  std::uint64_t cursor = 0;
  for (std::size_t i = 0; i < t.arrays.size(); ++i) {
    zeros(layout[i].offset - cursor);
    write(t.arrays[i].data.data(), t.arrays[i].data.size());
    cursor = layout[i].offset + layout[i].nbytes;
  }
  return out;
}

}  // namespace

Table new_table(std::string_view kind, int order, const nlohmann::json& generator, const nlohmann::json& meta) {
  Table t;
  t.kind = std::string(kind);
  t.kind_version = "1.0";
  t.order = order;
  t.generator = dump_finite(generator, "the table's generator record");
  t.meta = dump_finite(meta, "the table's meta");
  return t;
}

nlohmann::json table_header(const Table& table) {
  return header_from(table, parse_field(table.generator, "generator"), parse_field(table.meta, "meta"),
                     compute_layout(table));
}

std::string encode_table(const Table& table, TableEncoding encoding, NonFinite non_finite) {
  try {
    const json generator = parse_field(table.generator, "generator");
    const json meta = parse_field(table.meta, "meta");
    if (auto p = check_for_write(table, generator, meta, encoding, non_finite)) throw InputError(*p);
    const std::vector<Layout> layout = compute_layout(table);
    const json header = header_from(table, generator, meta, layout);
    return encoding == TableEncoding::json ? json_document(header, table)
                                           : binary_document(table, header.dump(), layout);
  } catch (const InputError& e) {
    throw InputError(std::string("cannot write table: ") + e.what());
  } catch (const json::exception& e) {
    // dump() of a string that is not UTF-8
    throw InputError(std::string("cannot write table: ") + e.what());
  }
}

void write_table(const Table& table, const std::filesystem::path& path, TableEncoding encoding,
                 NonFinite non_finite) {
  std::string bytes;
  try {
    bytes = encode_table(table, encoding, non_finite);
  } catch (const InputError& e) {
    throw InputError(path.string() + ": " + e.what());
  }
  write_file_atomically(path, bytes);
}

}  // namespace shtool
