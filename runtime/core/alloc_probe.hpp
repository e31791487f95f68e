// Counts heap allocations made by the current thread while a scope is active: the proof that
// a real-time path allocates nothing. Link the pbppo_alloc_probe object library into the
// program: it replaces malloc and its relatives (operator new goes through them), or, in
// sanitizer builds, installs the sanitizer's allocation hooks. Not part of pbppo::runtime.
#pragma once

#include <cstdint>

namespace pbppo {

class AllocationScope {
 public:
  AllocationScope() noexcept;
  ~AllocationScope();
  AllocationScope(const AllocationScope&) = delete;
  AllocationScope& operator=(const AllocationScope&) = delete;
  // Allocations (malloc, calloc, realloc, aligned_alloc, posix_memalign, operator new) so far.
  std::uint64_t count() const noexcept;

 private:
  std::uint64_t start_;
};

// Whether this build can see every allocation (true in all supported configurations).
bool AllocationCountingActive() noexcept;

}  // namespace pbppo
