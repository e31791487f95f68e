#include "runtime/transport/dds/auv_dds_link.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
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
#include <fstream>
#include <mutex>
#include <semaphore>
#include <thread>

#include "runtime/core/clock.hpp"
#include "runtime/core/latest_mailbox.hpp"
#include "runtime/core/spsc_queue.hpp"
#include "runtime/transport/dds/auv_dds_convert.hpp"
#include "runtime/transport/dds/auv_message_check.hpp"

namespace pbppo::dds {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::Duration_t;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

Duration_t ToDuration(std::int64_t ns) {
  const std::int64_t n = std::max<std::int64_t>(ns, 0);
  return Duration_t(static_cast<std::int32_t>(n / 1'000'000'000), static_cast<std::uint32_t>(n % 1'000'000'000));
}

// Counts matches of one writer (readers of what we publish).
class MatchCounter final : public fdds::DataWriterListener {
 public:
  explicit MatchCounter(std::atomic<std::int32_t>* count) : count_(count) {}
  void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus& info) override {
    if (count_ != nullptr) count_->store(info.current_count, std::memory_order_relaxed);
  }

 private:
  std::atomic<std::int32_t>* count_;
};

}  // namespace

struct AuvDdsLink::Impl {
  AuvDdsRole role = AuvDdsRole::kController;
  AuvDdsOptions options;

  // DDS entities (owned by the participant; deleted in the destructor).
  fdds::DomainParticipant* participant = nullptr;
  fdds::Publisher* publisher = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  fdds::DataWriter* main_writer = nullptr;    // controller: command; vehicle: sensor state
  fdds::DataWriter* status_writer = nullptr;  // controller only
  fdds::DataReader* main_reader = nullptr;    // controller: sensor state; vehicle: command
  fdds::DataReader* status_reader = nullptr;  // vehicle only

  // Counters and the peer view.
  std::atomic<std::uint64_t> received{0}, invalid{0}, rejected{0}, written{0}, write_failed{0};
  std::atomic<std::int32_t> matched_readers{0}, matched_writers{0};
  std::atomic<std::int64_t> last_receive_ns{-1};

  // Listener side -> consumer. Listener callbacks are serialised by take_mu (one producer).
  std::mutex take_mu;
  LatestMailbox<AuvSensorInput> samples;                 // controller
  LatestMailbox<robot::AuvControllerStatus> status_box;  // vehicle
  std::unique_ptr<SpscQueue<AuvCommandInput>> inbox;     // vehicle
  pbppo_idl::auv::SensorState rx_sample;
  pbppo_idl::auv::Command rx_command;
  pbppo_idl::auv::ControllerStatus rx_status;

  // Wakes WaitForSample / WaitForCommand.
  std::mutex wait_mu;
  std::condition_variable wait_cv;
  std::uint64_t arrivals = 0;  // guarded by wait_mu

  // Controller: tick -> writer thread.
  std::unique_ptr<SpscQueue<robot::AuvCommand>> outbox;
  std::counting_semaphore<> wake{0};
  std::int64_t poll_us = 0;
  std::atomic<bool> stop{false};
  std::thread writer_thread;

  // Direct writes from non-real-time callers.
  std::mutex publish_mu;
  pbppo_idl::auv::SensorState tx_sample;
  pbppo_idl::auv::ControllerStatus tx_status;

