// The transport table: which code serves each kind of transport a robot file declares. A
// controller (pbppo-controller, a HIL's in-process controller, a test) builds a robot's transports
// from robot.yaml alone through it, and names no robot:
//
//   kind  binding
//   can   can::CanTransport over the robot's CAN map (SocketCAN, or an in-process network)
//   dds   dds::DdsTransport over the messages the robot file declares (runtime/robot/transport_spec.hpp)
//   evdev evdev::EvdevTransport: a gamepad's axes and buttons (a device, or a recorded event file)
//
// A new kind of link is one entry here and its transport; a new robot on an existing kind is data.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "runtime/transport/evdev/evdev_transport.hpp"

namespace pbppo::transport {

// What the caller (a command line) sets for the transports it opens; each kind reads its part.
struct Settings {
  can::CanTransportOptions can;           // interfaces, candump, receive_all, an in-process network
  std::int64_t can_lockstep_wait_ns = 0;  // > 0: each tick waits this long for the replies owed
  dds::DdsLinkOptions dds;                // domain, naming, profile file, security, writer polling, lost_after_s
  evdev::EvdevOptions evdev;              // a gamepad's device in place of the robot file's
};

struct Binding {
  const char* kind;
  const char* what;  // one line, for help and errors
  Result<std::unique_ptr<robot::Transport>> (*open)(const robot::RobotModel& model, const robot::TransportSpec& spec,
                                                    const Settings& settings);
};

// The table, in the order above.
std::span<const Binding> Bindings();

// Opens the transport `spec` of `model` through the binding of its kind; an unknown kind is
// refused naming the robot file, the transport and the kinds there are.
Result<std::unique_ptr<robot::Transport>> Open(const robot::RobotModel& model, const robot::TransportSpec& spec,
                                               const Settings& settings);

}  // namespace pbppo::transport
