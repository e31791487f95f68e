// The definitions of DdsReader<T> and DdsWriter<T> (dds_endpoint.hpp), with Fast DDS. Included
// only by the robots' DDS bindings beside it (auv_dds_*, quadruped_dds_convert, operator_dds_link),
// which declare how each message struct travels (the type fastddsgen generates from the robot's
// IDL), define the conversions and instantiate the templates:
//
//   PBPPO_DDS_TYPE(robot::AuvCommand, pbppo_idl::auv::Command);              // the header
//   PBPPO_DDS_FIELD_CONVERSIONS(robot::AuvCommand, PBPPO_AUV_COMMAND_FIELDS)  // a .cpp
//   PBPPO_DDS_INSTANTIATE(robot::AuvCommand);                                // the link's .cpp
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <map>
#include <mutex>
#include <semaphore>
#include <thread>

#include "runtime/core/clock.hpp"
#include "runtime/core/latest_mailbox.hpp"
#include "runtime/core/spsc_queue.hpp"
#include "runtime/transport/dds/dds_endpoint.hpp"

namespace pbppo::dds {

namespace fdds = eprosima::fastdds::dds;

// Specialised by a robot's binding for each of its message structs (see above).
template <typename T>
struct DdsType;

// DdsType<Message> for a message carried as the IDL type `Idl` (and fastddsgen's IdlPubSubType).
#define PBPPO_DDS_TYPE(Message, Idl)                             \
  template <>                                                    \
  struct DdsType<Message> {                                      \
    using Wire = Idl;                                            \
    using PubSubType = Idl##PubSubType;                          \
    static void ToWire(const Message& in, Wire* out) noexcept;   \
    static void FromWire(const Wire& in, Message* out) noexcept; \
  }

// The conversions of a message whose scalar fields are named alike in the struct and the IDL:
// FIELDS(X) lists them as X(name) X(name) ...
#define PBPPO_DDS_TO_WIRE_FIELD(f) out->f(in.f);
#define PBPPO_DDS_FROM_WIRE_FIELD(f) out->f = in.f();
#define PBPPO_DDS_FIELD_CONVERSIONS(Message, FIELDS)                       \
  void DdsType<Message>::ToWire(const Message& in, Wire* out) noexcept {   \
    FIELDS(PBPPO_DDS_TO_WIRE_FIELD)                                        \
  }                                                                        \
  void DdsType<Message>::FromWire(const Wire& in, Message* out) noexcept { \
    FIELDS(PBPPO_DDS_FROM_WIRE_FIELD)                                      \
  }

// The reader and writer of a message, compiled once (in its link's .cpp).
#define PBPPO_DDS_INSTANTIATE(Message) \
  template class DdsReader<Message>;   \
  template class DdsWriter<Message>

struct DdsParticipant::Impl {
  int domain_id = 0;
  fdds::DomainParticipant* participant = nullptr;
  fdds::Publisher* publisher = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  std::mutex topics_mu;
  std::map<std::string, fdds::Topic*> topics;
  ~Impl();
  // The topic `name` of `type` (the type registered, the topic created once); null on failure.
  // `type_name` non-empty: the type registered under that name instead of the IDL's.
  fdds::Topic* TopicFor(const std::string& name, fdds::TypeSupport type, const std::string& type_name);
};

// Reliable, transient-local, keep-last `depth`, no data-sharing (dds_participant.cpp says why).
fdds::DataWriterQos WriterQos(std::int32_t depth);
fdds::DataReaderQos ReaderQos(std::int32_t depth, bool transient_local);
Error DdsError(const std::string& what);

// Moves a created reader or writer into `out`; the creation's error otherwise.
template <typename T>
Status TakeInto(Result<std::unique_ptr<T>> r, std::unique_ptr<T>* out) {
  if (!r) return std::move(r).error();
  *out = std::move(*r);
  return {};
}

// A link's Impl (its members `role` and `participant`, the latter declared first) with a new
// participant on `options`; an empty topic prefix is refused.
template <typename Impl, typename Role, typename Options>
Result<std::unique_ptr<Impl>> NewLink(Role role, const Options& options) {
  if (options.topic_prefix.empty()) return DdsError("topic_prefix is empty");
  auto participant = DdsParticipant::Create(options);
  if (!participant) return std::move(participant).error();
  auto impl = std::make_unique<Impl>();
  impl->role = role;
  impl->participant = std::move(*participant);
  return impl;
}

// Polls `ready` every 5 ms: true once it holds, false when timeout_ns has passed first.
template <typename Ready>
bool PollUntil(Ready ready, std::int64_t timeout_ns) {
  const std::int64_t deadline = MonotonicNs() + timeout_ns;
  while (!ready()) {
    if (MonotonicNs() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// ---- DdsReader ---------------------------------------------------------------------------------

template <typename T>
struct DdsReader<T>::Impl final : public fdds::DataReaderListener {
  DdsParticipant::Impl* owner = nullptr;
  fdds::DataReader* reader = nullptr;
  DdsReaderOptions options;
  Check check = nullptr;
  // Listener callbacks are serialised by take_mu (one producer for the mailbox or the queue).
  std::mutex take_mu;
  typename DdsType<T>::Wire rx;
  LatestMailbox<DdsReceived<T>> latest;
  std::unique_ptr<SpscQueue<DdsReceived<T>>> queue;
  std::atomic<std::uint64_t> received{0}, invalid{0}, rejected{0};
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
      DdsReceived<T> in;
      DdsType<T>::FromWire(rx, &in.value);
      in.flags = check != nullptr ? check(in.value) : 0;
      in.received_ns = now;
      if ((in.flags & options.reject_mask) != 0) {
        rejected.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      if (in.flags != 0) invalid.fetch_add(1, std::memory_order_relaxed);
      if (queue) {
        queue->TryPush(in);  // counts the drop when full
      } else {
        latest.Write(in);
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

// Defined here, where Impl is complete (its destructor deletes the DDS entity).
template <typename T>
DdsReader<T>::~DdsReader() = default;

template <typename T>
Result<std::unique_ptr<DdsReader<T>>> DdsReader<T>::Create(DdsParticipant& participant, const std::string& topic,
                                                           const DdsReaderOptions& o, Check check) {
  if (o.history_depth < 1 || o.history_depth > 4096)
    return DdsError("history_depth " + std::to_string(o.history_depth) + " is outside 1..4096");
  if (o.mode == DdsReaderMode::kQueue && (o.queue_capacity < 1 || o.queue_capacity > 65536))
    return DdsError("queue_capacity " + std::to_string(o.queue_capacity) + " is outside 1..65536");
  auto impl = std::make_unique<Impl>();
  impl->owner = &participant.impl();
  impl->options = o;
  impl->check = check;
  if (o.mode == DdsReaderMode::kQueue) impl->queue = std::make_unique<SpscQueue<DdsReceived<T>>>(o.queue_capacity);
  fdds::Topic* t = impl->owner->TopicFor(topic, fdds::TypeSupport(new typename DdsType<T>::PubSubType()), o.type_name);
  if (t == nullptr) return DdsError("cannot create topic '" + topic + "' (type '" + o.type_name + "')");
  const fdds::StatusMask mask = fdds::StatusMask::data_available() << fdds::StatusMask::subscription_matched();
  impl->reader =
      impl->owner->subscriber->create_datareader(t, ReaderQos(o.history_depth, o.transient_local), impl.get(), mask);
  if (impl->reader == nullptr) return DdsError("cannot create a reader of topic '" + topic + "'");
  return std::unique_ptr<DdsReader>(new DdsReader(std::move(impl)));
}

template <typename T>
std::uint64_t DdsReader<T>::Read(DdsReceived<T>* out) noexcept {
  return impl_->queue ? 0 : impl_->latest.Read(out);
}

template <typename T>
std::uint64_t DdsReader<T>::ReadValue(T* out) noexcept {
  DdsReceived<T> r;
  const std::uint64_t v = Read(&r);
  if (v != 0) *out = r.value;
  return v;
}

template <typename T>
std::uint64_t DdsReader<T>::version() const noexcept {
  return impl_->latest.version();
}

template <typename T>
bool DdsReader<T>::WaitNewer(std::uint64_t after_version, std::int64_t timeout_ns) {
  Impl& m = *impl_;
  std::unique_lock<std::mutex> lk(m.wait_mu);
  return m.wait_cv.wait_for(lk, std::chrono::nanoseconds(timeout_ns),
                            [&] { return m.latest.version() > after_version; });
}

template <typename T>
bool DdsReader<T>::Pop(DdsReceived<T>* out) noexcept {
  return impl_->queue && impl_->queue->TryPop(out);
}

template <typename T>
bool DdsReader<T>::WaitPop(DdsReceived<T>* out, std::int64_t timeout_ns) {
  Impl& m = *impl_;
  if (!m.queue) return false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(timeout_ns);
  for (;;) {
    std::uint64_t seen = 0;
    {
      std::lock_guard<std::mutex> lk(m.wait_mu);
      seen = m.arrivals;
    }
    if (m.queue->TryPop(out)) return true;
    std::unique_lock<std::mutex> lk(m.wait_mu);
    if (!m.wait_cv.wait_until(lk, deadline, [&] { return m.arrivals != seen; })) return m.queue->TryPop(out);
  }
}

template <typename T>
std::int32_t DdsReader<T>::matched_writers() const noexcept {
  return impl_->matched.load(std::memory_order_relaxed);
}

template <typename T>
std::int64_t DdsReader<T>::last_receive_ns() const noexcept {
  return impl_->last_ns.load(std::memory_order_relaxed);
}

template <typename T>
DdsReaderCounters DdsReader<T>::counters() const noexcept {
  const Impl& m = *impl_;
  constexpr auto relaxed = std::memory_order_relaxed;
  return {m.received.load(relaxed), m.invalid.load(relaxed), m.rejected.load(relaxed),
          m.queue ? m.queue->dropped() : 0};
}

// ---- DdsWriter ---------------------------------------------------------------------------------

template <typename T>
struct DdsWriter<T>::Impl final : public fdds::DataWriterListener {
  DdsParticipant::Impl* owner = nullptr;
  fdds::DataWriter* writer = nullptr;
  DdsWriterOptions options;
  std::mutex write_mu;  // direct writes
  typename DdsType<T>::Wire tx;
  std::unique_ptr<SpscQueue<T>> queue;
  std::counting_semaphore<> wake{0};
  std::atomic<bool> stop{false};
  std::thread thread;
  std::atomic<std::uint64_t> written{0}, failed{0};
  std::atomic<std::int32_t> matched{0};

  void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus& s) override {
    matched.store(s.current_count, std::memory_order_relaxed);
  }
  void Count(bool ok) { (ok ? written : failed).fetch_add(1, std::memory_order_relaxed); }
  void Loop() {
    typename DdsType<T>::Wire msg;
    T m{};
    for (;;) {
      if (options.poll_us > 0) {
        std::this_thread::sleep_for(std::chrono::microseconds(options.poll_us));
      } else {
        wake.try_acquire_for(std::chrono::milliseconds(50));
      }
      // Read before draining: whatever was pushed before the stop request is still written.
      const bool stopping = stop.load(std::memory_order_acquire);
      while (queue->TryPop(&m)) {
        DdsType<T>::ToWire(m, &msg);
        Count(writer->write(&msg));
      }
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

// Defined here, where Impl is complete (its destructor deletes the DDS entity).
template <typename T>
DdsWriter<T>::~DdsWriter() = default;

template <typename T>
Result<std::unique_ptr<DdsWriter<T>>> DdsWriter<T>::Create(DdsParticipant& participant, const std::string& topic,
                                                           const DdsWriterOptions& o) {
  if (o.history_depth < 1 || o.history_depth > 4096)
    return DdsError("history_depth " + std::to_string(o.history_depth) + " is outside 1..4096");
  if (o.queue_capacity > 65536)
    return DdsError("queue_capacity " + std::to_string(o.queue_capacity) + " is above 65536");
  if (o.poll_us < 0 || o.poll_us > 1000000)
    return DdsError("poll_us " + std::to_string(o.poll_us) + " is outside 0..1000000");
  auto impl = std::make_unique<Impl>();
  impl->owner = &participant.impl();
  impl->options = o;
  fdds::Topic* t = impl->owner->TopicFor(topic, fdds::TypeSupport(new typename DdsType<T>::PubSubType()), o.type_name);
  if (t == nullptr) return DdsError("cannot create topic '" + topic + "' (type '" + o.type_name + "')");
  impl->writer = impl->owner->publisher->create_datawriter(t, WriterQos(o.history_depth), impl.get(),
                                                           fdds::StatusMask::publication_matched());
  if (impl->writer == nullptr) return DdsError("cannot create a writer of topic '" + topic + "'");
  if (o.queue_capacity > 0) {
    impl->queue = std::make_unique<SpscQueue<T>>(o.queue_capacity);
    Impl* m = impl.get();
    impl->thread = std::thread([m] { m->Loop(); });
  }
  return std::unique_ptr<DdsWriter>(new DdsWriter(std::move(impl)));
}

template <typename T>
Status DdsWriter<T>::Write(const T& message) {
  Impl& m = *impl_;
  std::lock_guard<std::mutex> lk(m.write_mu);
  DdsType<T>::ToWire(message, &m.tx);
  const bool ok = m.writer->write(&m.tx);
  m.Count(ok);
  if (!ok) return DdsError("write on topic '" + m.writer->get_topic()->get_name() + "' failed");
  return {};
}

template <typename T>
bool DdsWriter<T>::Push(const T& message) noexcept {
  Impl& m = *impl_;
  if (!m.queue || !m.queue->TryPush(message)) return false;
  if (m.options.poll_us == 0) m.wake.release();
  return true;
}

template <typename T>
bool DdsWriter<T>::Flush(std::int64_t timeout_ns) {
  const std::int64_t n = timeout_ns > 0 ? timeout_ns : 0;
  const eprosima::fastrtps::Duration_t d(static_cast<std::int32_t>(n / 1'000'000'000),
                                         static_cast<std::uint32_t>(n % 1'000'000'000));
  return impl_->writer->wait_for_acknowledgments(d) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
}

template <typename T>
std::int32_t DdsWriter<T>::matched_readers() const noexcept {
  return impl_->matched.load(std::memory_order_relaxed);
}

template <typename T>
DdsWriterCounters DdsWriter<T>::counters() const noexcept {
  const Impl& m = *impl_;
  constexpr auto relaxed = std::memory_order_relaxed;
  return {m.written.load(relaxed), m.failed.load(relaxed), m.queue ? m.queue->dropped() : 0};
}

}  // namespace pbppo::dds
