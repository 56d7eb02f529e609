// The consumers' own code for the interop tests: three.js, Babylon.js,
// @playcanvas/splat-transform and the Khronos glTF validator, installed from npm
// (tests/consumer/node/package.json, exact versions) into <build>/node_consumers once,
// with the scripts of tests/consumer/node copied beside them. Returns false with the
// reason when node or npm cannot do it; the tests then fail under CI and skip elsewhere.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "run_command.h"

namespace shtool::test {

inline std::filesystem::path node_consumers_dir() {
  return std::filesystem::path(SHTOOL_BINARY_DIR) / "node_consumers";
}

inline bool node_consumers(std::string& why) {
  namespace fs = std::filesystem;
  const fs::path dir = node_consumers_dir(), source = fs::path(SHTOOL_SOURCE_DIR) / "tests/consumer/node";
  if (run_command({"node", "--version"}).exit_code != 0) return why = "node is not installed", false;
  fs::create_directories(dir);
  // Tests run in parallel: one npm install at a time, the others wait for it.
  const int lock = ::open((dir / ".lock").c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) return why = "cannot lock " + (dir / ".lock").string(), false;
  struct Unlock {
    int fd;
    ~Unlock() { ::close(fd); }
  } unlock{lock};
  const bool same_manifest = fs::exists(dir / "package.json") && fs::exists(dir / "node_modules") &&
                             fs::last_write_time(dir / "package.json") >= fs::last_write_time(source / "package.json");
  if (!same_manifest) {
    fs::copy_file(source / "package.json", dir / "package.json", fs::copy_options::overwrite_existing);
    CommandOptions o;
    o.working_directory = dir.string();
    o.timeout_seconds = 900;
    const CommandResult r = run_command({"npm", "install", "--no-audit", "--no-fund", "--loglevel=error"}, o);
    if (r.exit_code != 0) return why = "npm install failed: " + r.err, false;
  }
  for (const auto& f : fs::directory_iterator(source))
    if (f.path().extension() == ".mjs") fs::copy_file(f.path(), dir / f.path().filename(), fs::copy_options::overwrite_existing);
  return true;
}

}  // namespace shtool::test

// In a test body: installs the consumers, or ends the test, failed under CI (where they
// must run) and skipped elsewhere.
#define SHTOOL_REQUIRE_NODE_CONSUMERS()                                          \
  do {                                                                           \
    std::string node_consumers_missing;                                          \
    if (!::shtool::test::node_consumers(node_consumers_missing)) {               \
      if (std::getenv("CI")) FAIL() << node_consumers_missing;                   \
      GTEST_SKIP() << node_consumers_missing << " (set CI to make this a failure)"; \
    }                                                                            \
  } while (false)
