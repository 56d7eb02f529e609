// What the end-to-end tests of the shtool executable share: where shtool and the source
// tree's data are, running shtool (or any program) so that a hang or a crash is a failed
// test with a message, scratch folders and reading back what a command wrote.
// Header-only; SHTOOL_EXE and SHTOOL_SOURCE_DIR come from tests/CMakeLists.txt.
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lighting/image_io.h"
#include "lighting/lighting_output.h"
#include "run_command.h"
#include "schema_check.h"
#include "scratch_files.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool::test {

// Paths are what these tests pass around most: their `using namespace` brings fs along.
namespace fs = std::filesystem;

inline const std::string kShtoolExe = SHTOOL_EXE;
inline const std::string kSourceDir = SHTOOL_SOURCE_DIR;
inline const std::string kSpotObj = kSourceDir + "/data/spot.obj";

// Runs argv. The timeout (240 s unless the options say otherwise: under the 300 s ctest
// gives each test) only turns a hang into a failure that names the command instead of a
// ctest timeout; a child killed by a signal fails the test, so a crash never passes as an
// ordinary non-zero exit.
inline CommandResult run_checked(const std::vector<std::string>& argv, CommandOptions options = {}) {
  if (options.timeout_seconds <= 0) options.timeout_seconds = 240;
  CommandResult r = run_command(argv, options);
  EXPECT_FALSE(r.signaled) << describe_command(argv) << " was killed by signal " << r.signal
                           << (r.timed_out ? " (timed out)" : "") << "\nstderr: " << r.err;
  return r;
}

// shtool with these arguments.
inline CommandResult run_shtool(std::vector<std::string> args, CommandOptions options = {}) {
  args.insert(args.begin(), kShtoolExe);
  return run_checked(args, std::move(options));
}

// A command that has to succeed for the test to mean anything (making inputs).
inline void must(const CommandResult& r) { ASSERT_EQ(r.exit_code, 0) << r.err; }

// A request shtool must refuse: `command args out_option out` exits 1 with `message` in
// its stderr and writes nothing at `out` (removed first: a file an earlier case left must
// not pass for this one's).
inline void expect_refused(const std::string& command, const std::vector<std::string>& args,
                           const std::string& message, const std::filesystem::path& out,
                           const std::string& out_option = "--out") {
  std::filesystem::remove(out);
  std::vector<std::string> argv = {command};
  argv.insert(argv.end(), args.begin(), args.end());
  argv.insert(argv.end(), {out_option, out.string()});
  const CommandResult r = run_shtool(argv);
  EXPECT_EQ(r.exit_code, 1) << message << "\n" << r.err;
  EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out)) << message;
}

// One request shtool must refuse: its arguments, and what the message must name.
struct Refused {
  std::vector<std::string> args;
  std::string message;
};

// expect_refused for every case, its arguments after the `common` ones.
inline void expect_all_refused(const std::string& command, const std::vector<std::string>& common,
                               const std::vector<Refused>& cases, const std::filesystem::path& out) {
  for (const Refused& c : cases) {
    std::vector<std::string> args = common;
    args.insert(args.end(), c.args.begin(), c.args.end());
    expect_refused(command, args, c.message, out);
  }
}

// The table a command has to write: shtool `args` exits 0 with `report` in its stderr,
// then `out` is read as `expect` says.
inline Result<Table> run_and_read_table(const std::vector<std::string>& args, const std::string& report,
                                        const std::filesystem::path& out, const TableExpectation& expect) {
  const CommandResult r = run_shtool(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(report), std::string::npos) << r.err;
  if (r.exit_code != 0) return Error{"shtool failed: " + r.err};
  return read_table(out, expect);
}

inline nlohmann::json read_json(const std::filesystem::path& p) { return nlohmann::json::parse(read_file(p)); }

// An image a command wrote, decoded as shtool decodes its own inputs (alpha dropped).
inline lighting::Image read_image(const std::filesystem::path& p) { return lighting::decode_image(read_file(p), p); }

// The lights of the render tests: constant 1 (a white furnace) and data/sky.hdr projected.
inline void make_white_and_sky_lights(int order, const std::filesystem::path& white, const std::filesystem::path& sky) {
  const std::string o = std::to_string(order);
  must(run_shtool({"light", "--type", "constant", "--color", "1,1,1", "--order", o, "--json", white.string()}));
  must(run_shtool({"project-env", kSourceDir + "/data/sky.hdr", "--order", o, "--json", sky.string()}));
}

// An RGB radiance of `order`: seeded standard normal coefficients times `spread`, with
// `dc` added to each channel's constant term (a light that stays mostly positive).
inline lighting::Lighting random_radiance(int order, unsigned seed, double spread, const std::array<double, 3>& dc) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  lighting::Lighting l;
  l.order = order;
  l.quantity = lighting::Quantity::radiance;
  l.coefficients.resize(static_cast<std::size_t>(sh_count(order)) * 3);
  for (double& v : l.coefficients) v = spread * g(rng);
  for (int c = 0; c < 3; ++c) l.coefficients[c] += dc[c];
  return l;
}

// A test program's scratch files: scratch("x.json") is <temp>/shtool_<suite>_<pid>/x.json.
class Scratch {
 public:
  explicit Scratch(std::string suite) : suite_(std::move(suite)) {}
  std::filesystem::path operator()(const std::string& name) const { return scratch_path(suite_, name); }

 private:
  std::string suite_;
};

// An empty folder of the program's scratch folder named after the running test, for tests
// that check which files a command left behind.
inline std::filesystem::path empty_folder_for_this_test(const Scratch& scratch) {
  const std::filesystem::path dir = scratch(::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  std::filesystem::create_directories(dir);
  return dir;
}

// A command that writes a table at `out` and its JSON summary at `json` on `threads`
// threads: a fit command as its tests run it, small.
using TableAndSummaryCommand = std::function<std::vector<std::string>(const fs::path& out, const fs::path& json, int threads)>;

// What such a command wrote: the table (read as expected) and where, its summary, and the
// table's metadata.
struct TableAndSummary {
  fs::path out;
  Table table;
  nlohmann::json summary, meta;
};

// `command` on 2 threads, which has to exit 0 with `report` in its stderr and write a table
// that reads as `expect` says.
inline Result<TableAndSummary> run_table_and_summary(const Scratch& scratch, const TableAndSummaryCommand& command,
                                                     const std::string& report, const TableExpectation& expect) {
  const fs::path out = scratch("written.shtb"), json = scratch("written.json");
  Result<Table> table = run_and_read_table(command(out, json, 2), report, out, expect);
  if (!table) return table.error();
  nlohmann::json meta = nlohmann::json::parse(table.value().meta);
  return TableAndSummary{out, std::move(table).value(), read_json(json), std::move(meta)};
}

// `command` writes the same table and summary, byte for byte, on 1 thread as on 2.
inline void expect_same_bytes_on_one_and_two_threads(const Scratch& scratch, const TableAndSummaryCommand& command) {
  const fs::path a = scratch("t1.shtb"), aj = scratch("t1.json"), b = scratch("t2.shtb"), bj = scratch("t2.json");
  CommandResult r = run_shtool(command(a, aj, 1));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_shtool(command(b, bj, 2));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_file(a), read_file(b)) << "the table";
  EXPECT_EQ(read_file(aj), read_file(bj)) << "the summary";
}

}  // namespace shtool::test
