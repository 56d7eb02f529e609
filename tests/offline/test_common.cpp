// The offline floor (src/offline/common): atomic outputs, the job frame's output sets
// (all or none, checked against inputs, signals), the
// thread pool's determinism and error propagation, the input reader's messages, and the
// platform-stable random draws against the standard library they reproduce.
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <csignal>
#include <functional>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <sched.h>

#include <gtest/gtest.h>

#include "common/atomic_file.h"
#include "common/finite.h"
#include "common/input_error.h"
#include "common/job_outputs.h"
#include "common/input_file.h"
#include "common/parallel_for.h"
#include "common/random.h"
#include "shtool/table.h"

namespace shtool {
namespace {

namespace fs = std::filesystem;

class CommonFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("shtool-test-common-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  static std::string read(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }
  fs::path dir_;
};

TEST_F(CommonFiles, AtomicWriteReplacesAndLeavesNoTemporary) {
  write_file_atomically(dir_ / "a.txt", "first");
  write_file_atomically(dir_ / "a.txt", "second");
  EXPECT_EQ(read(dir_ / "a.txt"), "second");
  EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
}

TEST_F(CommonFiles, AbandonedPendingFileRemovesItsTemporary) {
  write_file_atomically(dir_ / "a.txt", "old");
  {
    PendingFile f(dir_ / "a.txt");
    f.write(std::string_view("new, never committed"));
    f.finish();
    EXPECT_EQ(listing().size(), 2u) << "the temporary file exists while pending";
  }
  EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
  EXPECT_EQ(read(dir_ / "a.txt"), "old");
}

TEST_F(CommonFiles, OutputSetIsAllOrNothing) {
  write_file_atomically(dir_ / "keep.txt", "old");
  // A second output after "keep.txt" as --a: refused when it is declared, with `needle`.
  auto expect_second_refused = [&](const fs::path& second, const std::string& needle) {
    JobOutputs io;
    io.output(dir_ / "keep.txt", "--a");
    try {
      io.output(second, "--b");
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // Its folder does not exist.
  expect_second_refused(dir_ / "missing" / "b.txt", "does not exist");
  // Two outputs naming one file (here through a different spelling).
  expect_second_refused(dir_ / "." / "keep.txt", "--b and --a name the same file");
  EXPECT_EQ(read(dir_ / "keep.txt"), "old");
  // And a good set writes both.
  JobOutputs io;
  io.output(dir_ / "keep.txt", "--a");
  io.output(dir_ / "b.txt", "--b");
  EXPECT_TRUE(io.requested("--b"));
  EXPECT_FALSE(io.requested("--c"));
  io.set("--a", "A");
  io.set("--b", "B");
  io.commit();
  EXPECT_EQ(read(dir_ / "keep.txt"), "A");
  EXPECT_EQ(read(dir_ / "b.txt"), "B");
  EXPECT_EQ(listing(), (std::vector<std::string>{"b.txt", "keep.txt"}));
}

TEST_F(CommonFiles, OutputsNeverNameAnInputWhateverTheSpelling) {
  write_file_atomically(dir_ / "mesh.obj", "v 0 0 0\n");
  fs::create_hard_link(dir_ / "mesh.obj", dir_ / "linked.obj");
  fs::create_symlink(dir_ / "mesh.obj", dir_ / "symlinked.obj");
  for (const fs::path& out : {dir_ / "mesh.obj", dir_ / "linked.obj", dir_ / "symlinked.obj",
                              dir_ / "sub" / ".." / "mesh.obj"}) {
    fs::create_directories(dir_ / "sub");
    // Declared in either order.
    for (bool input_first : {true, false}) {
      JobOutputs io;
      try {
        if (input_first) io.input(dir_ / "mesh.obj", "the mesh");
        io.output(out, "--out");
        if (!input_first) io.input(dir_ / "mesh.obj", "the mesh");
        FAIL() << out;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--out: '"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("(the mesh); refusing to overwrite it"), std::string::npos) << e.what();
      }
    }
  }
  EXPECT_EQ(read(dir_ / "mesh.obj"), "v 0 0 0\n");
}

TEST_F(CommonFiles, AFailedRenameGivesTheReplacedOutputsBackTheirContents) {
  write_file_atomically(dir_ / "a.txt", "old a");
  write_file_atomically(dir_ / "b.txt", "old b");
  JobOutputs io;
  io.output(dir_ / "a.txt", "--a");
  io.output(dir_ / "b.txt", "--b");
  io.output(dir_ / "c.txt", "--c");  // new
  io.set("--a", "new a");
  io.set("--b", "new b");
  io.set("--c", "new c");
  io.stage();
  // The last of three cannot be replaced any more: a folder took its place (with a file
  // in it, so that no rename can remove it).
  fs::create_directories(dir_ / "c.txt");
  write_file_atomically(dir_ / "c.txt" / "inside", "x");
  try {
    io.publish();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--c: cannot move the finished file into place"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("no output was changed"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read(dir_ / "a.txt"), "old a");
  EXPECT_EQ(read(dir_ / "b.txt"), "old b");
  // No temporary file and no kept copy is left.
  EXPECT_EQ(listing(), (std::vector<std::string>{"a.txt", "b.txt", "c.txt"}));
  // The same, with the first output new: it goes again.
  JobOutputs again;
  again.output(dir_ / "new.txt", "--a");
  again.output(dir_ / "d.txt", "--b");
  again.set("--a", "new a");
  again.set("--b", "new b");
  again.stage();
  fs::create_directories(dir_ / "d.txt" / "x");
  EXPECT_THROW(again.publish(), InputError);
  EXPECT_EQ(listing(), (std::vector<std::string>{"a.txt", "b.txt", "c.txt", "d.txt"}));
}

// The child ends by the signal it raised; what it leaves in the folder is the test.
int child_status(const std::function<void()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    body();
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

TEST_F(CommonFiles, ASignalRemovesTheTemporaryFilesThenEndsTheProcessAsItWould) {
  write_file_atomically(dir_ / "a.txt", "old");
  for (int sig : {SIGTERM, SIGINT}) {
    const int status = child_status([&] {
      JobOutputs io;
      io.output(dir_ / "a.txt", "--a");
      io.output(dir_ / "b.txt", "--b");
      io.set("--a", "new");
      io.set("--b", "new");
      io.stage();  // both temporary files exist now
      std::raise(sig);
      ::_exit(42);  // not reached
    });
    ASSERT_TRUE(WIFSIGNALED(status)) << status;
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
    EXPECT_EQ(read(dir_ / "a.txt"), "old");
  }
}

// Folders made for the outputs go too (innermost first), as they do when the job fails;
// a folder that holds something else stays.
TEST_F(CommonFiles, ASignalRemovesTheFoldersMadeForTheOutputs) {
  for (int sig : {SIGTERM, SIGINT}) {
    const int status = child_status([&] {
      MadeFolders made;
      made.make(dir_ / "new" / "deep" / "er", "--out");
      made.make(dir_ / "kept", "--out");
      write_file_atomically(dir_ / "kept" / "someone-else.txt", "x");
      JobOutputs io;
      io.output(dir_ / "new" / "deep" / "er" / "a.txt", "--a");
      io.set("--a", "new");
      io.stage();  // the temporary file exists in the innermost folder
      std::raise(sig);
      ::_exit(42);  // not reached
    });
    ASSERT_TRUE(WIFSIGNALED(status)) << status;
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(listing(), std::vector<std::string>{"kept"});
    fs::remove_all(dir_ / "kept");
  }
}

TEST_F(CommonFiles, ASignalDuringACommitWaitsForItsEnd) {
  const int status = child_status([&] {
    PendingFile f(dir_ / "a.txt");
    f.write(std::string_view("done"));
    f.finish();
    {
      const CommitGuard guard;
      std::raise(SIGTERM);  // held back
      f.commit();
    }
    ::_exit(42);  // not reached: the guard's end delivers the signal
  });
  ASSERT_TRUE(WIFSIGNALED(status)) << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
  EXPECT_EQ(read(dir_ / "a.txt"), "done");
}

TEST_F(CommonFiles, OutputPathChecksNameTheProblem) {
  try {
    check_output_path(dir_, "--out");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--out: cannot write"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is a folder"), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_output_path(dir_ / "no" / "x", "--json"), InputError);
  EXPECT_NO_THROW(check_output_path(dir_ / "x", "--json"));
  EXPECT_EQ(listing(), std::vector<std::string>{}) << "the trial file is removed";
  // A folder that exists but takes no file (even for root): refused before any work, by
  // the option's name.
  try {
    check_output_path("/proc/shtool-test.json", "--json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--json: cannot write '/proc/shtool-test.json': cannot create a "
                                         "temporary file in '/proc'"),
              std::string::npos)
        << e.what();
  }
}

// A write that fails at the commit still names the option (the folder went away after
// the checks).
TEST_F(CommonFiles, CommitFailureNamesTheOption) {
  fs::create_directory(dir_ / "sub");
  JobOutputs outputs;
  outputs.output(dir_ / "sub" / "x.json", "--json");
  fs::remove(dir_ / "sub");
  outputs.set("--json", "{}");
  try {
    outputs.commit();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--json: cannot write", 0), 0u) << e.what();
  }
  EXPECT_EQ(listing(), std::vector<std::string>{});
}

// A rename into place replaces whatever the path is: a link that names a file is written
// through (the link stays), and a FIFO or a device is refused before any work (the rename
// would have turned /dev/full, or the FIFO a reader waits on, into a regular file).
TEST_F(CommonFiles, OutputsWriteThroughLinksAndRefuseSpecialFiles) {
  write_file_atomically(dir_ / "target.json", "old");
  fs::create_symlink("target.json", dir_ / "link.json");
  JobOutputs outputs;
  outputs.output(dir_ / "link.json", "--out");
  outputs.set("--out", "new");
  outputs.commit();
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.json"));
  EXPECT_EQ(read(dir_ / "target.json"), "new");
  // A chain of links, and one whose file does not exist yet.
  fs::create_symlink("link.json", dir_ / "chain.json");
  write_file_atomically(dir_ / "chain.json", "chained");
  EXPECT_TRUE(fs::is_symlink(dir_ / "chain.json"));
  EXPECT_EQ(read(dir_ / "target.json"), "chained");
  fs::create_symlink("later.json", dir_ / "dangling.json");
  // Two outputs of one job, one through the link to a file not yet there: the same file.
  {
    JobOutputs two;
    two.output(dir_ / "later.json", "--out");
    EXPECT_THROW(two.output(dir_ / "dangling.json", "--json"), InputError);
    JobOutputs other_order;
    other_order.output(dir_ / "dangling.json", "--json");
    EXPECT_THROW(other_order.output(dir_ / "later.json", "--out"), InputError);
  }
  write_file_atomically(dir_ / "dangling.json", "created");
  EXPECT_TRUE(fs::is_symlink(dir_ / "dangling.json"));
  EXPECT_EQ(read(dir_ / "later.json"), "created");
  // The input seen through a link is still the input.
  JobOutputs same;
  same.input(dir_ / "target.json", "the table");
  EXPECT_THROW(same.output(dir_ / "link.json", "--out"), InputError);

  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  for (const fs::path& special : {dir_ / "fifo", fs::path("/dev/null")}) {
    try {
      JobOutputs o;
      o.output(special, "--json");
      FAIL() << special;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--json: cannot write '" + special.string() + "': it is a"),
                std::string::npos)
          << e.what();
    }
    EXPECT_THROW(write_file_atomically(special, "x"), InputError);
  }
  EXPECT_TRUE(fs::is_fifo(dir_ / "fifo"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  fs::create_symlink("fifo", dir_ / "to-fifo");
  EXPECT_THROW(write_file_atomically(dir_ / "to-fifo", "x"), InputError);
  EXPECT_TRUE(fs::is_fifo(dir_ / "fifo"));
}

TEST_F(CommonFiles, InputReaderMessages) {
  auto message = [](const fs::path& p) {
    try {
      read_json_input(p, "--in");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(dir_ / "none.json").find("--in '"), std::string::npos);
  EXPECT_NE(message(dir_ / "none.json").find("no such file"), std::string::npos);
  EXPECT_NE(message(dir_).find("is a folder"), std::string::npos);
  write_file_atomically(dir_ / "bad.json", "{\"a\": [1, 2");
  EXPECT_NE(message(dir_ / "bad.json").find("not valid JSON"), std::string::npos);
  write_file_atomically(dir_ / "deep.json", std::string(100000, '[') + std::string(100000, ']'));
  EXPECT_NE(message(dir_ / "deep.json").find("nested more than"), std::string::npos) << message(dir_ / "deep.json");
  // Brackets inside strings do not count.
  write_file_atomically(dir_ / "ok.json", "{\"s\": \"" + std::string(1000, '[') + "\"}");
  EXPECT_EQ(message(dir_ / "ok.json"), "");
}

TEST(FiniteOutputs, JsonWithANanOrAnInfinityAnywhereIsRefused) {
  const nlohmann::json good = {{"a", {1.5, 2}}, {"b", {{"c", -0.25}}}};
  EXPECT_EQ(dump_finite(good, "--json", 2), good.dump(2));
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const nlohmann::json nested = {{"a", {1.5, 2}}, {"b", {{"c", {0.0, bad}}}}};
    try {
      (void)dump_finite(nested, "--json");
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--json: a value is not finite"), std::string::npos) << e.what();
    }
  }
}

TEST(ParallelFor, SameResultsForEveryThreadCountAndAllItemsOnce) {
  const std::size_t n = 1000;
  std::vector<std::uint64_t> reference(n);
  for (std::size_t i = 0; i < n; ++i) reference[i] = splitmix64(i);
  for (int threads : {1, 2, 3, 7, 16}) {
    std::vector<std::uint64_t> out(n, 0);
    std::vector<std::atomic<int>> hits(n);
    parallel_for(n, threads, [&](std::size_t i) {
      out[i] = splitmix64(i);
      ++hits[i];
    });
    EXPECT_EQ(out, reference) << threads << " threads";
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << i;
  }
}

TEST(ParallelFor, ExceptionsReachTheCaller) {
  for (int threads : {1, 4}) {
    EXPECT_THROW(parallel_for(100, threads,
                              [](std::size_t i) {
                                if (i == 77) throw InputError("item 77");
                              }),
                 InputError);
  }
  ThreadPool pool(3);
  EXPECT_THROW(pool.run(10, [](int worker, std::size_t, std::size_t) {
    if (worker == 2) throw std::runtime_error("worker 2");
  }),
               std::runtime_error);
  // The pool still works after an error.
  std::atomic<std::size_t> sum{0};
  pool.run(10, [&](int, std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) sum += i;
  });
  EXPECT_EQ(sum.load(), 45u);
}

TEST(ParallelFor, ThreadRequestsAreCapped) {
  EXPECT_GE(resolve_threads(0), 1);
  EXPECT_EQ(resolve_threads(2), 2);
  EXPECT_THROW(resolve_threads(max_threads() + 1), InputError);
  EXPECT_THROW(resolve_threads(100000), InputError);
}

// --threads 0 means the CPUs this process may use, not the machine's: bound to one CPU
// (taskset, a cpuset, mpirun --bind-to core) it is 1.
TEST(ParallelFor, EveryCoreMeansTheCoresThisProcessMayUse) {
  cpu_set_t old;
  ASSERT_EQ(::sched_getaffinity(0, sizeof old, &old), 0);
  int first = 0;
  while (!CPU_ISSET(first, &old)) ++first;
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(first, &one);
  ASSERT_EQ(::sched_setaffinity(0, sizeof one, &one), 0);
  const int bound = resolve_threads(0);
  ASSERT_EQ(::sched_setaffinity(0, sizeof old, &old), 0);
  EXPECT_EQ(bound, 1);
  EXPECT_EQ(resolve_threads(0), CPU_COUNT(&old));
}

// The draws reproduce libstdc++'s distributions on std::mt19937_64 bit for bit (the
// shipped lobe tables were made with those); this build is libstdc++, so they are the
// independent reference here.
TEST(Random, UniformDrawsMatchLibstdcxxDistributions) {
  for (std::uint64_t n : {1ull, 2ull, 3ull, 7ull, 10ull, 1000ull, (1ull << 32) + 3, ~0ull / 3}) {
    std::mt19937_64 a(42 + n), b(42 + n);
    std::uniform_int_distribution<std::uint64_t> d(0, n - 1);
    for (int k = 0; k < 2000; ++k) ASSERT_EQ(uniform_below(a, n), d(b)) << "n " << n << " draw " << k;
  }
  std::mt19937_64 a(7), b(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 20000; ++k) ASSERT_EQ(uniform_01(a), u(b)) << k;
  // int-typed distributions (as the lobe search once used) give the same values.
  std::mt19937_64 c(9), e(9);
  std::uniform_int_distribution<int> di(0, 40);
  for (int k = 0; k < 2000; ++k) ASSERT_EQ(static_cast<int>(uniform_below(c, 41)), di(e));
}

TEST(Random, UnitDoubleIsInRange) {
  EXPECT_EQ(unit_double(0), 0.0);
  EXPECT_LT(unit_double(~0ull), 1.0);
  SplitMixStream s{1};
  for (int k = 0; k < 1000; ++k) {
    const double u = s.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

}  // namespace
}  // namespace shtool

namespace {

// MappedInput gives the bytes read_input_file gives, for a mapped file and for an empty
// one (read instead), and refuses what read_input_file refuses, with its messages.
TEST(InputFile, MappedInputIsTheFilesBytes) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("shtool_mapped_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::string bytes(3 * 4096 + 17, '\0');
  std::mt19937 rng(3);
  for (char& c : bytes) c = static_cast<char>(rng());
  std::ofstream(dir / "some.bin", std::ios::binary) << bytes;
  std::ofstream(dir / "empty.bin", std::ios::binary).flush();
  {
    const shtool::MappedInput mapped(dir / "some.bin", "image");
    EXPECT_EQ(mapped.bytes(), bytes);
    EXPECT_EQ(mapped.bytes(), shtool::read_input_file(dir / "some.bin", "image"));
    EXPECT_EQ(shtool::MappedInput(dir / "empty.bin", "image").bytes(), "");
  }
  for (const std::filesystem::path& bad : {dir / "none.bin", dir}) {
    std::string mapped_error, read_error;
    try {
      shtool::MappedInput m(bad, "image");
    } catch (const shtool::InputError& e) {
      mapped_error = e.what();
    }
    try {
      shtool::read_input_file(bad, "image");
    } catch (const shtool::InputError& e) {
      read_error = e.what();
    }
    EXPECT_FALSE(mapped_error.empty()) << bad;
    EXPECT_EQ(mapped_error, read_error);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

// input_crc32 is zlib's fast CRC; the table format's byte-at-a-time table_crc32 is the
// reference it must equal (a table records its input's CRC, and tests recompute it so).
TEST(InputCrc32, EqualsTheTableFormatsReferenceCrc) {
  std::mt19937 rng(7);
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{64}, std::size_t{1000},
                        std::size_t{1} << 20}) {
    std::string bytes(n, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    EXPECT_EQ(shtool::input_crc32(bytes),
              shtool::table_crc32(std::as_bytes(std::span<const char>(bytes.data(), bytes.size()))))
        << n << " bytes";
  }
  EXPECT_EQ(shtool::input_crc32("123456789"), 0xCBF43926u);
}
