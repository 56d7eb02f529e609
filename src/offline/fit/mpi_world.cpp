#include "fit/mpi_world.h"

#include <climits>
#include <cstdlib>
#include <string>
#include <vector>

#include "common/input_error.h"

#ifdef SHTOOL_HAVE_MPI
#include <mpi.h>
#endif

namespace shtool::fit {

#ifdef SHTOOL_HAVE_MPI

bool mpi_built() { return true; }

namespace {

// At process exit, after main has printed this rank's error if it has one: when a rank
// exits with an error mpirun stops the others, so every rank first waits here until all
// have reached the end (and printed theirs), then finalizes.
void finish_mpi() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (finalized) return;
  MPI_Barrier(MPI_COMM_WORLD);
  MPI_Finalize();
}

}  // namespace

MpiJob::MpiJob() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) {
    if (MPI_Init(nullptr, nullptr) != MPI_SUCCESS) throw InputError("--mpi: MPI_Init failed");
    std::atexit(finish_mpi);
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

bool MpiJob::agree(bool ok) {
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}

bool MpiJob::all_ok(bool ok) {
  const bool all = agree(ok);
  synchronised_ = true;
  return all;
}

std::vector<double> MpiJob::allgather(std::vector<double> mine) {
  // The same collective as a failed rank's all_ok(false): it meets this one.
  if (!agree(true)) {
    synchronised_ = true;
    throw InputError("rank " + std::to_string(rank_) + ": stopped, another rank failed");
  }
  const long long count = static_cast<long long>(mine.size());
  long long total = 0;
  MPI_Allreduce(&count, &total, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  if (total > INT_MAX)
    throw InputError("--mpi: one bounce of the transfer vectors is " + std::to_string(total) +
                     " values, more than MPI's int counts (2^31 - 1) can gather; run this interreflected bake in "
                     "one process");
  const int mine_count = static_cast<int>(count);
  std::vector<int> counts(size_), offsets(size_);
  MPI_Allgather(&mine_count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (int r = 1; r < size_; ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
  std::vector<double> all(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), mine_count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE,
                 MPI_COMM_WORLD);
  return all;
}

void MpiJob::check_same_job(const std::string& mine, std::string_view what) {
  if (!agree(true)) {
    synchronised_ = true;
    throw InputError("rank " + std::to_string(rank_) + ": stopped, another rank failed");
  }
  long long length = static_cast<long long>(mine.size());
  MPI_Bcast(&length, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  std::string root = rank_ == 0 ? mine : std::string(static_cast<std::size_t>(length), '\0');
  MPI_Bcast(root.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD);
  const bool same = root == mine;
  if (agree(same)) return;
  synchronised_ = true;
  if (!same)
    throw InputError("--mpi: rank " + std::to_string(rank_) + "'s " + std::string(what) + " differ from rank 0's: " +
                     mine + " against " + root + " (every rank must run the same command on the same files)");
  throw InputError("rank " + std::to_string(rank_) + ": stopped, another rank's " + std::string(what) +
                   " differ from this one's");
}

std::vector<std::string> MpiJob::gather(std::string_view mine) {
  const long long count = static_cast<long long>(mine.size());
  long long total = 0;
  MPI_Allreduce(&count, &total, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  // Decided from the sum every rank has, so that all of them stop, none waits.
  if (total > INT_MAX)
    throw InputError("--mpi: the partial tables exceed 2^31 - 1 bytes in all (MPI's int counts); use --shard "
                     "and merge for a bake this large");
  const int mine_count = static_cast<int>(count);
  std::vector<int> counts(rank_ == 0 ? size_ : 0), offsets(counts.size());
  MPI_Gather(&mine_count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    offsets[r] = static_cast<int>(all.size());
    all.resize(all.size() + counts[r]);
  }
  MPI_Gatherv(mine.data(), mine_count, MPI_BYTE, all.data(), counts.data(), offsets.data(), MPI_BYTE, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> parts;
  for (std::size_t r = 0; r < counts.size(); ++r) parts.push_back(all.substr(offsets[r], counts[r]));
  return parts;
}

#else

bool mpi_built() { return false; }

MpiJob::MpiJob() {
  throw InputError("--mpi: this shtool was built without MPI (install an MPI library, e.g. Debian's "
                   "libopenmpi-dev, and configure again)");
}

// A one-rank job: what the MPI calls compute when MPI_COMM_WORLD has one process.
bool MpiJob::all_ok(bool ok) {
  synchronised_ = true;
  return ok;
}

std::vector<std::string> MpiJob::gather(std::string_view mine) { return {std::string(mine)}; }

void MpiJob::check_same_job(const std::string&, std::string_view) {}

std::vector<double> MpiJob::allgather(std::vector<double> mine) { return mine; }

#endif

}  // namespace shtool::fit
