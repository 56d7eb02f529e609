// Files of the end-to-end tests: a scratch folder per test program and process (so
// parallel test programs never share one), and whole-file reads.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <sys/types.h>
#include <unistd.h>

namespace shtool::test {

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

inline void write_file(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary);
  f << bytes;
  if (!f) throw std::runtime_error("cannot write " + p.string());
}

// The scratch folders this process made, removed when it exits normally (a test that
// fails an assertion still exits normally), so that test runs do not fill the temp
// folder. Only by the process that made them: a forked child that exits must not.
struct ScratchFolders {
  std::vector<std::filesystem::path> made;
  pid_t owner = ::getpid();
  ~ScratchFolders() {
    if (::getpid() != owner) return;
    for (const auto& dir : made) {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  }
};
inline ScratchFolders& scratch_folders() {
  static ScratchFolders folders;
  return folders;
}

// <temp>/shtool_<suite>_<pid>/<name>, the folder made on first use.
inline std::filesystem::path scratch_path(const std::string& suite, const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("shtool_" + suite + "_" + std::to_string(::getpid()));
  ScratchFolders& folders = scratch_folders();  // constructed before the folder exists
  if (std::filesystem::create_directories(dir)) folders.made.push_back(dir);
  return dir / name;
}

}  // namespace shtool::test
