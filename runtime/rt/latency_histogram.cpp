#include "runtime/rt/latency_histogram.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>

namespace pbppo::rt {
namespace {
constexpr auto kRelaxed = std::memory_order_relaxed;

// Single writer: load + store instead of a locked read-modify-write.
template <typename T>
void Bump(std::atomic<T>& a, T by) noexcept {
  a.store(a.load(kRelaxed) + by, kRelaxed);
}
}  // namespace

LatencyHistogram::LatencyHistogram() : buckets_(new std::atomic<std::uint64_t>[kBuckets]) {
  Reset();
}

std::uint32_t LatencyHistogram::BucketOf(std::int64_t ns) noexcept {
  if (ns < static_cast<std::int64_t>(kSub)) return ns < 0 ? 0u : static_cast<std::uint32_t>(ns);
  const auto v = static_cast<std::uint64_t>(ns);
  const auto e = static_cast<std::uint32_t>(63 - std::countl_zero(v));  // >= kSubBits
  if (e > kMaxExponent) return kBuckets - 1;
  const auto sub = static_cast<std::uint32_t>((v >> (e - kSubBits)) & (kSub - 1));
  return kSub + (e - kSubBits) * kSub + sub;
}

std::int64_t LatencyHistogram::BucketLower(std::uint32_t b) noexcept {
  if (b < kSub) return b;
  const std::uint32_t octave = (b - kSub) / kSub, sub = (b - kSub) % kSub;
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(kSub + sub) << octave);
}

std::int64_t LatencyHistogram::BucketWidth(std::uint32_t b) noexcept {
  if (b < kSub) return 1;
  return static_cast<std::int64_t>(std::uint64_t{1} << ((b - kSub) / kSub));
}

void LatencyHistogram::Record(std::int64_t ns) noexcept {
  if (ns < 0) ns = 0;
  Bump(buckets_[BucketOf(ns)], std::uint64_t{1});
  const std::uint64_t n = count_.load(kRelaxed);
  if (n == 0 || ns < min_ns_.load(kRelaxed)) min_ns_.store(ns, kRelaxed);
  if (n == 0 || ns > max_ns_.load(kRelaxed)) max_ns_.store(ns, kRelaxed);
  Bump(sum_ns_, ns);
  count_.store(n + 1, std::memory_order_release);
}

void LatencyHistogram::Reset() noexcept {
  for (std::uint32_t i = 0; i < kBuckets; ++i) buckets_[i].store(0, kRelaxed);
  count_.store(0, kRelaxed);
  min_ns_.store(0, kRelaxed);
  max_ns_.store(0, kRelaxed);
  sum_ns_.store(0, kRelaxed);
}

LatencySnapshot LatencyHistogram::Snapshot() const {
  LatencySnapshot s;
  const std::uint64_t n = count_.load(std::memory_order_acquire);
  s.min_ns_ = min_ns_.load(kRelaxed);
  s.max_ns_ = max_ns_.load(kRelaxed);
  s.sum_ns_ = static_cast<double>(sum_ns_.load(kRelaxed));
  s.buckets_.resize(kBuckets);
  std::uint64_t total = 0;
  for (std::uint32_t i = 0; i < kBuckets; ++i) total += s.buckets_[i] = buckets_[i].load(kRelaxed);
  // The buckets are the population the quantiles walk; records that landed after `n` was read
  // are included (the writer never stops).
  s.count_ = total;
  if (n == 0) s.min_ns_ = s.max_ns_ = 0;
  return s;
}

std::int64_t LatencySnapshot::Quantile(double q) const noexcept {
  if (count_ == 0) return 0;
  q = std::clamp(std::isnan(q) ? 0.0 : q, 0.0, 1.0);
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_))));
  // Exact extremes where min and max lie in the first and last non-empty buckets (a snapshot
  // taken while recording may see a bucket before the min or max of the same record).
  std::uint32_t first = 0, last = 0;
  for (std::uint32_t b = 0; b < buckets_.size(); ++b) {
    if (buckets_[b] == 0) continue;
    if (buckets_[first] == 0) first = b;
    last = b;
  }
  const auto bounds = [](std::uint32_t b) {
    return std::pair{LatencyHistogram::BucketLower(b),
                     LatencyHistogram::BucketLower(b) + LatencyHistogram::BucketWidth(b) - 1};
  };
  const std::int64_t lo = LatencyHistogram::BucketOf(min_ns_) == first ? min_ns_ : bounds(first).first;
  const std::int64_t hi = LatencyHistogram::BucketOf(max_ns_) == last ? max_ns_ : bounds(last).second;
  std::uint64_t seen = 0;
  for (std::uint32_t b = 0; b < buckets_.size(); ++b) {
    seen += buckets_[b];
    if (seen >= rank) {
      const std::int64_t mid = LatencyHistogram::BucketLower(b) + LatencyHistogram::BucketWidth(b) / 2;
      return std::clamp(mid, lo, std::max(lo, hi));
    }
  }
  return hi;
}

LatencyStats LatencySnapshot::Stats() const noexcept {
  LatencyStats s;
  s.count = count_;
  s.min_ns = min_ns_;
  s.max_ns = max_ns_;
  s.mean_ns = count_ > 0 ? sum_ns_ / static_cast<double>(count_) : 0.0;
  s.p50_ns = Quantile(0.5);
  s.p99_ns = Quantile(0.99);
  s.p999_ns = Quantile(0.999);
  s.p9999_ns = Quantile(0.9999);
  return s;
}

std::vector<LatencySnapshot::Bucket> LatencySnapshot::NonEmptyBuckets() const {
  std::vector<Bucket> out;
  for (std::uint32_t b = 0; b < buckets_.size(); ++b) {
    if (buckets_[b] != 0)
      out.push_back({LatencyHistogram::BucketLower(b), LatencyHistogram::BucketWidth(b), buckets_[b]});
  }
  return out;
}

}  // namespace pbppo::rt
