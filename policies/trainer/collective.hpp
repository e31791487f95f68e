// The processes one training run spans: this process alone, or the ranks of an mpirun. The trainer
// exchanges what its ranks share (the rollout's samples, evaluation returns, the update's chunk
// gradients, the decision to stop) through this interface and never names MPI; the command line's
// ProcessGroup implements it over Open MPI. Every call is collective: every rank makes it, in the
// same order, with the same sizes where a size is given.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace pbppo::trainer {

class Collective {
 public:
  virtual ~Collective() = default;
  virtual int rank() const noexcept = 0;
  virtual int size() const noexcept = 0;
  // `bytes` bytes at `data`, rank `root`'s, onto every rank (any size: no count limit).
  virtual void Broadcast(void* data, std::size_t bytes, int root) const = 0;
  // Every rank's `mine` (its own length), by rank, on every rank.
  virtual std::vector<std::vector<char>> AllGather(std::span<const char> mine) const = 0;
};

}  // namespace pbppo::trainer
