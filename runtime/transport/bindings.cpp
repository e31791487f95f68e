#include "runtime/transport/bindings.hpp"

#include "runtime/transport/dds/dds_transport.hpp"

namespace pbppo::transport {
namespace {

Result<std::unique_ptr<robot::Transport>> OpenCan(const robot::RobotModel& model, const robot::TransportSpec& spec,
                                                  const Settings& s) {
  auto t = can::CanTransport::Open(model, spec.name, s.can);
  if (!t) return std::move(t).error();
  (*t)->SetLockStep(s.can_lockstep_wait_ns);
  return std::unique_ptr<robot::Transport>(std::move(*t));
}

Result<std::unique_ptr<robot::Transport>> OpenDds(const robot::RobotModel& model, const robot::TransportSpec& spec,
                                                  const Settings& s) {
  auto t = dds::DdsTransport::Open(model, spec.name, s.dds);
  if (!t) return std::move(t).error();
  return std::unique_ptr<robot::Transport>(std::move(*t));
}

Result<std::unique_ptr<robot::Transport>> OpenEvdev(const robot::RobotModel& model, const robot::TransportSpec& spec,
                                                    const Settings& s) {
  auto t = evdev::EvdevTransport::Open(model, spec.name, s.evdev);
  if (!t) return std::move(t).error();
  return std::unique_ptr<robot::Transport>(std::move(*t));
}

constexpr Binding kBindings[] = {
    {"can", "MIT motors and IMUs of the CAN map over SocketCAN (or an in-process network)", OpenCan},
    {"dds", "the messages robot.yaml declares (IDL), over Fast DDS", OpenDds},
    {"evdev", "a gamepad's axes and buttons through Linux evdev (or a recorded event file)", OpenEvdev},
};

}  // namespace

std::span<const Binding> Bindings() {
  return kBindings;
}

Result<std::unique_ptr<robot::Transport>> Open(const robot::RobotModel& model, const robot::TransportSpec& spec,
                                               const Settings& settings) {
  std::string known;
  for (const Binding& b : kBindings) {
    if (spec.kind == b.kind) return b.open(model, spec, settings);
    known += (known.empty() ? "" : ", ") + std::string(b.kind);
  }
  return MakeError(ErrorCode::kUnsupported, model.path + ": transport '" + spec.name + "': no binding for kind '" +
                                                spec.kind + "' (known: " + known + ")");
}

}  // namespace pbppo::transport
