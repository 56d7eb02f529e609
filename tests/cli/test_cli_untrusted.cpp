// The command line on the inputs that once crashed it, overwrote an input, left partial
// outputs or said "internal error": each must exit 1 with a message naming the problem
// and leave no output behind (docs/reliability.md).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "run_command.h"

namespace shtool {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;

class CliUntrusted : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shtool-test-untrusted-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    mesh_ = dir_ / "m.obj";
    fs::copy_file(fs::path(SHTOOL_SOURCE_DIR) / "data/spot.obj", mesh_);
    std::ofstream(dir_ / "t.json") << R"({"order":2,"vectors":[[1,0.1,0.2,0.3]]})";
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  CommandResult run(std::vector<std::string> args, const std::string& stdin_data = "") {
    args.insert(args.begin(), SHTOOL_EXE);
    test::CommandOptions o;
    o.stdin_data = stdin_data;
    o.timeout_seconds = 120;
    return test::run_command(args, o);
  }
  // Exit 1, the fragment in the message, no "internal error".
  void expect_refused(const CommandResult& r, const std::string& fragment) {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << "stderr '" << r.err << "' lacks '" << fragment << "'";
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_, mesh_;
};

TEST_F(CliUntrusted, OutputsThatAreTheInputOrEachOtherAreRefused) {
  const std::uintmax_t size = fs::file_size(mesh_);
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--out", mesh_.string()}), "is the input");
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--ply", (dir_ / "." / "m.obj").string()}),
                 "is the input");
  EXPECT_EQ(fs::file_size(mesh_), size) << "the mesh was overwritten";
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--out", (dir_ / "x").string(), "--json",
                      (dir_ / "x").string()}),
                 "name the same file");
  EXPECT_EQ(listing(), (std::vector<std::string>{"m.obj", "t.json"}));
}

TEST_F(CliUntrusted, AllOutputsOrNone) {
  // The second output's folder does not exist: refused before the bake, nothing written.
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--out", (dir_ / "ok.shtb").string(), "--json",
                      (dir_ / "nodir" / "x.json").string()}),
                 "does not exist");
  expect_refused(run({"search-lobes", "--band", "2", "--restarts", "1", "--out", (dir_ / "l.shtb").string(),
                      "--json", (dir_ / "nodir" / "l.json").string()}),
                 "does not exist");
  // gen-tensors whose kernel target is a folder: no table, no temporary file.
  fs::create_directories(dir_ / "k" / "rotation_kernels_generated.inc");
  expect_refused(run({"gen-tensors", "--what", "rotation,rotation-kernels", "--out", (dir_ / "k").string()}),
                 "is a folder");
  EXPECT_FALSE(fs::exists(dir_ / "k" / "rotation-helpers.shtb"));
  EXPECT_EQ(listing(), (std::vector<std::string>{"k", "m.obj", "t.json"}));
  std::size_t in_k = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "k")) in_k += e.path().filename() != "rotation_kernels_generated.inc";
  EXPECT_EQ(in_k, 0u);
}

TEST_F(CliUntrusted, FoldersAndMissingFilesAreNamed) {
  expect_refused(run({"product", "--order", "2", "--in", dir_.string()}), "is a folder");
  expect_refused(run({"fit-zh", "--transfer", dir_.string()}), "is a folder");
  expect_refused(run({"rotate", "--order", "2", "--zyz", "0,0,0", "--in", dir_.string()}), "is a folder");
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--ply", dir_.string()}), "is a folder");
}

TEST_F(CliUntrusted, LimitsAreRefusedWithTheirFigures) {
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "t.json").string(), "--threads", "100000"}), "at most");
  expect_refused(run({"search-lobes", "--band", "3", "--threads", "100000"}), "at most");
  expect_refused(run({"search-lobes", "--band", "100"}), "GiB");
  expect_refused(run({"fit-zh", mesh_.string(), "--mode", "interreflected", "--bounces", "2147483647"}),
                 "--bounces must be in 1..64");
  const CommandResult seed = run({"fit-zh", "--transfer", (dir_ / "t.json").string(), "--seed", "-1"});
  EXPECT_EQ(seed.exit_code, 1) << seed.err;
  EXPECT_NE(seed.err.find("must not be negative"), std::string::npos) << seed.err;
}

TEST_F(CliUntrusted, HugeValuesNeverBecomeNullOrNan) {
  std::ofstream(dir_ / "huge.json") << R"({"order":3,"vectors":[[1,8,1e308,3,8,8,0,3,3]]})";
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "huge.json").string(), "--out", (dir_ / "h.shtb").string()}),
                 "beyond 1e100");
  EXPECT_FALSE(fs::exists(dir_ / "h.shtb"));
  expect_refused(run({"rotate", "--order", "2", "--zyz", "0.3,1,0.2", "--coeffs", "1.7e308,1.7e308,1.7e308,1.7e308",
                      "--method", "reference"}),
                 "overflow");
}

TEST_F(CliUntrusted, DeepJsonIsAnErrorNotACrash) {
  const std::string deep = "{\"inputs\": " + std::string(52000, '[') + std::string(52000, ']') + "}";
  expect_refused(run({"product", "--order", "2", "--in", "-"}, deep), "nested more than");
  std::ofstream(dir_ / "deep.json") << "{\"order\": 2, \"vectors\": " << std::string(52000, '[') << "}";
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "deep.json").string()}), "nested more than");
  std::ofstream(dir_ / "deep.shtb") << "{\"format\": " << std::string(52000, '[');
  expect_refused(run({"inspect", (dir_ / "deep.shtb").string()}), "nested more than");
}

}  // namespace
}  // namespace shtool
