// A fixed-size latency histogram for real-time threads: log-linear buckets (exact below 64 ns,
// then 64 buckets per power of two, at most 1/64 = 1.6 % wide relative to their lower edge) from
// 1 ns to 2^31 ns (2.1 s; longer values go to the last bucket and still count in the exact max).
// Allocated once at construction; Record() is noexcept, allocation- and lock-free. One writer
// (the real-time thread); any other thread may take a Snapshot() at any time: every counter is a
// relaxed atomic, so a snapshot may see a record partly applied (a bucket counted but not the
// sum, or the other way round) but never a torn value.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace pbppo::rt {

struct LatencyStats {
  std::uint64_t count = 0;
  std::int64_t min_ns = 0, max_ns = 0;  // exact
  double mean_ns = 0;
  // From the buckets: the midpoint of the bucket holding the rank, clamped to [min, max].
  std::int64_t p50_ns = 0, p99_ns = 0, p999_ns = 0, p9999_ns = 0;
};

class LatencySnapshot {
 public:
  std::uint64_t count() const noexcept { return count_; }
  // The value at quantile q in [0, 1] (rank ceil(q * count)); 0 when empty.
  std::int64_t Quantile(double q) const noexcept;
  LatencyStats Stats() const noexcept;
  // Non-empty buckets as (lower edge ns, width ns, count), for plots.
  struct Bucket {
    std::int64_t lower_ns, width_ns;
    std::uint64_t count;
  };
  std::vector<Bucket> NonEmptyBuckets() const;

 private:
  friend class LatencyHistogram;
  std::vector<std::uint64_t> buckets_;
  std::uint64_t count_ = 0;
  std::int64_t min_ns_ = 0, max_ns_ = 0;
  double sum_ns_ = 0;
};

class LatencyHistogram {
 public:
  static constexpr std::uint32_t kSubBits = 6;  // 64 sub-buckets per power of two
  static constexpr std::uint32_t kSub = 1u << kSubBits;
  static constexpr std::uint32_t kMaxExponent = 30;  // last octave [2^30, 2^31)
  static constexpr std::uint32_t kBuckets = kSub + (kMaxExponent - kSubBits + 1) * kSub;

  LatencyHistogram();
  LatencyHistogram(const LatencyHistogram&) = delete;
  LatencyHistogram& operator=(const LatencyHistogram&) = delete;

  // Negative values count as 0.
  void Record(std::int64_t ns) noexcept;
  void Reset() noexcept;  // writer thread only
  LatencySnapshot Snapshot() const;

  static std::uint32_t BucketOf(std::int64_t ns) noexcept;
  static std::int64_t BucketLower(std::uint32_t bucket) noexcept;
  static std::int64_t BucketWidth(std::uint32_t bucket) noexcept;

 private:
  std::unique_ptr<std::atomic<std::uint64_t>[]> buckets_;
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> min_ns_{0}, max_ns_{0};
  std::atomic<std::int64_t> sum_ns_{0};
};

}  // namespace pbppo::rt
