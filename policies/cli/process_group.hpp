// The processes a `pbppo sweep` runs in: this process alone, or the ranks of an mpirun (Open MPI,
// initialised only when mpirun started the process). The only code of the project that knows MPI.
#pragma once

#include <string>
#include <vector>

namespace pbppo::cli {

class ProcessGroup {
 public:
  // mpirun (Open MPI) sets its variables in every process it starts; plain `pbppo` never
  // initialises MPI.
  static bool UnderMpirun();

  ProcessGroup();
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool mpi() const { return mpi_; }

  // Rank 0's `v`, on every rank.
  void Broadcast(std::vector<long>& v) const;
  // On rank 0: every rank's `mine`, by rank; elsewhere: nothing.
  std::vector<std::string> Gather(const std::string& mine) const;

 private:
  bool mpi_ = false;
  int rank_ = 0, size_ = 1;
};

}  // namespace pbppo::cli
