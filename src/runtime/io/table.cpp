// Table container: the validating loader. The byte layout is specified in
// docs/table-format.md; the writer (offline) shares io/table_format.h with it.
#include "shtool/table.h"

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <system_error>

#include <nlohmann/json.hpp>

#include "io/table_format.h"

namespace shtool {

namespace table_format {

using json = nlohmann::json;

std::optional<std::uint64_t> checked_nbytes(const std::vector<std::int64_t>& shape, DType dtype) {
  std::uint64_t n = dtype_size(dtype);
  bool empty = false;
  for (std::int64_t d : shape) {
    if (d < 0) return std::nullopt;
    if (d == 0) empty = true;
  }
  if (empty) return 0;
  for (std::int64_t d : shape) {
    if (static_cast<std::uint64_t>(d) > kMaxArrayBytes / n) return std::nullopt;
    n *= static_cast<std::uint64_t>(d);
  }
  return n;
}

std::optional<Version> parse_version(std::string_view s) {
  const std::size_t dot = s.find('.');
  if (dot == std::string_view::npos) return std::nullopt;
  auto part = [](std::string_view p) -> std::optional<int> {
    if (p.empty() || p.size() > 9 || (p.size() > 1 && p[0] == '0')) return std::nullopt;
    int v = 0;
    for (char c : p) {
      if (c < '0' || c > '9') return std::nullopt;
      v = v * 10 + (c - '0');
    }
    return v;
  };
  const auto a = part(s.substr(0, dot));
  const auto b = part(s.substr(dot + 1));
  if (!a || !b) return std::nullopt;
  return Version{*a, *b};
}

bool valid_kind_name(std::string_view k) {
  if (k.empty() || k.size() > 64) return false;
  for (char c : k)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-')) return false;
  return k.front() != '-';
}

std::string shape_text(const std::vector<std::int64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

std::optional<std::string> check_generator(const json& g) {
  if (!g.is_object()) return "'generator' must be a JSON object";
  for (const char* key : {"tool", "version", "command"}) {
    auto it = g.find(key);
    if (it == g.end() || !it->is_string()) return std::string("'generator' needs a string field '") + key + "'";
  }
  auto p = g.find("parameters");
  if (p == g.end() || !p->is_object()) return "'generator' needs an object field 'parameters'";
  return std::nullopt;
}

Error error_at(const std::filesystem::path& path, const std::string& problem) {
  return Error{path.string() + ": " + problem};
}

std::optional<std::string> check_json_depth(std::string_view text, int limit) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > limit)
        return "nested more than " + std::to_string(limit) + " levels deep at byte " + std::to_string(i);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return std::nullopt;
}

}  // namespace table_format

namespace {

using json = nlohmann::json;
using namespace table_format;

constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t n = 0; n < 256; ++n) {
    std::uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[n] = c;
  }
  return t;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table();

std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", v);
  return buf;
}

std::string hex_bytes(const unsigned char* p, std::size_t n) {
  std::string s;
  char buf[4];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%02x", p[i]);
    if (i) s += ' ';
    s += buf;
  }
  return s;
}

// Where a document that failed to parse goes wrong, from the parser's own report: one
// SAX pass that records the first error (no exception involved).
std::string json_syntax_error(std::string_view text) {
  struct FirstError : nlohmann::json_sax<json> {
    std::string message = "syntax error";
    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(number_integer_t) override { return true; }
    bool number_unsigned(number_unsigned_t) override { return true; }
    bool number_float(number_float_t, const string_t&) override { return true; }
    bool string(string_t&) override { return true; }
    bool binary(binary_t&) override { return true; }
    bool start_object(std::size_t) override { return true; }
    bool key(string_t&) override { return true; }
    bool end_object() override { return true; }
    bool start_array(std::size_t) override { return true; }
    bool end_array() override { return true; }
    bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) override {
      message = std::string(e.what()) + " (byte " + std::to_string(position) + ")";
      return false;
    }
  } sax;
  json::sax_parse(text, &sax, nlohmann::detail::input_format_t::json, /*strict=*/true, /*ignore_comments=*/false);
  return sax.message;
}

