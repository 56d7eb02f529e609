// PLY files as 3D Gaussian Splatting tools write them: a header, then elements of
// fixed-size scalar properties, binary (little or big endian) or ASCII. The header is
// kept byte for byte and each value is addressed in place, so a file can be rewritten
// with some values changed and everything else (comments, extra properties, their
// order and types) untouched.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shtool::interop {

enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };
enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

struct PlyProperty {
  std::string name;
  PlyType type;
  std::size_t offset = 0;  // binary: byte offset in the element's record
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t record_size = 0;  // binary
  std::size_t data_offset = 0;  // binary: first record's byte offset in the file

  std::optional<std::size_t> find(std::string_view property) const;
};

// The parsed header of a whole file held in memory. ASCII bodies are split into their
// numbers (text spans) once.
class PlyFile {
 public:
  // Throws InputError naming `name` on a malformed header, list properties, unknown
  // types, or a body shorter or longer than the header says.
  static PlyFile parse(std::string bytes, const std::filesystem::path& name);
  // The header alone, with the same checks (a binary body's size included), for a file
  // read in place elsewhere (mapped): elements, properties and their offsets, no values
  // (get and set are not to be called on it). An ASCII body is not looked at.
  static PlyFile parse_header(std::string_view bytes, const std::filesystem::path& name);

  PlyFormat format() const { return format_; }
  // Binary: whether the file's byte order is the machine's (values can be used in place).
  bool native_order() const { return !swap_; }
  std::size_t header_size() const { return header_size_; }
  const std::vector<PlyElement>& elements() const { return elements_; }
  const PlyElement* element(std::string_view name) const;

  // Value of property p of record i of element e, as double (any type).
  double get(const PlyElement& e, std::size_t i, std::size_t p) const {
    if (format_ == PlyFormat::ascii) return get_ascii(e, i, p);
    const PlyProperty& q = e.properties[p];
    const char* at = data_.data() + e.data_offset + i * e.record_size + q.offset;
    // The common case inline: float32 in the machine's byte order.
    if (q.type == PlyType::float32 && !swap_) {
      float v;
      std::memcpy(&v, at, sizeof v);
      return v;
    }
    return get_binary(q.type, at);
  }
  // Writes v into that place (binary: the property's type, in the file's byte order;
  // ASCII: the shortest text that reads back to the same float32 / float64 value).
  // Only float32 / float64 properties are written.
  void set(const PlyElement& e, std::size_t i, std::size_t p, double v) {
    if (format_ == PlyFormat::ascii) return set_ascii(e, i, p, v);
    const PlyProperty& q = e.properties[p];
    char* at = data_.data() + e.data_offset + i * e.record_size + q.offset;
    if (q.type == PlyType::float32 && !swap_) {
      const float f = static_cast<float>(v);
      std::memcpy(at, &f, sizeof f);
      return;
    }
    set_binary(q.type, at, v);
  }

  // The file's bytes with every set() applied: a view of them in place for binary files
  // (no copy of a multi-GiB scene), text assembled for ASCII ones.
  std::string_view binary_bytes() const { return data_; }
  std::string bytes() const;
  // The binary bytes handed over (the file is empty afterwards): no copy of the scene.
  std::string take_binary_bytes() { return std::move(data_); }

 private:
  // Everything but the ASCII body's values; returns the body's offset.
  static std::size_t parse_layout(std::string_view bytes, const std::filesystem::path& name, PlyFile& f);
  double get_ascii(const PlyElement& e, std::size_t i, std::size_t p) const;
  void set_ascii(const PlyElement& e, std::size_t i, std::size_t p, double v);
  double get_binary(PlyType type, const char* at) const;
  void set_binary(PlyType type, char* at, double v);

  PlyFormat format_ = PlyFormat::binary_little_endian;
  bool swap_ = false;  // the file's byte order is not the machine's
  std::string data_;
  std::size_t header_size_ = 0;
  std::vector<PlyElement> elements_;
  // ASCII: the text of every value, element by element, record-major.
  std::vector<std::string> ascii_values_;
  std::vector<std::size_t> ascii_first_;  // index of each element's first value
  std::string ascii_tail_;                // text after the last value (line ending)
};

}  // namespace shtool::interop
