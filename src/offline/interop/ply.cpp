#include "interop/ply.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <sstream>

#include "common/input_error.h"

namespace shtool::interop {
namespace {

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::int8: case PlyType::uint8: return 1;
    case PlyType::int16: case PlyType::uint16: return 2;
    case PlyType::int32: case PlyType::uint32: case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 0;
}

std::optional<PlyType> type_from_name(const std::string& n) {
  if (n == "char" || n == "int8") return PlyType::int8;
  if (n == "uchar" || n == "uint8") return PlyType::uint8;
  if (n == "short" || n == "int16") return PlyType::int16;
  if (n == "ushort" || n == "uint16") return PlyType::uint16;
  if (n == "int" || n == "int32") return PlyType::int32;
  if (n == "uint" || n == "uint32") return PlyType::uint32;
  if (n == "float" || n == "float32") return PlyType::float32;
  if (n == "double" || n == "float64") return PlyType::float64;
  return std::nullopt;
}

bool big_endian(PlyFormat f) { return f == PlyFormat::binary_big_endian; }

template <class T>
T load(const char* p, bool swap) {
  std::array<char, sizeof(T)> b;
  std::memcpy(b.data(), p, sizeof(T));
  if (swap) std::reverse(b.begin(), b.end());
  T v;
  std::memcpy(&v, b.data(), sizeof(T));
  return v;
}

template <class T>
void store(char* p, T v, bool swap) {
  std::array<char, sizeof(T)> b;
  std::memcpy(b.data(), &v, sizeof(T));
  if (swap) std::reverse(b.begin(), b.end());
  std::memcpy(p, b.data(), sizeof(T));
}

// An ASCII value as C's strtod reads it (PLY's writers print with printf): from_chars
// with an optional leading '+' (not a second sign). False unless the whole token is one number.
bool parse_ascii_value(std::string_view token, double& v) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '+' && token[1] != '-') token.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  return ec == std::errc() && ptr == token.data() + token.size();
}

}  // namespace

std::optional<std::size_t> PlyElement::find(std::string_view property) const {
  for (std::size_t p = 0; p < properties.size(); ++p)
    if (properties[p].name == property) return p;
  return std::nullopt;
}

namespace {

// Whether a header line's words are all read (a trailing word makes the line malformed).
bool no_more_words(std::istringstream& words) {
  std::string extra;
  return !(words >> extra);
}

}  // namespace

const PlyElement* PlyFile::element(std::string_view name) const {
  for (const PlyElement& e : elements_)
    if (e.name == name) return &e;
  return nullptr;
}

std::size_t PlyFile::parse_layout(std::string_view bytes, const std::filesystem::path& name, PlyFile& f) {
  auto fail = [&](const std::string& why) { return InputError(name.string() + ": PLY: " + why); };
  if (bytes.rfind("ply\n", 0) != 0 && bytes.rfind("ply\r\n", 0) != 0) throw fail("not a PLY file (no 'ply' line)");
  // The header ends at a line that is exactly "end_header" (not a comment holding it).
  std::size_t end = std::string::npos;
  for (std::size_t at = 0; at < bytes.size();) {
    const std::size_t eol = std::min(bytes.find('\n', at), bytes.size());
    std::string_view line(bytes.data() + at, eol - at);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line == "end_header") {
      end = at;
      break;
    }
    at = eol + 1;
  }
  if (end == std::string::npos) throw fail("no end_header line");
  std::size_t body = bytes.find('\n', end);
  if (body == std::string::npos) throw fail("nothing after end_header");
  ++body;
  f.header_size_ = body;
  std::istringstream header(std::string(bytes.substr(0, end)));
  std::string line;
  bool have_format = false;
  std::getline(header, line);  // "ply"
  while (std::getline(header, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      std::string fmt, version;
      words >> fmt >> version;
      if (version != "1.0") throw fail("format version '" + version + "' (PLY 1.0 is read)");
      if (!no_more_words(words)) throw fail("malformed format line '" + line + "'");
      if (fmt == "ascii") f.format_ = PlyFormat::ascii;
      else if (fmt == "binary_little_endian") f.format_ = PlyFormat::binary_little_endian;
      else if (fmt == "binary_big_endian") f.format_ = PlyFormat::binary_big_endian;
      else throw fail("unknown format '" + fmt + "'");
      have_format = true;
    } else if (key == "element") {
      PlyElement e;
      long long count = -1;
      std::string count_text;
      words >> e.name >> count_text;
      // A count is a whole number, nothing else ("20abc" is not 20).
      const auto [ptr, ec] = std::from_chars(count_text.data(), count_text.data() + count_text.size(), count);
      if (e.name.empty() || count_text.empty() || ec != std::errc() || ptr != count_text.data() + count_text.size() ||
          count < 0 || !no_more_words(words))
        throw fail("malformed element line '" + line + "' (expected: element NAME COUNT)");
      e.count = static_cast<std::size_t>(count);
      f.elements_.push_back(e);
    } else if (key == "property") {
      if (f.elements_.empty()) throw fail("a property before any element");
      std::string type, pname;
      words >> type;
      if (type == "list") throw fail("list properties (element '" + f.elements_.back().name + "') are not supported");
      words >> pname;
      const std::optional<PlyType> t = type_from_name(type);
      if (!t || pname.empty() || !no_more_words(words)) throw fail("malformed property line '" + line + "'");
      PlyElement& e = f.elements_.back();
      if (e.find(pname)) throw fail("property '" + pname + "' appears twice");
      e.properties.push_back({pname, *t, e.record_size});
      e.record_size += type_size(*t);
    } else {
      throw fail("unknown header line '" + line + "'");
    }
  }
  if (!have_format) throw fail("no format line");
  if (f.format_ != PlyFormat::ascii) {
    std::size_t at = body;
    for (PlyElement& e : f.elements_) {
      if (e.record_size && e.count > (bytes.size() - at) / e.record_size)
        throw fail("the body ends before the " + std::to_string(e.count) + " records of element '" + e.name + "'");
      e.data_offset = at;
      at += e.count * e.record_size;
    }
    if (at != bytes.size())
      throw fail(std::to_string(bytes.size() - at) + " bytes after the last element (the header's counts do not match the body)");
  }
  f.swap_ = big_endian(f.format_) != (std::endian::native == std::endian::big);
  return body;
}

