// Reading the offline tool's input files: the one place that opens them, so every input
// gets the same checks and messages (a folder, a missing file, a read error, JSON that
// is malformed or nested absurdly deep).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace shtool {

// The whole file as bytes. `what` names the input in messages ("--transfer", "mesh").
// Throws InputError.
std::string read_input_file(const std::filesystem::path& path, std::string_view what);

// All of standard input as bytes, for an option given "-". A closed stdin, a read error
// and empty input are refused by name ("--in -: standard input is closed"), so none of
// them reaches a parser as "unexpected end of input". Throws InputError.
std::string read_standard_input(std::string_view what);

// A whole input file mapped read-only into memory, for the big ones (images): the pages
// are read ahead and used in place, never copied (a 100 MB EXR: 0.06 s against 0.43 s
// through read_input_file here, where first touches of fresh memory are slow). The same
// checks and messages as read_input_file; a file that cannot be mapped (empty, a pipe)
// is read instead. The file must not shrink while it is mapped.
class MappedInput {
 public:
  MappedInput(const std::filesystem::path& path, std::string_view what);
  ~MappedInput();
  MappedInput(const MappedInput&) = delete;
  MappedInput& operator=(const MappedInput&) = delete;
  std::string_view bytes() const { return map_ ? std::string_view(static_cast<const char*>(map_), size_) : read_; }

 private:
  void* map_ = nullptr;
  std::size_t size_ = 0;
  std::string read_;
};

// A file name's extension in lower case (".glb" for "Scene.GLB"): formats go by it.
std::string lowercase_extension(const std::filesystem::path& path);

// Parses `text` (the contents of `path`) as JSON. Throws InputError naming the input, the
// parser's position and message, or nesting deeper than the tables' limit (64 levels,
// refused before parsing so that no later step can exhaust the stack).
nlohmann::json parse_json_input(std::string_view text, const std::filesystem::path& path, std::string_view what);

// read_input_file + parse_json_input.
nlohmann::json read_json_input(const std::filesystem::path& path, std::string_view what);

// The CRC-32 of bytes (as table_crc32): records which input a table was made from.
std::uint32_t input_crc32(std::string_view bytes);

}  // namespace shtool