  // Listeners.
  MatchCounter main_writer_listener{&matched_readers};
  MatchCounter status_writer_listener{nullptr};
  struct ReaderListener final : public fdds::DataReaderListener {
    Impl* impl = nullptr;
    bool is_main = true;
    void on_data_available(fdds::DataReader* reader) override { impl->OnData(reader, is_main); }
    void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& info) override {
      if (is_main) impl->matched_writers.store(info.current_count, std::memory_order_relaxed);
    }
  };
  ReaderListener main_reader_listener;
  ReaderListener status_reader_listener;

  void Notify() {
    {
      std::lock_guard<std::mutex> lk(wait_mu);
      ++arrivals;
    }
    wait_cv.notify_all();
  }

  void OnData(fdds::DataReader* reader, bool is_main) {
    std::lock_guard<std::mutex> lk(take_mu);
    fdds::SampleInfo info;
    bool any = false;
    for (;;) {
      void* data = !is_main                          ? static_cast<void*>(&rx_status)
                   : role == AuvDdsRole::kController ? static_cast<void*>(&rx_sample)
                                                     : static_cast<void*>(&rx_command);
      if (reader->take_next_sample(data, &info) != ReturnCode_t::RETCODE_OK) break;
      if (!info.valid_data) continue;  // dispose / unregister notifications
      any = true;
      if (!is_main) {
        robot::AuvControllerStatus s;
        FromDds(rx_status, &s);
        status_box.Write(s);
        continue;
      }
      const std::int64_t now = MonotonicNs();
      received.fetch_add(1, std::memory_order_relaxed);
      last_receive_ns.store(now, std::memory_order_relaxed);
      if (role == AuvDdsRole::kController) {
        AuvSensorInput in;
        FromDds(rx_sample, &in.sample);
        in.flags = CheckAuvSensorSample(in.sample);
        in.received_ns = now;
        if ((in.flags & kSampleTooManyBeams) != 0) {
          rejected.fetch_add(1, std::memory_order_relaxed);
          continue;
        }
        if (in.flags != 0) invalid.fetch_add(1, std::memory_order_relaxed);
        samples.Write(in);
      } else {
        AuvCommandInput in;
        FromDds(rx_command, &in.command);
        in.flags = CheckAuvCommand(in.command);
        in.received_ns = now;
        if (in.flags != 0) invalid.fetch_add(1, std::memory_order_relaxed);
        inbox->TryPush(in);  // counts the drop when full
      }
    }
    if (any) Notify();
  }

  void CountWrite(bool ok) { (ok ? written : write_failed).fetch_add(1, std::memory_order_relaxed); }

  void WriterLoop() {
    pbppo_idl::auv::Command msg;
    robot::AuvCommand c;
    for (;;) {
      if (poll_us > 0) {
        std::this_thread::sleep_for(std::chrono::microseconds(poll_us));
      } else {
        wake.try_acquire_for(std::chrono::milliseconds(50));
      }
      // Read before draining: whatever was pushed before the stop request is still written.
      const bool stopping = stop.load(std::memory_order_acquire);
      while (outbox->TryPop(&c)) {
        ToDds(c, &msg);
        CountWrite(main_writer->write(&msg));
      }
      if (stopping) return;
    }
  }

  ~Impl() {
    if (writer_thread.joinable()) {
      stop.store(true, std::memory_order_release);
      wake.release();
      writer_thread.join();
    }
    if (participant != nullptr) {
      if (main_reader != nullptr) main_reader->set_listener(nullptr);
      if (status_reader != nullptr) status_reader->set_listener(nullptr);
      if (main_writer != nullptr) main_writer->set_listener(nullptr);
      participant->delete_contained_entities();
      fdds::DomainParticipantFactory::get_instance()->delete_participant(participant);
    }
  }
};

namespace {

Error Fail(const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, "dds: " + what);
}

// Reliable, and transient-local: discovery is not symmetric (our writer may know a reader before
// that reader knows our writer, and a volatile reader drops what was written before it matched),
// so the first lock-step sample or command written right after matching would otherwise be lost.
// A reader that joins late gets the writer's last `depth` messages.
fdds::DataWriterQos WriterQos(std::int32_t depth) {
  fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  q.publish_mode().kind = fdds::SYNCHRONOUS_PUBLISH_MODE;
  q.data_sharing().off();  // see ReaderQos
  return q;
}

fdds::DataReaderQos ReaderQos(std::int32_t depth) {
  fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  // No data-sharing (shared-memory delivery between participants on one host): Fast DDS 2.9's
  // DataSharingListener can spin forever on a sample it rejects, and deleting the reader then
  // hangs joining that thread (seen here: a test process at 100 % CPU in
  // DataSharingListener::process_new_data while ~DataReaderImpl waited; fixed upstream in
  // eProsima/Fast-DDS#6490, not in Debian's 2.9). Samples take the loopback UDP transport of the
  // profile, like between machines.
  q.data_sharing().off();
  return q;
}

}  // namespace

