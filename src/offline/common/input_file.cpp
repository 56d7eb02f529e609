#include "common/input_file.h"

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <system_error>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "common/input_error.h"
#include "io/table_format.h"
#include "shtool/table.h"

namespace shtool {

std::string lowercase_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}
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
  // Straight into a buffer of the file's size: a big image is copied once, not through a
  // bounce buffer into a string that doubles (which cost 0.9 s for a 100 MB EXR here). The
  // size is a hint: a file that grows or shrinks meanwhile is read to its end all the same.
  std::string bytes;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > 0 && size < (std::uintmax_t(1) << 40)) bytes.resize(static_cast<std::size_t>(size));
  std::size_t filled = std::fread(bytes.data(), 1, bytes.size(), f.get());
  if (filled == bytes.size()) {
    char buf[1 << 16];
    for (;;) {
      const std::size_t n = std::fread(buf, 1, sizeof buf, f.get());
      bytes.append(buf, n);
      filled += n;
      if (n < sizeof buf) break;
    }
  }
  bytes.resize(filled);
  if (std::ferror(f.get())) throw InputError(where(path, what) + ": read error: " + std::strerror(errno));
  return bytes;
}

std::string read_standard_input(std::string_view what) {
  const std::string name = std::string(what) + " -";
  if (::fcntl(STDIN_FILENO, F_GETFD) == -1) throw InputError(name + ": standard input is closed");
  std::string bytes;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
    if (n > 0) {
      bytes.append(buf, static_cast<std::size_t>(n));
    } else if (n == 0) {
      break;
    } else if (errno != EINTR) {
      throw InputError(name + ": cannot read standard input: " + std::strerror(errno));
    }
  }
  if (bytes.empty()) throw InputError(name + ": standard input is empty");
  return bytes;
}

MappedInput::MappedInput(const std::filesystem::path& path, std::string_view what) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw InputError(where(path, what) + ": no such file");
  if (std::filesystem::is_directory(status)) throw InputError(where(path, what) + ": is a folder, not a file");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(where(path, what) + ": cannot open: " + std::strerror(errno));
  struct stat st{};
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
    void* p = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (p != MAP_FAILED) {
      map_ = p;
      size_ = static_cast<std::size_t>(st.st_size);
    }
  }
  ::close(fd);
  if (!map_) read_ = read_input_file(path, what);
}

MappedInput::~MappedInput() {
  if (map_) ::munmap(map_, size_);
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

// zlib's CRC-32 is table_crc32's (the same polynomial and conditioning), computed several
// bytes at a time: an input image of 100 MB is hashed in tens of milliseconds, not a
// quarter of a second.
std::uint32_t input_crc32(std::string_view bytes) {
  return static_cast<std::uint32_t>(
      crc32_z(0, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<z_size_t>(bytes.size())));
}

}  // namespace shtool
