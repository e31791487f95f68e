// The processes a `pbppo sweep` or one data-parallel `pbppo train` runs in: this process alone, or
// the ranks of an mpirun (Open MPI, initialised only when mpirun started the process). The only
// code of the project that knows MPI; the trainer sees it as a trainer::Collective.
#pragma once

#include <string>
#include <vector>

#include "policies/trainer/collective.hpp"

namespace pbppo::cli {

class ProcessGroup final : public trainer::Collective {
 public:
  // mpirun (Open MPI) sets its variables in every process it starts; plain `pbppo` never
  // initialises MPI.
  static bool UnderMpirun();

  ProcessGroup();
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  int rank() const noexcept override { return rank_; }
  int size() const noexcept override { return size_; }
  bool mpi() const { return mpi_; }

  void Broadcast(void* data, std::size_t bytes, int root) const override;
  std::vector<std::vector<char>> AllGather(std::span<const char> mine) const override;
  // Ends every rank of the job with exit status `rc` (a rank that fails alone would leave the
  // others waiting in a collective call); outside mpirun, only this process.
  [[noreturn]] void Abort(int rc) const;

  // Rank 0's `v`, on every rank.
  void Broadcast(std::vector<long>& v) const;
  // On rank 0: every rank's `mine`, by rank; elsewhere: nothing.
  std::vector<std::string> Gather(const std::string& mine) const;

 private:
  bool mpi_ = false;
  int rank_ = 0, size_ = 1;
};

}  // namespace pbppo::cli
