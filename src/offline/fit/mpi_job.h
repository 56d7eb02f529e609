// fit-zh --mpi: the ranks of an MPI job split the vertices like shards (rank R of S fits
// shard R/S), rank 0 gathers their partial tables and merges them into the table a
// one-process run writes.
// MPI is optional at build time; without it constructing an MpiJob is refused.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace shtool::fit {

// Whether this build has MPI.
bool mpi_built();

// This process's part of the job: MPI_Init on construction (or joins an MPI already
// initialised), MPI_Finalize on destruction. One per process.
class MpiJob {
 public:
  // Throws InputError when shtool was built without MPI or MPI cannot start.
  MpiJob();
  ~MpiJob();
  MpiJob(const MpiJob&) = delete;
  MpiJob& operator=(const MpiJob&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  // Collective: whether every rank passes true. A rank that failed passes false, so that
  // the others stop here instead of waiting for it in a later collective.
  bool all_ok(bool ok);
  bool synchronised() const { return synchronised_; }

  // Collective: every rank's bytes, in rank order, on rank 0 (empty on the others).
  // Throws InputError on every rank when the total passes 2^31 - 1 bytes (MPI's int
  // counts and displacements).
  std::vector<std::string> gather(std::string_view mine);

 private:
  int rank_ = 0, size_ = 1;
  bool finalize_ = false;
  bool synchronised_ = false;
};

}  // namespace shtool::fit