const json* field(const json& obj, const char* key) {
  auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

std::optional<std::uint64_t> as_u64(const json* v) {
  if (!v || !v->is_number_unsigned()) return std::nullopt;
  return v->get<std::uint64_t>();
}

// Validates the header fields shared by both encodings and fills the table skeleton
// (arrays named, typed and shaped, without data) and the stored layout.
std::optional<std::string> parse_header(const json& h, Table& t, std::vector<Layout>& layout) {
  if (!h.is_object()) return "header is not a JSON object";
  auto missing = [](const char* key, const char* what) {
    return std::string("header field '") + key + "' is missing or not " + what;
  };
  const json* format = field(h, "format");
  if (!format || !format->is_string() || format->get<std::string>() != kTableFormatName)
    return "header field 'format' is not \"" + std::string(kTableFormatName) + "\" (not a shtool table)";
  const json* fv = field(h, "format_version");
  if (!fv || !fv->is_string()) return missing("format_version", "a \"major.minor\" string");
  const auto version = parse_version(fv->get<std::string>());
  if (!version) return "header field 'format_version' is '" + fv->get<std::string>() + "', not major.minor";
  if (version->major != kTableFormatMajor)
    return "unsupported table format version " + fv->get<std::string>() + " (this reader reads " +
           std::to_string(kTableFormatMajor) + ".x)";

  const json* kind = field(h, "kind");
  if (!kind || !kind->is_string() || !valid_kind_name(kind->get<std::string>()))
    return missing("kind", "a kind name");
  t.kind = kind->get<std::string>();
  const json* kv = field(h, "kind_version");
  if (!kv || !kv->is_string() || !parse_version(kv->get<std::string>()))
    return missing("kind_version", "a \"major.minor\" string");
  t.kind_version = kv->get<std::string>();
  const json* order = field(h, "order");
  if (!order || !order->is_number_integer() || order->get<std::int64_t>() < 0 ||
      order->get<std::int64_t>() > kMaxOrderInHeader)
    return missing("order", "a non-negative integer");
  t.order = static_cast<int>(order->get<std::int64_t>());
  const json* conv = field(h, "conventions");
  if (!conv || !conv->is_string()) return missing("conventions", "a string");
  if (conv->get<std::string>() != kConventionsId)
    return "table uses SH conventions '" + conv->get<std::string>() + "', this reader uses '" +
           std::string(kConventionsId) + "'";
  const json* gen = field(h, "generator");
  if (!gen) return missing("generator", "an object");
  if (auto p = check_generator(*gen)) return "header " + *p;
  t.generator = gen->dump();
  const json* meta = field(h, "meta");
  if (!meta || !meta->is_object()) return missing("meta", "an object");
  t.meta = meta->dump();

  const json* arrays = field(h, "arrays");
  if (!arrays || !arrays->is_array()) return missing("arrays", "a list");
  std::set<std::string> names;
  std::uint64_t prev_end = 0;
  for (std::size_t i = 0; i < arrays->size(); ++i) {
    const json& e = (*arrays)[i];
    const std::string where = "header array #" + std::to_string(i);
    if (!e.is_object()) return where + " is not an object";
    const json* name = field(e, "name");
    if (!name || !name->is_string() || name->get<std::string>().empty())
      return where + " has no name";
    TableArray a;
    a.name = name->get<std::string>();
    const std::string which = "array '" + a.name + "'";
    if (!names.insert(a.name).second) return "two arrays are named '" + a.name + "'";
    const json* dt = field(e, "dtype");
    if (!dt || !dt->is_string()) return which + " has no dtype";
    const auto dtype = dtype_from_name(dt->get<std::string>());
    if (!dtype) return which + " has unknown dtype '" + dt->get<std::string>() + "'";
    a.dtype = *dtype;
    const json* shape = field(e, "shape");
    if (!shape || !shape->is_array() || shape->size() > 32) return which + " has no valid shape";
    for (const json& d : *shape) {
      if (!d.is_number_unsigned() || d.get<std::uint64_t>() > kMaxArrayBytes)
        return which + " has a shape entry that is not a non-negative integer";
      a.shape.push_back(static_cast<std::int64_t>(d.get<std::uint64_t>()));
    }
    const auto offset = as_u64(field(e, "offset"));
    const auto nbytes = as_u64(field(e, "nbytes"));
    const auto crc = as_u64(field(e, "crc32"));
    if (!offset || !nbytes || !crc || *crc > 0xFFFFFFFFu)
      return which + " needs non-negative integer fields offset, nbytes and crc32 (< 2^32)";
    const auto need = checked_nbytes(a.shape, a.dtype);
    if (!need) return which + " has a shape too large to address: " + shape_text(a.shape);
    if (*need != *nbytes)
      return which + ": shape " + shape_text(a.shape) + " of " + std::string(dtype_name(a.dtype)) +
             " needs " + std::to_string(*need) + " bytes, header says nbytes = " + std::to_string(*nbytes);
    if (*offset % kTableAlignment != 0 || *offset > kMaxArrayBytes)
      return which + " offset " + std::to_string(*offset) + " is not a multiple of " +
             std::to_string(kTableAlignment);
    if (*offset < prev_end)
      return which + " offset " + std::to_string(*offset) + " overlaps the previous array (which ends at " +
             std::to_string(prev_end) + ")";
    prev_end = *offset + *nbytes;
    layout.push_back({*offset, *nbytes, static_cast<std::uint32_t>(*crc)});
    t.arrays.push_back(std::move(a));
  }
  return std::nullopt;
}

std::optional<std::string> check_expectation(const Table& t, const TableExpectation& expect) {
  if (!expect.kind.empty() && t.kind != expect.kind)
    return "table kind is '" + t.kind + "', expected '" + expect.kind + "'";
  if (expect.kind_major != 0 && parse_version(t.kind_version)->major != expect.kind_major)
    return "table kind '" + t.kind + "' has version " + t.kind_version + ", this reader needs major version " +
           std::to_string(expect.kind_major);
  if (expect.order != 0 && t.order != expect.order)
    return "table is for SH order " + std::to_string(t.order) + ", expected order " + std::to_string(expect.order);
  return std::nullopt;
}

// Sequential reads from the table's bytes.
class Reader {
 public:
  explicit Reader(std::span<const std::byte> bytes) : bytes_(bytes) {}
  bool read(void* p, std::uint64_t n) {
    if (n == 0) return true;
    if (n > bytes_.size() - pos_) return false;
    std::memcpy(p, bytes_.data() + pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return true;
  }
  // Reads n padding bytes; false with bad_at set if one is not zero.
  bool zeros(std::uint64_t n, std::uint64_t pos, std::optional<std::uint64_t>& bad_at) {
    unsigned char buf[4096];
    while (n > 0) {
      const std::uint64_t k = std::min<std::uint64_t>(n, sizeof buf);
      if (!read(buf, k)) return false;
      for (std::uint64_t i = 0; i < k; ++i)
        if (buf[i] != 0) {
          bad_at = pos + i;
          return true;
        }
      n -= k;
      pos += k;
    }
    return true;
  }

 private:
  std::span<const std::byte> bytes_;
  std::size_t pos_ = 0;
};

Result<Table> read_binary(std::span<const std::byte> in, const std::filesystem::path& path,
                          const TableExpectation& expect, TableFileInfo* info, bool verify) {
  const std::uint64_t size = in.size();
  auto fail = [&](const std::string& p) { return Result<Table>(error_at(path, p)); };
  Reader r(in);
  unsigned char prefix[kTablePrefixSize] = {};
  const std::uint64_t have = std::min<std::uint64_t>(size, kTablePrefixSize);
  if (!r.read(prefix, have)) return fail("read error in the prefix");
  const std::size_t magic_have = static_cast<std::size_t>(std::min<std::uint64_t>(have, 8));
  if (std::memcmp(prefix, kTableMagic, magic_have) != 0)
    return fail("bad magic bytes " + hex_bytes(prefix, magic_have) + ", expected " +
                hex_bytes(kTableMagic, 8) +
                " (not a shtool table, or mangled by a text-mode transfer)");
  if (size < kTablePrefixSize)
    return fail("truncated: the file has " + std::to_string(size) + " bytes, fewer than the " +
                std::to_string(kTablePrefixSize) + "-byte prefix");
  const auto* pb = reinterpret_cast<const std::byte*>(prefix);
  const auto header_len = table_detail::load_le<std::uint64_t>(pb + 8);
  const auto header_crc = table_detail::load_le<std::uint32_t>(pb + 16);
  const auto reserved = table_detail::load_le<std::uint32_t>(pb + 20);
  if (reserved != 0) return fail("reserved prefix field is " + hex32(reserved) + ", expected 0");
  if (header_len > size - kTablePrefixSize)
    return fail("truncated: header length " + std::to_string(header_len) + " runs past the end of the file (" +
                std::to_string(size) + " bytes)");
  if (header_len > kMaxHeaderBytes)
    return fail("header length " + std::to_string(header_len) + " exceeds the " +
                std::to_string(kMaxHeaderBytes >> 20) + " MiB limit (corrupted length field?)");
  std::string header_text(static_cast<std::size_t>(header_len), '\0');
  if (!r.read(header_text.data(), header_len)) return fail("read error in the header");
  const std::uint32_t crc = table_crc32(
      std::span<const std::byte>(reinterpret_cast<const std::byte*>(header_text.data()), header_text.size()));
  if (verify && crc != header_crc)
    return fail("header CRC-32 mismatch: stored " + hex32(header_crc) + ", computed " + hex32(crc) +
                " (header corrupted)");
  if (auto p = check_json_depth(header_text, kMaxJsonDepth)) return fail("malformed header JSON: " + *p);
  json header = json::parse(header_text, nullptr, /*allow_exceptions=*/false);
  if (header.is_discarded()) return fail("malformed header JSON: " + json_syntax_error(header_text));
  Table t;
  std::vector<Layout> layout;
  if (auto p = parse_header(header, t, layout)) return fail(*p);
  if (auto p = check_expectation(t, expect)) return fail(*p);

  const std::uint64_t data_start = align_up(kTablePrefixSize + header_len);
  std::uint64_t data_end = 0;
  for (const Layout& l : layout) data_end = std::max(data_end, l.offset + l.nbytes);
  const std::uint64_t expected_size = data_start + data_end;  // bounded: no overflow
  if (size < expected_size) {
    for (std::size_t i = 0; i < layout.size(); ++i) {
      const std::uint64_t end = data_start + layout[i].offset + layout[i].nbytes;
      if (end > size)
        return fail("truncated: array '" + t.arrays[i].name + "' occupies file bytes [" +
                    std::to_string(data_start + layout[i].offset) + ", " + std::to_string(end) +
                    ") but the file has only " + std::to_string(size) + " bytes");
    }
    return fail("truncated: the header describes " + std::to_string(expected_size) +
                " bytes, the file has only " + std::to_string(size));
  }
  if (size > expected_size)
    return fail(std::to_string(size - expected_size) + " unexpected bytes after the last array (file has " +
                std::to_string(size) + " bytes, the header describes " + std::to_string(expected_size) + ")");

  std::uint64_t pos = kTablePrefixSize + header_len;
  std::optional<std::uint64_t> bad;
  auto pad_to = [&](std::uint64_t target) {
    const bool ok = r.zeros(target - pos, pos, bad);
    pos = target;
    return ok;
  };
  if (!pad_to(data_start)) return fail("read error in the header padding");
  for (std::size_t i = 0; i < layout.size() && !bad; ++i) {
    if (!pad_to(data_start + layout[i].offset)) return fail("read error before array '" + t.arrays[i].name + "'");
    if (bad) break;
    TableArray& a = t.arrays[i];
    a.data.resize(static_cast<std::size_t>(layout[i].nbytes));
    if (!r.read(a.data.data(), layout[i].nbytes)) return fail("read error in array '" + a.name + "'");
    pos += layout[i].nbytes;
    const std::uint32_t c = table_crc32(a.data);
    if (verify && c != layout[i].crc)
      return fail("CRC-32 mismatch in array '" + a.name + "': stored " + hex32(layout[i].crc) + ", computed " +
                  hex32(c) + " (data corrupted)");
  }
  if (bad) return fail("padding byte at file offset " + std::to_string(*bad) + " is not zero (file corrupted)");
  if (info) {
    info->encoding = TableEncoding::binary;
    info->file_size = size;
    info->header_json = header.dump();
  }
  return t;
}

// Converts one JSON number to the little-endian bytes of `dtype`; a message on failure.
std::optional<std::string> store_json_value(const json& v, DType dtype, std::byte* out) {
  auto int_in = [&](std::int64_t lo, std::uint64_t hi) -> std::optional<std::string> {
    if (!v.is_number_integer()) return "is not an integer";
    if (v.is_number_unsigned() ? v.get<std::uint64_t>() > hi : v.get<std::int64_t>() < lo)
      return "is out of range for " + std::string(dtype_name(dtype));
    return std::nullopt;
  };
  switch (dtype) {
    case DType::f64:
      if (!v.is_number()) return "is not a number";
      table_detail::store_le(v.get<double>(), out);
      return std::nullopt;
    case DType::f32: {
      if (!v.is_number()) return "is not a number";
      const double d = v.get<double>();
      if (std::fabs(d) > std::numeric_limits<float>::max()) return "is out of range for f32";
      table_detail::store_le(static_cast<float>(d), out);
      return std::nullopt;
    }
    case DType::i32:
      if (auto p = int_in(std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max())) return p;
      table_detail::store_le(static_cast<std::int32_t>(v.get<std::int64_t>()), out);
      return std::nullopt;
    case DType::u32:
      if (auto p = int_in(0, std::numeric_limits<std::uint32_t>::max())) return p;
      table_detail::store_le(static_cast<std::uint32_t>(v.get<std::uint64_t>()), out);
      return std::nullopt;
    case DType::i64:
      if (auto p = int_in(std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max())) return p;
      table_detail::store_le(v.get<std::int64_t>(), out);
      return std::nullopt;
    case DType::u64:
      if (auto p = int_in(0, std::numeric_limits<std::uint64_t>::max())) return p;
      table_detail::store_le(v.get<std::uint64_t>(), out);
      return std::nullopt;
    case DType::u8:
      if (auto p = int_in(0, 255)) return p;
      *out = static_cast<std::byte>(v.get<std::uint64_t>());
      return std::nullopt;
  }
  return "has an unknown dtype";
}

Result<Table> read_json(std::span<const std::byte> in, const std::filesystem::path& path,
                        const TableExpectation& expect, TableFileInfo* info, bool verify) {
  const std::uint64_t size = in.size();
  auto fail = [&](const std::string& p) { return Result<Table>(error_at(path, p)); };
  // Parsed in place: the bytes are the document.
  const std::string_view text(reinterpret_cast<const char*>(in.data()), static_cast<std::size_t>(size));
  if (auto p = check_json_depth(text, kMaxJsonDepth)) return fail("malformed JSON table: " + *p);
  json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) return fail("malformed JSON table: " + json_syntax_error(text));
  if (!doc.is_object()) return fail("JSON table is not an object");
  auto data_it = doc.find("data");
  if (data_it == doc.end() || !data_it->is_object()) return fail("JSON table has no \"data\" object");
  json data = std::move(*data_it);
  doc.erase("data");
  Table t;
  std::vector<Layout> layout;
  if (auto p = parse_header(doc, t, layout)) return fail(*p);
  if (auto p = check_expectation(t, expect)) return fail(*p);
  for (auto it = data.begin(); it != data.end(); ++it)
    if (!t.find(it.key())) return fail("\"data\" holds array '" + it.key() + "' that the header does not list");
  for (std::size_t i = 0; i < t.arrays.size(); ++i) {
    TableArray& a = t.arrays[i];
    auto v = data.find(a.name);
    if (v == data.end() || !v->is_array()) return fail("\"data\" has no list for array '" + a.name + "'");
    const std::size_t n = a.element_count();
    if (v->size() != n)
      return fail("\"data\" for array '" + a.name + "' has " + std::to_string(v->size()) + " values, shape " +
                  shape_text(a.shape) + " needs " + std::to_string(n));
    const std::size_t es = dtype_size(a.dtype);
    a.data.resize(static_cast<std::size_t>(layout[i].nbytes));
    for (std::size_t k = 0; k < n; ++k)
      if (auto p = store_json_value((*v)[k], a.dtype, a.data.data() + k * es))
        return fail("array '" + a.name + "' element " + std::to_string(k) + " " + *p);
    const std::uint32_t c = table_crc32(a.data);
    if (verify && c != layout[i].crc)
      return fail("CRC-32 mismatch in array '" + a.name + "': header says " + hex32(layout[i].crc) +
                  ", the values give " + hex32(c) + " (a value was edited or rounded)");
  }
  if (info) {
    info->encoding = TableEncoding::json;
    info->file_size = size;
    info->header_json = doc.dump();
  }
  return t;
}

}  // namespace

