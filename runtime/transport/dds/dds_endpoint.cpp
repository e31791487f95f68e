#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <semaphore>
#include <thread>
#include <vector>

#include "runtime/core/byte_records.hpp"
#include "runtime/core/clock.hpp"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/cdr_type.hpp"
#include "runtime/transport/dds/dds_internal.hpp"

namespace pbppo::dds {

// ---- DdsReader ---------------------------------------------------------------------------------

struct DdsReader::Impl final : public fdds::DataReaderListener {
  DdsParticipant::Impl* owner = nullptr;
  fdds::DataReader* reader = nullptr;
  DdsReaderOptions options;
  std::size_t bytes = 0;
  // Listener callbacks are serialised by take_mu (one producer for the mailbox or the queue).
  std::mutex take_mu;
  std::vector<std::byte> rx_bytes;
  CdrSample rx;
  std::unique_ptr<ByteMailbox> latest;
  std::unique_ptr<ByteQueue> queue;
  std::atomic<std::uint64_t> received{0}, malformed{0};
  std::atomic<std::int32_t> matched{0};
  std::atomic<std::int64_t> last_ns{-1};
  // Wakes WaitNewer / WaitPop.
  std::mutex wait_mu;
  std::condition_variable wait_cv;
  std::uint64_t arrivals = 0;  // guarded by wait_mu

  void on_data_available(fdds::DataReader* r) override {
    std::lock_guard<std::mutex> lk(take_mu);
    fdds::SampleInfo info;
    bool any = false;
    while (r->take_next_sample(&rx, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;  // dispose / unregister notifications
      const std::int64_t now = MonotonicNs();
      received.fetch_add(1, std::memory_order_relaxed);
      last_ns.store(now, std::memory_order_relaxed);
      if (!rx.ok) {
        malformed.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      if (queue) {
        queue->TryPush(rx.bytes, now);  // counts the drop when full
      } else {
        latest->Write(rx.bytes, now);
      }
      any = true;
    }
    if (!any) return;
    {
      std::lock_guard<std::mutex> wait_lk(wait_mu);
      ++arrivals;
    }
    wait_cv.notify_all();
  }
  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& s) override {
    matched.store(s.current_count, std::memory_order_relaxed);
  }
  ~Impl() override {
    if (reader != nullptr) {
      reader->set_listener(nullptr);
      owner->subscriber->delete_datareader(reader);
    }
  }
};

DdsReader::DdsReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsReader::~DdsReader() = default;

Result<std::unique_ptr<DdsReader>> DdsReader::Create(DdsParticipant& participant, const std::string& topic,
                                                     const robot::IdlMessage& type, const DdsReaderOptions& o) {
  if (o.history_depth < 1 || o.history_depth > 4096)
    return DdsError("history_depth " + std::to_string(o.history_depth) + " is outside 1..4096");
  if (o.mode == DdsReaderMode::kQueue && (o.queue_capacity < 1 || o.queue_capacity > 65536))
    return DdsError("queue_capacity " + std::to_string(o.queue_capacity) + " is outside 1..65536");
  auto impl = std::make_unique<Impl>();
  impl->owner = &participant.impl();
  impl->options = o;
  impl->bytes = CdrSampleBytes(type);
  impl->rx_bytes.assign(impl->bytes, std::byte{0});
  impl->rx.bytes = impl->rx_bytes.data();
  if (o.mode == DdsReaderMode::kQueue) {
    impl->queue = std::make_unique<ByteQueue>(impl->bytes, o.queue_capacity);
  } else {
    impl->latest = std::make_unique<ByteMailbox>(impl->bytes);
  }
  fdds::Topic* t = impl->owner->TopicFor(topic, type, o.type_name);
  if (t == nullptr) return DdsError("cannot create topic '" + topic + "' (type '" + o.type_name + "')");
  const fdds::StatusMask mask = fdds::StatusMask::data_available() << fdds::StatusMask::subscription_matched();
  impl->reader =
      impl->owner->subscriber->create_datareader(t, ReaderQos(o.history_depth, o.transient_local), impl.get(), mask);
  if (impl->reader == nullptr) return DdsError("cannot create a reader of topic '" + topic + "'");
  return std::unique_ptr<DdsReader>(new DdsReader(std::move(impl)));
}

std::size_t DdsReader::sample_bytes() const noexcept {
  return impl_->bytes;
}

std::uint64_t DdsReader::Read(std::byte* out, std::int64_t* received_ns) noexcept {
  return impl_->latest ? impl_->latest->Read(out, received_ns) : 0;
}

std::uint64_t DdsReader::version() const noexcept {
  return impl_->latest ? impl_->latest->version() : 0;
}

bool DdsReader::WaitNewer(std::uint64_t after_version, std::int64_t timeout_ns) {
  Impl& m = *impl_;
  if (!m.latest) return false;
  std::unique_lock<std::mutex> lk(m.wait_mu);
  return m.wait_cv.wait_for(lk, std::chrono::nanoseconds(timeout_ns),
                            [&] { return m.latest->version() > after_version; });
}

bool DdsReader::Pop(std::byte* out, std::int64_t* received_ns) noexcept {
  return impl_->queue && impl_->queue->TryPop(out, received_ns);
}

bool DdsReader::WaitPop(std::byte* out, std::int64_t* received_ns, std::int64_t timeout_ns) {
  Impl& m = *impl_;
  if (!m.queue) return false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(timeout_ns);
  for (;;) {
    std::uint64_t seen = 0;
    {
      std::lock_guard<std::mutex> lk(m.wait_mu);
      seen = m.arrivals;
    }
    if (m.queue->TryPop(out, received_ns)) return true;
    std::unique_lock<std::mutex> lk(m.wait_mu);
    if (!m.wait_cv.wait_until(lk, deadline, [&] { return m.arrivals != seen; }))
      return m.queue->TryPop(out, received_ns);
  }
}

std::int32_t DdsReader::matched_writers() const noexcept {
  return impl_->matched.load(std::memory_order_relaxed);
}

std::int64_t DdsReader::last_receive_ns() const noexcept {
  return impl_->last_ns.load(std::memory_order_relaxed);
}

DdsReaderCounters DdsReader::counters() const noexcept {
  const Impl& m = *impl_;
  constexpr auto relaxed = std::memory_order_relaxed;
  return {m.received.load(relaxed), m.malformed.load(relaxed), m.queue ? m.queue->dropped() : 0};
}

// ---- DdsWriter ---------------------------------------------------------------------------------

struct DdsWriter::Impl final : public fdds::DataWriterListener {
  DdsParticipant::Impl* owner = nullptr;
  fdds::DataWriter* writer = nullptr;
  DdsWriterOptions options;
  std::size_t bytes = 0;
  std::mutex write_mu;  // direct writes
  std::unique_ptr<ByteQueue> queue;
  std::counting_semaphore<> wake{0};
  std::atomic<bool> stop{false};
  std::thread thread;
  std::atomic<std::uint64_t> written{0}, failed{0};
  std::atomic<std::int32_t> matched{0};

