// A fixed set of worker threads that run one function on every worker index and wait for all:
// index 0 runs on the calling thread. Work is assigned by index, never by timing, so results
// do not depend on scheduling.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace pbppo::trainer {

// A two-or-more-party barrier for short phases: spins briefly, then yields the CPU. Cheaper than
// a futex round trip when the parties arrive within microseconds of each other.
class SpinBarrier {
 public:
  explicit SpinBarrier(int parties) : parties_(parties) {}
  void ArriveAndWait() {
    const unsigned gen = generation_.load(std::memory_order_acquire);
    if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == parties_) {
      arrived_.store(0, std::memory_order_relaxed);
      generation_.fetch_add(1, std::memory_order_acq_rel);
      return;
    }
    for (int spin = 0; generation_.load(std::memory_order_acquire) == gen; ++spin) {
      if (spin > 2000) std::this_thread::yield();
    }
  }

 private:
  const int parties_;
  std::atomic<int> arrived_{0};
  std::atomic<unsigned> generation_{0};
};

class WorkerPool {
 public:
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const noexcept { return size_; }
  // Runs fn(0) ... fn(size() - 1) concurrently and returns when all have finished.
  void Run(const std::function<void(int)>& fn);

 private:
  void Loop(int index);
  int size_;
  std::vector<std::thread> threads_;
  std::mutex mu_;
  std::condition_variable start_cv_, done_cv_;
  const std::function<void(int)>* job_ = nullptr;
  unsigned long generation_ = 0;
  int remaining_ = 0;
  bool quit_ = false;
};

}  // namespace pbppo::trainer
