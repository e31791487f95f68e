#include "runtime/transport/dds/auv_dds_link.hpp"

#include "runtime/transport/dds/auv_dds_convert.hpp"
#include "runtime/transport/dds/auv_message_check.hpp"

namespace pbppo::dds {

PBPPO_DDS_INSTANTIATE(robot::AuvSensorSample);
PBPPO_DDS_INSTANTIATE(robot::AuvCommand);
PBPPO_DDS_INSTANTIATE(robot::AuvControllerStatus);

namespace {

std::uint32_t CheckSample(const robot::AuvSensorSample& s) {
  return CheckAuvSensorSample(s);
}
std::uint32_t CheckCommand(const robot::AuvCommand& c) {
  return CheckAuvCommand(c);
}

}  // namespace

struct AuvDdsLink::Impl {
  AuvDdsRole role = AuvDdsRole::kController;
  // The participant is declared first: its readers and writers go before it.
  std::unique_ptr<DdsParticipant> participant;
  std::unique_ptr<DdsReader<robot::AuvSensorSample>> samples_in;      // controller
  std::unique_ptr<DdsWriter<robot::AuvCommand>> commands_out;         // controller (writer thread)
  std::unique_ptr<DdsWriter<robot::AuvControllerStatus>> status_out;  // controller
  std::unique_ptr<DdsWriter<robot::AuvSensorSample>> samples_out;     // vehicle
  std::unique_ptr<DdsReader<robot::AuvCommand>> commands_in;          // vehicle (every command, in order)
  std::unique_ptr<DdsReader<robot::AuvControllerStatus>> status_in;   // vehicle
};

Result<std::unique_ptr<AuvDdsLink>> AuvDdsLink::Create(AuvDdsRole role, const AuvDdsOptions& o) {
  if (o.command_queue_capacity < 1 || o.command_queue_capacity > 65536)
    return DdsError("command_queue_capacity " + std::to_string(o.command_queue_capacity) + " is outside 1..65536");
  if (o.command_inbox_capacity < 1 || o.command_inbox_capacity > 65536)
    return DdsError("command_inbox_capacity " + std::to_string(o.command_inbox_capacity) + " is outside 1..65536");
  auto impl = NewLink<Impl>(role, o);
  if (!impl) return std::move(impl).error();
  Impl& m = **impl;
  DdsParticipant& p = *m.participant;
  const std::string sensor = WireTopic(o.naming, o.topic_prefix + "sensor_state"),
                    command = WireTopic(o.naming, o.topic_prefix + "command"),
                    status = WireTopic(o.naming, o.topic_prefix + "controller_status");
  const std::string sensor_type = WireTypeName(o.naming, "AuvSensorState"),
                    command_type = WireTypeName(o.naming, "AuvCommand"),
                    status_type = WireTypeName(o.naming, "AuvControllerStatus");
  const DdsReaderOptions latest{DdsReaderMode::kLatest, 1, o.history_depth, kSampleTooManyBeams, sensor_type};
  const DdsWriterOptions direct{o.history_depth, 0, 0, sensor_type};
  Status st;
  if (role == AuvDdsRole::kController) {
    const DdsWriterOptions queued{o.history_depth, o.command_queue_capacity, o.writer_poll_us, command_type};
    if (!(st = TakeInto(DdsReader<robot::AuvSensorSample>::Create(p, sensor, latest, CheckSample), &m.samples_in)) ||
        !(st = TakeInto(DdsWriter<robot::AuvCommand>::Create(p, command, queued), &m.commands_out)) ||
        !(st = TakeInto(DdsWriter<robot::AuvControllerStatus>::Create(p, status, {4, 0, 0, status_type}),
                        &m.status_out)))
      return st.error();
  } else {
    const DdsReaderOptions inbox{DdsReaderMode::kQueue, o.command_inbox_capacity, o.history_depth, 0, command_type};
    if (!(st = TakeInto(DdsWriter<robot::AuvSensorSample>::Create(p, sensor, direct), &m.samples_out)) ||
        !(st = TakeInto(DdsReader<robot::AuvCommand>::Create(p, command, inbox, CheckCommand), &m.commands_in)) ||
        !(st = TakeInto(
              DdsReader<robot::AuvControllerStatus>::Create(p, status, {DdsReaderMode::kLatest, 1, 4, 0, status_type}),
              &m.status_in)))
      return st.error();
  }
  return std::unique_ptr<AuvDdsLink>(new AuvDdsLink(std::move(*impl)));
}

AuvDdsLink::AuvDdsLink(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AuvDdsLink::~AuvDdsLink() = default;

AuvDdsRole AuvDdsLink::role() const noexcept {
  return impl_->role;
}

int AuvDdsLink::domain_id() const noexcept {
  return impl_->participant->domain_id();
}

std::uint64_t AuvDdsLink::ReadSample(AuvSensorInput* out) noexcept {
  return impl_->samples_in ? impl_->samples_in->Read(out) : 0;
}

bool AuvDdsLink::PushCommand(const robot::AuvCommand& command) noexcept {
  return impl_->commands_out && impl_->commands_out->Push(command);
}

bool AuvDdsLink::WaitForSample(std::uint64_t after_version, std::int64_t timeout_ns) {
  return impl_->samples_in && impl_->samples_in->WaitNewer(after_version, timeout_ns);
}

Status AuvDdsLink::PublishStatus(const robot::AuvControllerStatus& status) {
  if (!impl_->status_out) return DdsError("PublishStatus: only the controller side publishes status");
  return impl_->status_out->Write(status);
}

Status AuvDdsLink::PublishSample(const robot::AuvSensorSample& sample) {
  if (!impl_->samples_out) return DdsError("PublishSample: only the vehicle side publishes samples");
  if (auto st = impl_->samples_out->Write(sample); !st)
    return DdsError("sensor sample write failed (tick " + std::to_string(sample.tick) + ")");
  return {};
}

bool AuvDdsLink::PopCommand(AuvCommandInput* out) noexcept {
  return impl_->commands_in && impl_->commands_in->Pop(out);
}

bool AuvDdsLink::WaitForCommand(AuvCommandInput* out, std::int64_t timeout_ns) {
  return impl_->commands_in && impl_->commands_in->WaitPop(out, timeout_ns);
}

std::uint64_t AuvDdsLink::ReadStatus(robot::AuvControllerStatus* out) noexcept {
  return impl_->status_in ? impl_->status_in->ReadValue(out) : 0;
}

bool AuvDdsLink::WaitForPeer(std::int64_t timeout_ns) {
  return PollUntil(
      [this] {
        const AuvPeerView p = Peer();
        return p.matched_readers > 0 && p.matched_writers > 0;
      },
      timeout_ns);
}

bool AuvDdsLink::Flush(std::int64_t timeout_ns) {
  const Impl& m = *impl_;
  if (m.role == AuvDdsRole::kVehicle) return m.samples_out->Flush(timeout_ns);
  const bool commands = m.commands_out->Flush(timeout_ns);
  return m.status_out->Flush(timeout_ns) && commands;
}

AuvPeerView AuvDdsLink::Peer() const noexcept {
  const Impl& m = *impl_;
  const bool controller = m.role == AuvDdsRole::kController;
  AuvPeerView p;
  p.matched_readers = controller ? m.commands_out->matched_readers() : m.samples_out->matched_readers();
  p.matched_writers = controller ? m.samples_in->matched_writers() : m.commands_in->matched_writers();
  const std::int64_t last = controller ? m.samples_in->last_receive_ns() : m.commands_in->last_receive_ns();
  p.last_receive_age_ns = last < 0 ? -1 : MonotonicNs() - last;
  return p;
}

AuvLinkCounters AuvDdsLink::counters() const noexcept {
  const Impl& m = *impl_;
  const bool controller = m.role == AuvDdsRole::kController;
  const DdsReaderCounters in = controller ? m.samples_in->counters() : m.commands_in->counters();
  const DdsWriterCounters out = controller ? m.commands_out->counters() : m.samples_out->counters();
  const DdsWriterCounters st = controller ? m.status_out->counters() : DdsWriterCounters{};
  AuvLinkCounters c;
  c.received = in.received;
  c.invalid = in.invalid;
  c.rejected = in.rejected;
  c.dropped_full = controller ? out.dropped : in.dropped;
  c.written = out.written + st.written;
  c.write_failed = out.failed + st.failed;
  return c;
}

}  // namespace pbppo::dds
