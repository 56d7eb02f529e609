#include "common/input_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <system_error>

#include "common/input_error.h"
#include "io/table_format.h"
#include "shtool/table.h"

namespace shtool {
namespace {

std::string where(const std::filesystem::path& path, std::string_view what) {
  return std::string(what) + " '" + path.string() + "'";
}

}  // namespace

std::string read_input_file(const std::filesystem::path& path, std::string_view what) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw InputError(where(path, what) + ": no such file");
  if (std::filesystem::is_directory(status)) throw InputError(where(path, what) + ": is a folder, not a file");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(where(path, what) + ": cannot open: " + std::strerror(errno));
  std::string bytes;
  char buf[1 << 16];
  for (;;) {
    const std::size_t n = std::fread(buf, 1, sizeof buf, f.get());
    bytes.append(buf, n);
    if (n < sizeof buf) break;
  }
  if (std::ferror(f.get())) throw InputError(where(path, what) + ": read error: " + std::strerror(errno));
  return bytes;
}

nlohmann::json parse_json_input(std::string_view text, const std::filesystem::path& path, std::string_view what) {
  if (auto problem = table_format::check_json_depth(text, table_format::kMaxJsonDepth))
    throw InputError(where(path, what) + ": JSON " + *problem);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(where(path, what) + ": not valid JSON: " + e.what());
  }
}

nlohmann::json read_json_input(const std::filesystem::path& path, std::string_view what) {
  return parse_json_input(read_input_file(path, what), path, what);
}

std::uint32_t input_crc32(std::string_view bytes) {
  return table_crc32(std::span<const std::byte>(reinterpret_cast<const std::byte*>(bytes.data()), bytes.size()));
}

}  // namespace shtool
