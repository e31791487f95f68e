// LatestMailbox (triple buffer) and SpscQueue, and their run-time sized forms (ByteMailbox,
// ByteQueue): single-thread semantics, and two threads hammering them: a reader never sees a value
// mixed from two writes, versions only grow, the queue delivers every pushed item in order or
// counts it as dropped.
#include <doctest/doctest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/latest_mailbox.hpp"
#include "runtime/core/spsc_queue.hpp"

using namespace pbppo;

namespace {

// Every word carries the same number: a torn read shows two different ones.
struct Wide {
  std::array<std::uint64_t, 24> words{};
  void Fill(std::uint64_t v) { words.fill(v); }
  bool Consistent() const {
    for (auto w : words)
      if (w != words[0]) return false;
    return true;
  }
};

}  // namespace

TEST_CASE("mailbox: empty until written, then the newest value with its version") {
  LatestMailbox<int> box;
  int out = -1;
  CHECK(box.Read(&out) == 0);
  CHECK(out == -1);
  CHECK(box.version() == 0);
  CHECK(box.Write(10) == 1);
  CHECK(box.Write(11) == 2);
  CHECK(box.Write(12) == 3);
  CHECK(box.version() == 3);
  CHECK(box.Read(&out) == 3);
  CHECK(out == 12);
  // Reading again without a write gives the same value and version.
  out = -1;
  CHECK(box.Read(&out) == 3);
  CHECK(out == 12);
  CHECK(box.Write(13) == 4);
  CHECK(box.Read(&out) == 4);
  CHECK(out == 13);
}

TEST_CASE("mailbox: Read and Write do not allocate") {
  LatestMailbox<Wide> box;
  Wide w, r;
  std::uint64_t wrong = 0, allocations = 0;
  {
    AllocationScope scope;
    for (std::uint64_t i = 1; i <= 1000; ++i) {
      w.Fill(i);
      box.Write(w);
      if (box.Read(&r) != i || r.words[0] != i) ++wrong;
    }
    allocations = scope.count();
  }
  CHECK(wrong == 0);
  CHECK(allocations == 0);
}

TEST_CASE("mailbox: two threads, never a torn read, versions never go back") {
  LatestMailbox<Wide> box;
  constexpr std::uint64_t kWrites = 300'000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    Wide w;
    for (std::uint64_t i = 1; i <= kWrites; ++i) {
      w.Fill(i);
      box.Write(w);
    }
    done.store(true);
  });
  std::uint64_t last = 0, reads = 0, torn = 0, backwards = 0, mismatched = 0;
  Wide r;
  auto read = [&] {
    const std::uint64_t v = box.Read(&r);
    if (v == 0) return;
    ++reads;
    if (!r.Consistent()) ++torn;
    if (v < last) ++backwards;
    if (r.words[0] != v) ++mismatched;  // the value is the one written with that version
    last = v;
  };
  while (!done.load()) read();
  read();  // after the last write: the newest value
  writer.join();
  CHECK(torn == 0);
  CHECK(backwards == 0);
  CHECK(mismatched == 0);
  CHECK(last == kWrites);
  CHECK(reads > 0);
}

TEST_CASE("spsc queue: drops and counts when full, keeps order") {
  CHECK(SpscQueue<int>(5).capacity() == 8);  // a power of two, at least what was asked
  SpscQueue<int> q(4);
  REQUIRE(q.capacity() == 4);
  for (int i = 0; i < 4; ++i) CHECK(q.TryPush(i));
  CHECK_FALSE(q.TryPush(99));
  CHECK_FALSE(q.TryPush(100));
  CHECK(q.dropped() == 2);
  int v = -1;
  for (int i = 0; i < 4; ++i) {
    REQUIRE(q.TryPop(&v));
    CHECK(v == i);
  }
  CHECK_FALSE(q.TryPop(&v));
  CHECK(q.TryPush(5));
  REQUIRE(q.TryPop(&v));
  CHECK(v == 5);
}

TEST_CASE("spsc queue: two threads, every item in order or counted as dropped") {
  SpscQueue<std::uint64_t> q(64);
  constexpr std::uint64_t kItems = 200'000;
  std::atomic<bool> done{false};
  std::uint64_t pushed = 0;
  std::thread producer([&] {
    for (std::uint64_t i = 1; i <= kItems; ++i)
      if (q.TryPush(i)) ++pushed;
    done.store(true);
  });
  std::uint64_t popped = 0, last = 0, out_of_order = 0, v = 0;
  for (;;) {
    if (q.TryPop(&v)) {
      ++popped;
      if (v <= last) ++out_of_order;
      last = v;
    } else if (done.load()) {
      if (!q.TryPop(&v)) break;
      ++popped;
      if (v <= last) ++out_of_order;
      last = v;
    }
  }
  producer.join();
  CHECK(out_of_order == 0);
  CHECK(popped == pushed);
  CHECK(pushed + q.dropped() == kItems);
}

TEST_CASE("byte records: a mailbox and a queue of records sized at run time, with their stamps") {
  // 301 bytes (an odd size, as a message's CDR sample may be): the records never overlap.
  constexpr std::size_t kBytes = 301;
  ByteMailbox box(kBytes);
  CHECK(box.record_size() == kBytes);
  std::array<std::byte, kBytes> in{}, out{};
  std::int64_t stamp = -1;
  CHECK(box.Read(out.data(), &stamp) == 0);
  CHECK(stamp == -1);
  std::uint64_t wrong = 0, allocations = 0;
  {
    AllocationScope scope;
    for (std::uint64_t i = 1; i <= 1000; ++i) {
      in.fill(static_cast<std::byte>(i & 0xff));
      CHECK(box.Write(in.data(), static_cast<std::int64_t>(i) * 7) == i);
      if (box.Read(out.data(), &stamp) != i || out != in || stamp != static_cast<std::int64_t>(i) * 7) ++wrong;
    }
    allocations = scope.count();
  }
  CHECK(wrong == 0);
  CHECK(allocations == 0);

  ByteQueue q(kBytes, 3);
  CHECK(q.capacity() == 4);
  for (std::uint64_t i = 1; i <= 6; ++i) {
    in.fill(static_cast<std::byte>(i));
    CHECK(q.TryPush(in.data(), static_cast<std::int64_t>(i)) == (i <= 4));
  }
  CHECK(q.dropped() == 2);
  for (std::uint64_t i = 1; i <= 4; ++i) {
    REQUIRE(q.TryPop(out.data(), &stamp));
    CHECK(out[0] == static_cast<std::byte>(i));
    CHECK(out[kBytes - 1] == static_cast<std::byte>(i));
    CHECK(stamp == static_cast<std::int64_t>(i));
  }
  CHECK_FALSE(q.TryPop(out.data(), &stamp));
}