  void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus& s) override {
    matched.store(s.current_count, std::memory_order_relaxed);
  }
  bool WriteNow(std::byte* sample) {
    CdrSample s{sample, true};
    const bool ok = writer->write(&s);
    (ok ? written : failed).fetch_add(1, std::memory_order_relaxed);
    return ok;
  }
  void Loop() {
    std::vector<std::byte> sample(bytes);
    for (;;) {
      if (options.poll_us > 0) {
        std::this_thread::sleep_for(std::chrono::microseconds(options.poll_us));
      } else {
        wake.try_acquire_for(std::chrono::milliseconds(50));
      }
      // Read before draining: whatever was pushed before the stop request is still written.
      const bool stopping = stop.load(std::memory_order_acquire);
      while (queue->TryPop(sample.data(), nullptr)) WriteNow(sample.data());
      if (stopping) return;
    }
  }
  ~Impl() override {
    if (thread.joinable()) {
      stop.store(true, std::memory_order_release);
      wake.release();
      thread.join();
    }
    if (writer != nullptr) {
      writer->set_listener(nullptr);
      owner->publisher->delete_datawriter(writer);
    }
  }
};

DdsWriter::DdsWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DdsWriter::~DdsWriter() = default;

Result<std::unique_ptr<DdsWriter>> DdsWriter::Create(DdsParticipant& participant, const std::string& topic,
                                                     const robot::IdlMessage& type, const DdsWriterOptions& o) {
  if (o.history_depth < 1 || o.history_depth > 4096)
    return DdsError("history_depth " + std::to_string(o.history_depth) + " is outside 1..4096");
  if (o.queue_capacity > 65536)
    return DdsError("queue_capacity " + std::to_string(o.queue_capacity) + " is above 65536");
  if (o.poll_us < 0 || o.poll_us > 1000000)
    return DdsError("poll_us " + std::to_string(o.poll_us) + " is outside 0..1000000");
  auto impl = std::make_unique<Impl>();
  impl->owner = &participant.impl();
  impl->options = o;
  impl->bytes = CdrSampleBytes(type);
  fdds::Topic* t = impl->owner->TopicFor(topic, type, o.type_name);
  if (t == nullptr) return DdsError("cannot create topic '" + topic + "' (type '" + o.type_name + "')");
  impl->writer = impl->owner->publisher->create_datawriter(t, WriterQos(o.history_depth), impl.get(),
                                                           fdds::StatusMask::publication_matched());
  if (impl->writer == nullptr) return DdsError("cannot create a writer of topic '" + topic + "'");
  if (o.queue_capacity > 0) {
    impl->queue = std::make_unique<ByteQueue>(impl->bytes, o.queue_capacity);
    Impl* m = impl.get();
    impl->thread = std::thread([m] { m->Loop(); });
  }
  return std::unique_ptr<DdsWriter>(new DdsWriter(std::move(impl)));
}

std::size_t DdsWriter::sample_bytes() const noexcept {
  return impl_->bytes;
}

Status DdsWriter::Write(const std::byte* sample) {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> lk(m.write_mu);
  // Fast DDS's write takes a mutable sample; serialize only reads it.
  if (!m.WriteNow(const_cast<std::byte*>(sample)))
    return DdsError("write on topic '" + m.writer->get_topic()->get_name() + "' failed");
  return {};
}

bool DdsWriter::Push(const std::byte* sample) noexcept {
  Impl& m = *impl_;
  if (!m.queue || !m.queue->TryPush(sample, 0)) return false;
  if (m.options.poll_us == 0) m.wake.release();
  return true;
}

bool DdsWriter::Flush(std::int64_t timeout_ns) {
  const std::int64_t n = timeout_ns > 0 ? timeout_ns : 0;
  const eprosima::fastrtps::Duration_t d(static_cast<std::int32_t>(n / 1'000'000'000),
                                         static_cast<std::uint32_t>(n % 1'000'000'000));
  return impl_->writer->wait_for_acknowledgments(d) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
}

std::int32_t DdsWriter::matched_readers() const noexcept {
  return impl_->matched.load(std::memory_order_relaxed);
}

DdsWriterCounters DdsWriter::counters() const noexcept {
  const Impl& m = *impl_;
  constexpr auto relaxed = std::memory_order_relaxed;
  return {m.written.load(relaxed), m.failed.load(relaxed), m.queue ? m.queue->dropped() : 0};
}

}  // namespace pbppo::dds