// ---------------------------------------------------------------------------

std::string_view dtype_name(DType type) {
  switch (type) {
    case DType::f64: return "f64";
    case DType::f32: return "f32";
    case DType::i32: return "i32";
    case DType::u32: return "u32";
    case DType::i64: return "i64";
    case DType::u64: return "u64";
    case DType::u8: return "u8";
  }
  return "?";
}

std::size_t dtype_size(DType type) {
  switch (type) {
    case DType::f64: case DType::i64: case DType::u64: return 8;
    case DType::f32: case DType::i32: case DType::u32: return 4;
    case DType::u8: return 1;
  }
  return 1;
}

std::optional<DType> dtype_from_name(std::string_view name) {
  for (DType t : {DType::f64, DType::f32, DType::i32, DType::u32, DType::i64, DType::u64, DType::u8})
    if (dtype_name(t) == name) return t;
  return std::nullopt;
}

std::uint32_t table_crc32(std::span<const std::byte> bytes, std::uint32_t crc) {
  crc = ~crc;
  for (std::byte b : bytes) crc = kCrcTable[(crc ^ static_cast<std::uint32_t>(b)) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

std::size_t TableArray::element_count() const {
  std::size_t n = 1;
  for (std::int64_t d : shape) n *= static_cast<std::size_t>(d);
  return n;
}

const TableArray* Table::find(std::string_view name) const {
  for (const TableArray& a : arrays)
    if (a.name == name) return &a;
  return nullptr;
}

Result<Table> read_table_bytes(std::span<const std::byte> bytes, std::string_view name,
                               const TableExpectation& expect, TableFileInfo* info, const TableReadOptions& options) {
  const std::filesystem::path path(name);
#if defined(__cpp_exceptions)
  try {
#endif
    if (bytes.empty()) return error_at(path, "empty file (not a shtool table)");
    const int first = static_cast<int>(bytes[0]);
    if (first == kTableMagic[0]) return read_binary(bytes, path, expect, info, options.verify_checksums);
    if (first == '{') return read_json(bytes, path, expect, info, options.verify_checksums);
    char buf[8];
    std::snprintf(buf, sizeof buf, "0x%02x", first & 0xFF);
    return error_at(path, std::string("bad magic: first byte ") + buf +
                              " is neither 0x89 (binary table) nor '{' (JSON table)");
#if defined(__cpp_exceptions)
  } catch (const std::exception& e) {
    // Out of memory for a huge (but size-consistent) table.
    return error_at(path, std::string("cannot read table: ") + e.what());
  }
#endif
}

Result<Table> read_table(const std::filesystem::path& path, const TableExpectation& expect, TableFileInfo* info) {
#if defined(__cpp_exceptions)
  try {
#endif
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status))
      return error_at(path, "cannot open: " + (ec ? ec.message() : std::string("no such file")));
    if (!std::filesystem::is_regular_file(status)) return error_at(path, "not a regular file");
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) return error_at(path, "cannot read the file size: " + ec.message());
    std::ifstream in(path, std::ios::binary);
    if (!in) return error_at(path, std::string("cannot open: ") + std::strerror(errno));
    std::vector<std::byte> bytes(static_cast<std::size_t>(size));
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
    if (in.gcount() != static_cast<std::streamsize>(size)) return error_at(path, "read error");
    return read_table_bytes(bytes, path.string(), expect, info);
#if defined(__cpp_exceptions)
  } catch (const std::exception& e) {
    // Out of memory for a huge file, or an I/O exception.
    return error_at(path, std::string("cannot read table: ") + e.what());
  }
#endif
}

std::filesystem::path find_shipped_table(std::string_view file_name) {
  std::vector<std::filesystem::path> dirs;
  if (const char* env = std::getenv("SHTOOL_TABLES"); env && *env) dirs.emplace_back(env);
  dirs.emplace_back(SHTOOL_INSTALL_TABLES_DIR);
  for (const std::filesystem::path& dir : dirs) {
    std::error_code ec;
    const std::filesystem::path p = dir / file_name;
    if (std::filesystem::is_regular_file(p, ec)) return p;
  }
  return {};
}

}  // namespace shtool
