// Checks shared by the tests of generated runtime sources (`shtool gen-tensors --what
// <kind>-kernels --out src/runtime/kernels`): the committed file is what the generator writes,
// byte for byte, both through the library call and through the command line.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "run_command.h"
#include "scratch_files.h"

namespace shtool::test {

// First differing line, for the failure message.
inline std::string first_difference(const std::string& generated, const std::string& committed) {
  std::istringstream sa(generated), sb(committed);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool ga = static_cast<bool>(std::getline(sa, la)), gb = static_cast<bool>(std::getline(sb, lb));
    if (!ga && !gb) return "no line differs (line endings?)";
    if (!ga || !gb || la != lb)
      return "line " + std::to_string(line) + ":\n  committed: " + (gb ? lb : "<end>") +
             "\n  generated: " + (ga ? la : "<end>");
  }
}

// `what`: the gen-tensors item (e.g. "tripling-kernels"); `file`: its name in src/runtime/kernels;
// `generated`: the generator's text.
inline void expect_committed_source(const std::string& what, const std::string& file,
                                    const std::string& generated) {
  const std::string regenerate = "regenerate with: shtool gen-tensors --what " + what + " --out src/runtime/kernels";
  const std::filesystem::path committed = std::filesystem::path(SHTOOL_SOURCE_DIR) / "src/runtime/kernels" / file;
  const std::string want = read_file(committed);
  ASSERT_FALSE(want.empty()) << "cannot read " << committed;
  EXPECT_TRUE(generated == want) << committed << " differs from its generator at "
                                 << first_difference(generated, want) << "\n" << regenerate;

  std::string pattern = (std::filesystem::temp_directory_path() / "shtool-test-kernels-XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const std::filesystem::path dir = pattern;
  const CommandResult r = run_command({SHTOOL_EXE, "gen-tensors", "--what", what, "--out", dir.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  const std::string written = read_file(dir / file);
  EXPECT_TRUE(!written.empty() && written == want) << "gen-tensors: " << first_difference(written, want)
                                                   << "\n" << regenerate;
  EXPECT_FALSE(std::filesystem::exists(dir / (file + ".tmp")));
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

}  // namespace shtool::test
