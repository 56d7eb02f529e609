// fit-zh --mpi: the ranks of an MPI job split the vertices like shards (rank R of S fits
// shard R/S), rank 0 gathers their partial tables and merges them into the table a
// one-process run writes. Interreflected bakes also share every bounce among the ranks.
// MPI is optional at build time; without it constructing an MpiJob is refused.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace shtool::fit {

// Whether this build has MPI.
bool mpi_built();

// This process's part of the job: MPI_Init on construction (or joins an MPI already
// initialised); MPI_Finalize at process exit, after a barrier (see mpi_world.cpp). One per
// process.
class MpiJob {
 public:
  // Throws InputError when shtool was built without MPI or MPI cannot start.
  MpiJob();
  ~MpiJob() = default;
  MpiJob(const MpiJob&) = delete;
  MpiJob& operator=(const MpiJob&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  // Collective: whether every rank passes true. A rank that failed passes false, so that
  // the others stop here (or at the next allgather) instead of waiting for it in a later
  // collective. After it no rank checks in again: a rank that fails later needs not call
  // it (synchronised()).
  bool all_ok(bool ok);
  bool synchronised() const { return synchronised_; }

  // Collective: every rank's doubles, in rank order, on every rank. First the ranks check
  // in as all_ok does, so a rank that failed since the last collective stops the others
  // here with InputError. Throws InputError on every rank when the total passes 2^31 - 1
  // values (MPI's int counts and displacements).
  std::vector<double> allgather(std::vector<double> mine);

  // Collective: checks that every rank describes its part of the job as rank 0 does
  // (`mine`: the settings and input checksums the ranks must share, as text). Checks in
  // first as allgather does. Throws InputError on every rank when one differs: that rank
  // names `what` and both descriptions, the others that another rank differs. Ranks that
  // disagree would otherwise exchange bounces of different sizes, or wait for one another
  // for ever.
  void check_same_job(const std::string& mine, std::string_view what);

  // Collective: every rank's bytes, in rank order, on rank 0 (empty on the others).
  // Throws InputError on every rank when the total passes 2^31 - 1 bytes (MPI's int
  // counts and displacements).
  std::vector<std::string> gather(std::string_view mine);

 private:
  bool agree(bool ok);

  int rank_ = 0, size_ = 1;
  bool synchronised_ = false;
};

}  // namespace shtool::fit
