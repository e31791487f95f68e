// The quadruped operator's DDS link (Fast DDS 2.9): velocity commands from an operator to the
// walking controller, the controller's status back. One object per side:
//
//  controller side (OperatorDdsRole::kController)
//    commands  -> a DDS listener thread stores each in a latest-value mailbox with its arrival
//                 time; the real-time tick reads the newest with ReadCommand (no allocation, lock
//                 or block). The reader is volatile: a command counts only when it is sent (a
//                 controller that starts late does not act on an operator's old command).
//    status    <- PublishStatus, from a non-real-time thread.
//
//  operator side (OperatorDdsRole::kOperator: a schedule player, a test, a joystick bridge)
//    commands  <- PublishCommand;   status -> ReadStatus (latest value).
//
// Topics <prefix>velocity_command and <prefix>status (prefix pbppo/quadruped/); with
// DdsNaming::kRos2, rt/pbppo/quadruped/... carrying pbppo_msgs::msg::dds_::VelocityCommand_ and
// QuadrupedStatus_, so ROS 2 nodes and other DDS implementations can drive the robot.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/result.hpp"
#include "runtime/robot/quadruped_messages.hpp"
#include "runtime/transport/dds/dds_endpoint.hpp"

namespace pbppo::dds {

enum class OperatorDdsRole { kController, kOperator };

// The participant (profiles, participant profile, domain: DdsOptions), and the link's own settings.
struct OperatorDdsOptions : DdsOptions {
  std::string topic_prefix = "pbppo/quadruped/";
  DdsNaming naming = DdsNaming::kNative;
};

using VelocityCommandInput = DdsReceived<robot::VelocityCommand>;

// Flag bits of a received command (DdsReceived::flags).
inline constexpr std::uint32_t kCommandNonFinite = 1u << 0;

class OperatorDdsLink {
 public:
  // Errors name the option and its value.
  static Result<std::unique_ptr<OperatorDdsLink>> Create(OperatorDdsRole role, const OperatorDdsOptions& options);
  ~OperatorDdsLink();
  OperatorDdsLink(const OperatorDdsLink&) = delete;
  OperatorDdsLink& operator=(const OperatorDdsLink&) = delete;

  // ---- controller ----
  // Real-time safe: the newest command and its version (1, 2 ... in arrival order), 0 while none.
  std::uint64_t ReadCommand(VelocityCommandInput* out) noexcept;
  Status PublishStatus(const robot::QuadrupedStatus& status);
  DdsReaderCounters command_counters() const noexcept;

  // ---- operator ----
  Status PublishCommand(const robot::VelocityCommand& command);
  // The newest status and its version, 0 while none.
  std::uint64_t ReadStatus(robot::QuadrupedStatus* out) noexcept;
  // Waits for a status newer than `after_version`; false on timeout.
  bool WaitForStatus(std::uint64_t after_version, std::int64_t timeout_ns);

  // ---- both ----
  // Until this side's writer has a matched reader and its reader a matched writer.
  bool WaitForPeer(std::int64_t timeout_ns);
  bool Flush(std::int64_t timeout_ns);
  std::int32_t matched_readers() const noexcept;
  std::int32_t matched_writers() const noexcept;

  struct Impl;

 private:
  explicit OperatorDdsLink(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::dds