PlyFile PlyFile::parse_header(std::string_view bytes, const std::filesystem::path& name) {
  PlyFile f;
  parse_layout(bytes, name, f);
  return f;
}

PlyFile PlyFile::parse(std::string bytes, const std::filesystem::path& name) {
  auto fail = [&](const std::string& why) { return InputError(name.string() + ": PLY: " + why); };
  PlyFile f;
  const std::size_t body = parse_layout(bytes, name, f);
  if (f.format_ == PlyFormat::ascii) {
    // Tokens with the whitespace that follows each, so that unchanged values keep their text.
    // Every value takes at least two bytes (a digit and a separator): counts beyond that
    // are refused before any multiplication can wrap or any memory is reserved.
    std::size_t at = body, total = 0;
    const std::size_t most = (bytes.size() - body) / 2 + 1;
    for (const PlyElement& e : f.elements_) {
      if (!e.properties.empty() && e.count > (most - total) / e.properties.size())
        throw fail("element '" + e.name + "' claims " + std::to_string(e.count) + " records, more than the body holds");
      total += e.count * e.properties.size();
    }
    f.ascii_values_.reserve(total);
    for (PlyElement& e : f.elements_) {
      f.ascii_first_.push_back(f.ascii_values_.size());
      for (std::size_t k = 0; k < e.count * e.properties.size(); ++k) {
        const std::size_t start = bytes.find_first_not_of(" \t\r\n", at);
        if (start == std::string::npos)
          throw fail("the body ends before the " + std::to_string(e.count) + " records of element '" + e.name + "'");
        const std::size_t stop = std::min(bytes.find_first_of(" \t\r\n", start), bytes.size());
        f.ascii_values_.push_back(bytes.substr(at, stop - at));  // leading whitespace included
        const std::string token = bytes.substr(start, stop - start);
        double v = 0;
        if (!parse_ascii_value(token, v))
          throw fail("'" + token + "' in element '" + e.name + "' is not a number");
        at = stop;
      }
    }
    f.ascii_tail_ = bytes.substr(at);
    if (f.ascii_tail_.find_first_not_of(" \t\r\n") != std::string::npos)
      throw fail("values after the last element (the header's counts do not match the body)");
  }
  f.data_ = std::move(bytes);
  return f;
}

double PlyFile::get_ascii(const PlyElement& e, std::size_t i, std::size_t p) const {
  const std::size_t e_index = static_cast<std::size_t>(&e - elements_.data());
  const std::string& s = ascii_values_[ascii_first_[e_index] + i * e.properties.size() + p];
  const std::size_t start = s.find_first_not_of(" \t\r\n");
  double v = 0;
  parse_ascii_value(std::string_view(s).substr(start), v);
  return v;
}

double PlyFile::get_binary(PlyType type, const char* at) const {
  switch (type) {
    case PlyType::int8: return load<std::int8_t>(at, swap_);
    case PlyType::uint8: return load<std::uint8_t>(at, swap_);
    case PlyType::int16: return load<std::int16_t>(at, swap_);
    case PlyType::uint16: return load<std::uint16_t>(at, swap_);
    case PlyType::int32: return load<std::int32_t>(at, swap_);
    case PlyType::uint32: return load<std::uint32_t>(at, swap_);
    case PlyType::float32: return load<float>(at, swap_);
    case PlyType::float64: return load<double>(at, swap_);
  }
  return 0;
}

void PlyFile::set_ascii(const PlyElement& e, std::size_t i, std::size_t p, double v) {
  const PlyType type = e.properties[p].type;
  // A value that reads back the same keeps its text (a float32 property holds the
  // float nearest its text).
  const double now = get_ascii(e, i, p);
  if (type == PlyType::float32 ? static_cast<float>(now) == static_cast<float>(v) : now == v) return;
  const std::size_t e_index = static_cast<std::size_t>(&e - elements_.data());
  std::string& s = ascii_values_[ascii_first_[e_index] + i * e.properties.size() + p];
  char text[64];
  const auto r = type == PlyType::float32 ? std::to_chars(text, text + sizeof text, static_cast<float>(v))
                                          : std::to_chars(text, text + sizeof text, v);
  s = s.substr(0, s.find_first_not_of(" \t\r\n")) + std::string(text, r.ptr);
}

void PlyFile::set_binary(PlyType type, char* at, double v) {
  if (type == PlyType::float32) store<float>(at, static_cast<float>(v), swap_);
  else store<double>(at, v, swap_);
}

std::string PlyFile::bytes() const {
  if (format_ != PlyFormat::ascii) return data_;
  std::string out = data_.substr(0, header_size_);
  for (const std::string& s : ascii_values_) out += s;
  return out + ascii_tail_;
}

}  // namespace shtool::interop
