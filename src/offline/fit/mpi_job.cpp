#include "fit/mpi_job.h"

#include <climits>
#include <string>

#include "common/input_error.h"

#ifdef SHTOOL_HAVE_MPI
#include <mpi.h>
#endif

namespace shtool::fit {

#ifdef SHTOOL_HAVE_MPI

bool mpi_built() { return true; }

MpiJob::MpiJob() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) {
    if (MPI_Init(nullptr, nullptr) != MPI_SUCCESS) throw InputError("--mpi: MPI_Init failed");
    finalize_ = true;
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiJob::~MpiJob() {
  if (finalize_) MPI_Finalize();
}

bool MpiJob::all_ok(bool ok) {
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  synchronised_ = true;
  return all == 1;
}

std::vector<double> MpiJob::gather(std::span<const double> mine) {
  // Every rank learns whether any part is too large before the gather, so none waits.
  const bool fits_int = mine.size() <= static_cast<std::size_t>(INT_MAX);
  int all_fit = 0, mine_fit = fits_int ? 1 : 0;
  MPI_Allreduce(&mine_fit, &all_fit, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (!all_fit) throw InputError("--mpi: a rank's rows exceed 2^31 - 1 values; run with more ranks");
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(rank_ == 0 ? size_ : 0), offsets;
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<double> all;
  if (rank_ == 0) {
    offsets.resize(size_);
    long long total = 0;
    for (int r = 0; r < size_; ++r) {
      offsets[r] = static_cast<int>(total);
      total += counts[r];
    }
    // MPI_Gatherv's displacements are ints too.
    if (total > INT_MAX) throw InputError("--mpi: the gathered rows exceed 2^31 - 1 values");
    all.resize(static_cast<std::size_t>(total));
  }
  MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0,
              MPI_COMM_WORLD);
  return all;
}

std::vector<std::uint32_t> MpiJob::gather(std::uint32_t mine) {
  std::vector<std::uint32_t> all(rank_ == 0 ? size_ : 0);
  MPI_Gather(&mine, 1, MPI_UINT32_T, all.data(), 1, MPI_UINT32_T, 0, MPI_COMM_WORLD);
  return all;
}

#else

bool mpi_built() { return false; }

MpiJob::MpiJob() {
  throw InputError("--mpi: this shtool was built without MPI (install an MPI library, e.g. Debian's "
                   "libopenmpi-dev, and configure again)");
}

MpiJob::~MpiJob() = default;

// A one-rank job: what the MPI calls compute when MPI_COMM_WORLD has one process.
bool MpiJob::all_ok(bool ok) {
  synchronised_ = true;
  return ok;
}

std::vector<double> MpiJob::gather(std::span<const double> mine) { return {mine.begin(), mine.end()}; }

std::vector<std::uint32_t> MpiJob::gather(std::uint32_t mine) { return {mine}; }

#endif

}  // namespace shtool::fit