Result<std::unique_ptr<AuvDdsLink>> AuvDdsLink::Create(AuvDdsRole role, const AuvDdsOptions& o) {
  if (o.domain_id < 0 || o.domain_id > 232)
    return Fail("domain_id " + std::to_string(o.domain_id) + " is outside 0..232");
  if (o.writer_poll_us < 0 || o.writer_poll_us > 1000000)
    return Fail("writer_poll_us " + std::to_string(o.writer_poll_us) + " is outside 0..1000000");
  if (o.command_queue_capacity < 1 || o.command_queue_capacity > 65536)
    return Fail("command_queue_capacity " + std::to_string(o.command_queue_capacity) + " is outside 1..65536");
  if (o.command_inbox_capacity < 1 || o.command_inbox_capacity > 65536)
    return Fail("command_inbox_capacity " + std::to_string(o.command_inbox_capacity) + " is outside 1..65536");
  if (o.history_depth < 1 || o.history_depth > 4096)
    return Fail("history_depth " + std::to_string(o.history_depth) + " is outside 1..4096");
  if (o.topic_prefix.empty()) return Fail("topic_prefix is empty");
  if (!std::ifstream(o.profile_file).good())
    return MakeError(ErrorCode::kIo, "dds: profile_file '" + o.profile_file + "' cannot be read");

  auto* factory = fdds::DomainParticipantFactory::get_instance();
  // Loading a file a second time in one process is harmless; a file Fast DDS cannot parse makes
  // the profile lookup below fail, which names both.
  const bool loaded = factory->load_XML_profiles_file(o.profile_file) == ReturnCode_t::RETCODE_OK;

  auto impl = std::make_unique<Impl>();
  impl->role = role;
  impl->options = o;
  Impl& m = *impl;
  m.participant =
      factory->create_participant_with_profile(static_cast<fdds::DomainId_t>(o.domain_id), o.participant_profile);
  if (m.participant == nullptr)
    return Fail("participant_profile '" + o.participant_profile + "' from profile_file '" + o.profile_file + "'" +
                (loaded ? "" : " (the file did not load)") + ": no participant on domain " +
                std::to_string(o.domain_id));

  fdds::TypeSupport sensor_type(new pbppo_idl::auv::SensorStatePubSubType());
  fdds::TypeSupport command_type(new pbppo_idl::auv::CommandPubSubType());
  fdds::TypeSupport status_type(new pbppo_idl::auv::ControllerStatusPubSubType());
  for (auto* t : {&sensor_type, &command_type, &status_type})
    if (t->register_type(m.participant) != ReturnCode_t::RETCODE_OK)
      return Fail("cannot register type " + t->get_type_name());
  auto topic = [&](const char* name, const fdds::TypeSupport& t) {
    return m.participant->create_topic(o.topic_prefix + name, t.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  };
  fdds::Topic* sensor_topic = topic("sensor_state", sensor_type);
  fdds::Topic* command_topic = topic("command", command_type);
  fdds::Topic* status_topic = topic("controller_status", status_type);
  if (sensor_topic == nullptr || command_topic == nullptr || status_topic == nullptr)
    return Fail("topic_prefix '" + o.topic_prefix + "': cannot create the topics");
  m.publisher = m.participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  m.subscriber = m.participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  if (m.publisher == nullptr || m.subscriber == nullptr) return Fail("cannot create publisher/subscriber");

  const bool controller = role == AuvDdsRole::kController;
  m.main_reader_listener.impl = &m;
  m.main_reader_listener.is_main = true;
  m.status_reader_listener.impl = &m;
  m.status_reader_listener.is_main = false;
  if (controller) {
    m.outbox = std::make_unique<SpscQueue<robot::AuvCommand>>(o.command_queue_capacity);
    m.poll_us = o.writer_poll_us;
  } else {
    m.inbox = std::make_unique<SpscQueue<AuvCommandInput>>(o.command_inbox_capacity);
  }
  const fdds::StatusMask data_mask = fdds::StatusMask::data_available() << fdds::StatusMask::subscription_matched();
  m.main_writer = m.publisher->create_datawriter(controller ? command_topic : sensor_topic, WriterQos(o.history_depth),
                                                 &m.main_writer_listener, fdds::StatusMask::publication_matched());
  m.main_reader = m.subscriber->create_datareader(controller ? sensor_topic : command_topic, ReaderQos(o.history_depth),
                                                  &m.main_reader_listener, data_mask);
  if (m.main_writer == nullptr || m.main_reader == nullptr) return Fail("cannot create the data writer/reader");
  if (controller) {
    m.status_writer =
        m.publisher->create_datawriter(status_topic, WriterQos(4), &m.status_writer_listener, fdds::StatusMask::none());
    if (m.status_writer == nullptr) return Fail("cannot create the status writer");
    m.writer_thread = std::thread([&m] { m.WriterLoop(); });
  } else {
    m.status_reader = m.subscriber->create_datareader(status_topic, ReaderQos(4), &m.status_reader_listener, data_mask);
    if (m.status_reader == nullptr) return Fail("cannot create the status reader");
  }
  return std::unique_ptr<AuvDdsLink>(new AuvDdsLink(std::move(impl)));
}

AuvDdsLink::AuvDdsLink(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AuvDdsLink::~AuvDdsLink() = default;

AuvDdsRole AuvDdsLink::role() const noexcept {
  return impl_->role;
}

std::uint64_t AuvDdsLink::ReadSample(AuvSensorInput* out) noexcept {
  if (impl_->role != AuvDdsRole::kController) return 0;
  return impl_->samples.Read(out);
}

bool AuvDdsLink::PushCommand(const robot::AuvCommand& command) noexcept {
  if (impl_->role != AuvDdsRole::kController) return false;
  if (!impl_->outbox->TryPush(command)) return false;
  if (impl_->poll_us == 0) impl_->wake.release();
  return true;
}

bool AuvDdsLink::WaitForSample(std::uint64_t after_version, std::int64_t timeout_ns) {
  Impl& m = *impl_;
  std::unique_lock<std::mutex> lk(m.wait_mu);
  return m.wait_cv.wait_for(lk, std::chrono::nanoseconds(timeout_ns),
                            [&] { return m.samples.version() > after_version; });
}

Status AuvDdsLink::PublishStatus(const robot::AuvControllerStatus& status) {
  Impl& m = *impl_;
  if (m.role != AuvDdsRole::kController) return Fail("PublishStatus: only the controller side publishes status");
  std::lock_guard<std::mutex> lk(m.publish_mu);
  ToDds(status, &m.tx_status);
  const bool ok = m.status_writer->write(&m.tx_status);
  m.CountWrite(ok);
  if (!ok) return Fail("status write failed");
  return {};
}

Status AuvDdsLink::PublishSample(const robot::AuvSensorSample& sample) {
  Impl& m = *impl_;
  if (m.role != AuvDdsRole::kVehicle) return Fail("PublishSample: only the vehicle side publishes samples");
  std::lock_guard<std::mutex> lk(m.publish_mu);
  ToDds(sample, &m.tx_sample);
  const bool ok = m.main_writer->write(&m.tx_sample);
  m.CountWrite(ok);
  if (!ok) return Fail("sensor sample write failed (tick " + std::to_string(sample.tick) + ")");
  return {};
}

bool AuvDdsLink::PopCommand(AuvCommandInput* out) noexcept {
  if (impl_->role != AuvDdsRole::kVehicle) return false;
  return impl_->inbox->TryPop(out);
}

bool AuvDdsLink::WaitForCommand(AuvCommandInput* out, std::int64_t timeout_ns) {
  Impl& m = *impl_;
  if (m.role != AuvDdsRole::kVehicle) return false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(timeout_ns);
  for (;;) {
    std::uint64_t seen = 0;
    {
      std::lock_guard<std::mutex> lk(m.wait_mu);
      seen = m.arrivals;
    }
    if (m.inbox->TryPop(out)) return true;
    std::unique_lock<std::mutex> lk(m.wait_mu);
    if (!m.wait_cv.wait_until(lk, deadline, [&] { return m.arrivals != seen; })) return m.inbox->TryPop(out);
  }
}

std::uint64_t AuvDdsLink::ReadStatus(robot::AuvControllerStatus* out) noexcept {
  if (impl_->role != AuvDdsRole::kVehicle) return 0;
  return impl_->status_box.Read(out);
}

bool AuvDdsLink::WaitForPeer(std::int64_t timeout_ns) {
  const std::int64_t deadline = MonotonicNs() + timeout_ns;
  for (;;) {
    const AuvPeerView p = Peer();
    if (p.matched_readers > 0 && p.matched_writers > 0) return true;
    if (MonotonicNs() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

bool AuvDdsLink::Flush(std::int64_t timeout_ns) {
  Impl& m = *impl_;
  bool ok = m.main_writer->wait_for_acknowledgments(ToDuration(timeout_ns)) == ReturnCode_t::RETCODE_OK;
  if (m.status_writer != nullptr)
    ok = m.status_writer->wait_for_acknowledgments(ToDuration(timeout_ns)) == ReturnCode_t::RETCODE_OK && ok;
  return ok;
}

AuvPeerView AuvDdsLink::Peer() const noexcept {
  const Impl& m = *impl_;
  AuvPeerView p;
  p.matched_readers = m.matched_readers.load(std::memory_order_relaxed);
  p.matched_writers = m.matched_writers.load(std::memory_order_relaxed);
  const std::int64_t last = m.last_receive_ns.load(std::memory_order_relaxed);
  p.last_receive_age_ns = last < 0 ? -1 : MonotonicNs() - last;
  return p;
}

AuvLinkCounters AuvDdsLink::counters() const noexcept {
  const Impl& m = *impl_;
  AuvLinkCounters c;
  c.received = m.received.load(std::memory_order_relaxed);
  c.invalid = m.invalid.load(std::memory_order_relaxed);
  c.rejected = m.rejected.load(std::memory_order_relaxed);
  c.dropped_full = m.role == AuvDdsRole::kController ? m.outbox->dropped() : m.inbox->dropped();
  c.written = m.written.load(std::memory_order_relaxed);
  c.write_failed = m.write_failed.load(std::memory_order_relaxed);
  return c;
}

}  // namespace pbppo::dds
