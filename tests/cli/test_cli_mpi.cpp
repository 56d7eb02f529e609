// `shtool fit-zh --mpi` and `shtool bake-probes --mpi`. Built with MPI: 2 and 3 ranks
// under mpiexec (oversubscribed on a small machine) write the bytes one process writes,
// shadowed and interreflected (and a probe grid with an invalid probe), a
// refusal reaches every rank, a rank that fails stops the others at the next bounce, and
// rank 0 refuses a rank that read another input.
// Built without MPI: --mpi is a clear error. A missing mpiexec fails the test.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_test.h"
#include "probe_scenes.h"

namespace {

using namespace shtool::test;

// Every random path runs: rays rotated per vertex, a multi-start on every vertex.
const std::vector<std::string> kQuick = {"--rays", "8", "--order", "2", "--lobes", "2", "--starts", "1",
                                         "--restart-above", "0"};

const Scratch scratch("test_cli_mpi");

std::vector<std::string> fit_args(const std::string& mesh, const std::vector<std::string>& extra) {
  std::vector<std::string> args = {kShtoolExe, "fit-zh", mesh};
  args.insert(args.end(), kQuick.begin(), kQuick.end());
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

#ifdef SHTOOL_MPIEXEC

// The environment the ranks inherit from mpiexec.
void prepare_mpirun() {
  // OpenMPI refuses to run as root unless told twice; test machines often are root.
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  // OpenMPI's library and its plugins keep allocations past MPI_Finalize, which
  // LeakSanitizer reports at each rank's exit in the sanitizer build. The ranks run the
  // same job code that the one-process runs beside them run leak-checked.
  setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
}

CommandResult mpirun(int ranks, std::vector<std::string> args) {
  prepare_mpirun();
  args.insert(args.begin(), {SHTOOL_MPIEXEC, "--oversubscribe", "-np", std::to_string(ranks)});
  return run_checked(args);
}

TEST(CliFitZhMpi, RanksWriteTheOneProcessTable) {
  const fs::path whole = scratch("whole.shtb"), whole_json = scratch("whole.json"), whole_glb = scratch("whole.glb");
  const CommandResult one = run_checked(
      fit_args(kSpotObj, {"--out", whole.string(), "--json", whole_json.string(), "--gltf", whole_glb.string()}));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_TRUE(fs::exists(whole_glb));
  for (int ranks : {2, 3}) {
    const fs::path out = scratch("mpi" + std::to_string(ranks) + ".shtb"),
                   json = scratch("mpi" + std::to_string(ranks) + ".json"),
                   glb = scratch("mpi" + std::to_string(ranks) + ".glb");
    // --gltf: rank 0 gathers the other ranks' transfer DC for the vertex colours.
    const CommandResult r = mpirun(ranks, fit_args(kSpotObj, {"--mpi", "--threads", "1", "--out", out.string(), "--json",
                                                           json.string(), "--gltf", glb.string()}));
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE(r.err.find("on each of " + std::to_string(ranks) + " MPI ranks"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(out), read_file(whole)) << ranks << " ranks";
    EXPECT_EQ(read_file(json), read_file(whole_json)) << ranks << " ranks";
    EXPECT_EQ(read_file(glb), read_file(whole_glb)) << ranks << " ranks";
  }
}

TEST(CliFitZhMpi, InterreflectedRanksWriteTheOneProcessTable) {
  // Each rank simulates its rows of every bounce and gathers the whole bounce before the
  // next one; two bounces make one gather read rows another rank bounced.
  const std::vector<std::string> inter = {"--mode", "interreflected", "--bounces", "2", "--albedo", "0.7"};
  std::vector<std::string> whole_args = inter;
  const fs::path whole = scratch("inter_whole.shtb");
  whole_args.insert(whole_args.end(), {"--out", whole.string()});
  const CommandResult one = run_checked(fit_args(kSpotObj, whole_args));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  for (int ranks : {2, 3}) {
    const fs::path out = scratch("inter_mpi" + std::to_string(ranks) + ".shtb");
    std::vector<std::string> args = inter;
    args.insert(args.end(), {"--mpi", "--threads", "1", "--out", out.string()});
    const CommandResult r = mpirun(ranks, fit_args(kSpotObj, args));
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_EQ(read_file(out), read_file(whole)) << ranks << " ranks";
  }
}

TEST(CliFitZhMpi, ARankThatFailsStopsTheOthersAtTheNextBounce) {
  // Rank 1 cannot read its mesh; rank 0 simulates its direct rows and learns it when it
  // gathers them, instead of waiting for rank 1's rows forever.
  const fs::path out = scratch("inter_failed.shtb");
  const std::vector<std::string> inter = {"--mpi", "--mode", "interreflected", "--out", out.string()};
  std::vector<std::string> args = {SHTOOL_MPIEXEC, "--oversubscribe", "-np", "1"};
  const std::vector<std::string> good = fit_args(kSpotObj, inter);
  args.insert(args.end(), good.begin(), good.end());
  args.insert(args.end(), {":", "-np", "1"});
  const std::vector<std::string> bad = fit_args(scratch("missing.obj").string(), inter);
  args.insert(args.end(), bad.begin(), bad.end());
  prepare_mpirun();
  const CommandResult r = run_checked(args);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("rank 0: stopped, another rank failed"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliFitZhMpi, ARefusalStopsEveryRank) {
  const fs::path out = scratch("refused.shtb");
  const CommandResult both = mpirun(2, fit_args(kSpotObj, {"--mpi", "--shard", "0/2", "--out", out.string()}));
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.err.find("--mpi and --shard both split the vertices"), std::string::npos) << both.err;
  EXPECT_FALSE(fs::exists(out));
  // One vector for two ranks: both refuse after reading it.
  const fs::path one = scratch("one.json");
  std::ofstream(one) << R"({"order": 2, "vectors": [[0.8, 0.1, 0.2, 0.3]]})";
  const CommandResult tiny = mpirun(2, {kShtoolExe, "fit-zh", "--transfer", one.string(), "--mpi", "--out", out.string()});
  EXPECT_NE(tiny.exit_code, 0);
  EXPECT_NE(tiny.err.find("2 ranks for 1 vectors would leave some without work"), std::string::npos) << tiny.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliFitZhMpi, RankZeroRefusesRowsOfAnotherInput) {
  // Two programs in one job (MPMD): rank 1 reads a mesh whose first vertex moved.
  std::ifstream in(kSpotObj, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  text.replace(text.find("0.348799"), 8, "0.348800");  // spot's first vertex
  const fs::path moved = scratch("moved.obj"), out = scratch("mixed.shtb");
  std::ofstream(moved) << text;
  std::vector<std::string> args = fit_args(kSpotObj, {"--mpi", "--out", out.string()});
  args.insert(args.begin(), {"-np", "1"});
  args.push_back(":");
  args.insert(args.end(), {"-np", "1"});
  const std::vector<std::string> other = fit_args(moved.string(), {"--mpi", "--out", out.string()});
  args.insert(args.end(), other.begin(), other.end());
  prepare_mpirun();
  args.insert(args.begin(), {SHTOOL_MPIEXEC, "--oversubscribe"});
  const CommandResult r = run_checked(args);
  EXPECT_NE(r.exit_code, 0);
  // Refused before the simulation, from the loaded meshes' checksums.
  EXPECT_NE(r.err.find("--mpi: rank 1's settings and mesh differ from rank 0's"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("rank 0: stopped, another rank's settings and mesh differ"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// Interreflected ranks exchange every bounce: ranks given other --bounces once waited for
// each other for ever, and other orders ended in an internal error. Both are refused by
// every rank before the simulation.
TEST(CliFitZhMpi, RanksThatDisagreeAreRefusedBeforeTheyExchangeBounces) {
  const fs::path out = scratch("disagree.shtb");
  auto rank_args = [&](const std::string& order, const std::string& bounces) {
    return std::vector<std::string>{kShtoolExe,  "fit-zh",  kSpotObj, "--rays",    "8",      "--order",
                                    order,       "--lobes", "1",      "--mpi",     "--mode", "interreflected",
                                    "--bounces", bounces,   "--out",  out.string()};
  };
  for (const std::vector<std::string>& differ :
       {std::vector<std::string>{"--bounces", "2"}, std::vector<std::string>{"--order", "3"}}) {
    std::vector<std::string> args = {SHTOOL_MPIEXEC, "--oversubscribe", "-np", "1"};
    const std::vector<std::string> first = rank_args("2", "1");
    args.insert(args.end(), first.begin(), first.end());
    args.insert(args.end(), {":", "-np", "1"});
    const std::vector<std::string> second =
        differ[0] == "--bounces" ? rank_args("2", differ[1]) : rank_args(differ[1], "1");
    args.insert(args.end(), second.begin(), second.end());
    prepare_mpirun();
    const CommandResult r = run_command(args, {.timeout_seconds = 120});
    EXPECT_FALSE(r.timed_out) << differ[0] << ": the ranks waited for each other";
    EXPECT_NE(r.exit_code, 0) << differ[0];
    EXPECT_NE(r.err.find("--mpi: rank 1's settings and mesh differ from rank 0's"), std::string::npos)
        << differ[0] << ": " << r.err;
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

// bake-probes: 2 and 3 ranks write the one-process table and JSON, the invalid probe
// (inside a solid cube) filled after the gather.
TEST(CliBakeProbesMpi, RanksWriteTheOneProcessTable) {
  const fs::path scene = scratch("solid.gltf");
  write_solid_cube_scene(scene);
  auto bake_args = [&](const fs::path& out, const fs::path& json, bool mpi) {
    std::vector<std::string> a = {kShtoolExe, "bake-probes", scene.string(), "--grid", "3,3,3", "--bounds",
                                  "-1.5,-1.5,-1.5,1.5,1.5,1.5", "--samples", "64", "--order", "2", "--threads", "1",
                                  "--out", out.string(), "--json", json.string()};
    if (mpi) a.push_back("--mpi");
    return a;
  };
  const fs::path whole = scratch("probes_whole.shtb"), whole_json = scratch("probes_whole.json");
  const CommandResult one = run_checked(bake_args(whole, whole_json, false));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  for (int ranks : {2, 3}) {
    const fs::path out = scratch("probes_mpi" + std::to_string(ranks) + ".shtb"),
                   json = scratch("probes_mpi" + std::to_string(ranks) + ".json");
    const CommandResult r = mpirun(ranks, bake_args(out, json, true));
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE(r.err.find("on each of " + std::to_string(ranks) + " MPI ranks"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(out), read_file(whole)) << ranks << " ranks";
    EXPECT_EQ(read_file(json), read_file(whole_json)) << ranks << " ranks";
  }
  // An encoded grid: rank 0 fills, then encodes (bake-probes --encoding zh3).
  auto zh3_args = [&](const fs::path& out, const fs::path& json, bool mpi) {
    std::vector<std::string> a = bake_args(out, json, mpi);
    *(std::find(a.begin(), a.end(), "--order") + 1) = "3";
    a.insert(a.end(), {"--encoding", "zh3"});
    return a;
  };
  ASSERT_EQ(run_checked(zh3_args(scratch("zh3_whole.shtb"), scratch("zh3_whole.json"), false)).exit_code, 0);
  const std::vector<std::string> zh3_mpi = zh3_args(scratch("zh3_mpi.shtb"), scratch("zh3_mpi.json"), true);
  const CommandResult r = mpirun(2, zh3_mpi);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(read_file(scratch("zh3_mpi.shtb")), read_file(scratch("zh3_whole.shtb")));
  EXPECT_EQ(read_file(scratch("zh3_mpi.json")), read_file(scratch("zh3_whole.json")));
}

#else

TEST(CliBakeProbesMpi, WithoutMpiTheOptionIsAClearError) {
  const fs::path out = scratch("probes_nompi.shtb");
  const CommandResult r = run_checked({kShtoolExe, "bake-probes", kSpotObj, "--grid", "2,2,2", "--mpi", "--out",
                                       out.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("built without MPI"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(CliFitZhMpi, WithoutMpiTheOptionIsAClearError) {
  const fs::path out = scratch("nompi.shtb");
  const CommandResult r = run_checked(fit_args(kSpotObj, {"--mpi", "--out", out.string()}));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("built without MPI"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

#endif

}  // namespace
