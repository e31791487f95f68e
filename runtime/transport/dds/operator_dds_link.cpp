#include "runtime/transport/dds/operator_dds_link.hpp"

#include <cmath>

#include "runtime/transport/dds/quadruped_dds_convert.hpp"

namespace pbppo::dds {

PBPPO_DDS_INSTANTIATE(robot::VelocityCommand);
PBPPO_DDS_INSTANTIATE(robot::QuadrupedStatus);

namespace {

std::uint32_t CheckCommand(const robot::VelocityCommand& c) {
  return std::isfinite(c.vx_mps) && std::isfinite(c.vy_mps) && std::isfinite(c.yaw_rate_radps) ? 0u : kCommandNonFinite;
}

}  // namespace

struct OperatorDdsLink::Impl {
  OperatorDdsRole role = OperatorDdsRole::kController;
  std::unique_ptr<DdsParticipant> participant;                      // first: its readers and writers go before it
  std::unique_ptr<DdsReader<robot::VelocityCommand>> commands_in;   // controller
  std::unique_ptr<DdsWriter<robot::QuadrupedStatus>> status_out;    // controller
  std::unique_ptr<DdsWriter<robot::VelocityCommand>> commands_out;  // operator
  std::unique_ptr<DdsReader<robot::QuadrupedStatus>> status_in;     // operator
};

Result<std::unique_ptr<OperatorDdsLink>> OperatorDdsLink::Create(OperatorDdsRole role, const OperatorDdsOptions& o) {
  auto impl = NewLink<Impl>(role, o);
  if (!impl) return std::move(impl).error();
  Impl& m = **impl;
  DdsParticipant& p = *m.participant;
  const std::string command = WireTopic(o.naming, o.topic_prefix + "velocity_command"),
                    status = WireTopic(o.naming, o.topic_prefix + "status");
  const std::string command_type = WireTypeName(o.naming, "VelocityCommand"),
                    status_type = WireTypeName(o.naming, "QuadrupedStatus");
  DdsReaderOptions command_reader{DdsReaderMode::kLatest, 1, 8, 0, command_type};
  command_reader.transient_local = false;
  const DdsReaderOptions status_reader{DdsReaderMode::kLatest, 1, 4, 0, status_type};
  Status st;
  if (role == OperatorDdsRole::kController) {
    if (!(st = TakeInto(DdsReader<robot::VelocityCommand>::Create(p, command, command_reader, CheckCommand),
                        &m.commands_in)) ||
        !(st = TakeInto(DdsWriter<robot::QuadrupedStatus>::Create(p, status, {4, 0, 0, status_type}), &m.status_out)))
      return st.error();
  } else {
    if (!(st = TakeInto(DdsWriter<robot::VelocityCommand>::Create(p, command, {8, 0, 0, command_type}),
                        &m.commands_out)) ||
        !(st = TakeInto(DdsReader<robot::QuadrupedStatus>::Create(p, status, status_reader), &m.status_in)))
      return st.error();
  }
  return std::unique_ptr<OperatorDdsLink>(new OperatorDdsLink(std::move(*impl)));
}

OperatorDdsLink::OperatorDdsLink(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OperatorDdsLink::~OperatorDdsLink() = default;

std::uint64_t OperatorDdsLink::ReadCommand(VelocityCommandInput* out) noexcept {
  return impl_->commands_in ? impl_->commands_in->Read(out) : 0;
}

Status OperatorDdsLink::PublishStatus(const robot::QuadrupedStatus& status) {
  if (!impl_->status_out) return DdsError("PublishStatus: only the controller side publishes status");
  return impl_->status_out->Write(status);
}

DdsReaderCounters OperatorDdsLink::command_counters() const noexcept {
  return impl_->commands_in ? impl_->commands_in->counters() : DdsReaderCounters{};
}

Status OperatorDdsLink::PublishCommand(const robot::VelocityCommand& command) {
  if (!impl_->commands_out) return DdsError("PublishCommand: only the operator side publishes commands");
  return impl_->commands_out->Write(command);
}

std::uint64_t OperatorDdsLink::ReadStatus(robot::QuadrupedStatus* out) noexcept {
  return impl_->status_in ? impl_->status_in->ReadValue(out) : 0;
}

bool OperatorDdsLink::WaitForStatus(std::uint64_t after_version, std::int64_t timeout_ns) {
  return impl_->status_in && impl_->status_in->WaitNewer(after_version, timeout_ns);
}

std::int32_t OperatorDdsLink::matched_readers() const noexcept {
  return impl_->status_out ? impl_->status_out->matched_readers() : impl_->commands_out->matched_readers();
}

std::int32_t OperatorDdsLink::matched_writers() const noexcept {
  return impl_->commands_in ? impl_->commands_in->matched_writers() : impl_->status_in->matched_writers();
}

bool OperatorDdsLink::WaitForPeer(std::int64_t timeout_ns) {
  return PollUntil([this] { return matched_readers() > 0 && matched_writers() > 0; }, timeout_ns);
}

bool OperatorDdsLink::Flush(std::int64_t timeout_ns) {
  return impl_->status_out ? impl_->status_out->Flush(timeout_ns) : impl_->commands_out->Flush(timeout_ns);
}

}  // namespace pbppo::dds
