// The AUV's DDS link (Fast DDS 2.9), one object per side:
//
//  controller side (AuvDdsRole::kController)
//    sensor samples  -> a DDS listener thread converts, checks and stores each one in a
//                       latest-value mailbox; the real-time tick reads it with ReadSample
//                       (no allocation, lock or block);
//    commands        <- the tick puts them into a bounded queue with PushCommand (dropped and
//                       counted when full); a writer thread of this object does the DDS write()
//                       (a reliable write allocates, so it never runs in the tick);
//    status          <- PublishStatus from a non-real-time thread.
//
//  vehicle side (AuvDdsRole::kVehicle, used by the HIL simulator)
//    sensor samples  <- PublishSample writes directly from the caller's thread;
//    commands        -> checked like the samples and queued in arrival order (PopCommand /
//                       WaitForCommand), so a lock-step simulator sees every one;
//    status          -> latest-value mailbox (ReadStatus).
//
// Both sides: counters, and a view of the peer (matched readers/writers, age of the last message
// received). Built from the generic DDS readers and writers (dds_endpoint.hpp); Fast DDS types
// never appear in this header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/clock.hpp"  // MonotonicNs: the clock of received_ns and the ages
#include "runtime/core/result.hpp"
#include "runtime/robot/auv_messages.hpp"
#include "runtime/transport/dds/dds_endpoint.hpp"

namespace pbppo::dds {

enum class AuvDdsRole { kController, kVehicle };

// The participant (profiles, participant profile, domain: DdsOptions), and the link's own settings.
struct AuvDdsOptions : DdsOptions {
  std::string topic_prefix = "pbppo/auv/";  // topics: <prefix>sensor_state, command, controller_status
  // kRos2: topics rt/<prefix>..., types pbppo_msgs::msg::dds_::AuvSensorState_, AuvCommand_,
  // AuvControllerStatus_ (dds_endpoint.hpp). Both sides must use the same naming.
  DdsNaming naming = DdsNaming::kNative;
  std::size_t command_queue_capacity = 16;   // controller: tick -> writer thread
  std::size_t command_inbox_capacity = 256;  // vehicle: listener -> simulator
  std::int32_t history_depth = 32;           // KEEP_LAST depth of the reliable writers/readers
  // Controller: how the writer thread learns of a command. 0: PushCommand wakes it (a futex
  // system call in the tick, lowest delivery latency); > 0: the writer polls the queue every
  // writer_poll_us and the tick makes no system call (delivery up to that much later).
  std::int64_t writer_poll_us = 0;
};

struct AuvLinkCounters {
  std::uint64_t received = 0;      // messages taken from DDS (samples or commands)
  std::uint64_t invalid = 0;       // of those, delivered with non-zero check flags
  std::uint64_t rejected = 0;      // of those, not delivered (more sonar beams than fit)
  std::uint64_t dropped_full = 0;  // queue full: commands dropped (controller: tick -> writer; vehicle: inbox)
  std::uint64_t written = 0;       // DDS writes that succeeded (commands, samples, status)
  std::uint64_t write_failed = 0;  // DDS writes that failed
};

struct AuvPeerView {
  std::int32_t matched_readers = 0;       // remote readers of what this side publishes (main topic)
  std::int32_t matched_writers = 0;       // remote writers of what this side reads (main topic)
  std::int64_t last_receive_age_ns = -1;  // since the last sample (controller) or command (vehicle); -1 never
};

// What the controller's tick gets: the sample (value), its check flags (auv_message_check.hpp)
// and when it arrived (CLOCK_MONOTONIC); and the vehicle, the command.
using AuvSensorInput = DdsReceived<robot::AuvSensorSample>;
using AuvCommandInput = DdsReceived<robot::AuvCommand>;

class AuvDdsLink {
 public:
  // Loads the XML profiles, creates the participant, topics, readers and writers (and the
  // controller's writer thread). Errors name the option and its value.
  static Result<std::unique_ptr<AuvDdsLink>> Create(AuvDdsRole role, const AuvDdsOptions& options);
  ~AuvDdsLink();  // joins the writer thread, deletes every DDS entity
  AuvDdsLink(const AuvDdsLink&) = delete;
  AuvDdsLink& operator=(const AuvDdsLink&) = delete;

  AuvDdsRole role() const noexcept;

  // ---- controller side; real-time safe: no allocation, lock or blocking wait ----
  // The newest sample: its version (1, 2 ... in arrival order), 0 while none has arrived.
  std::uint64_t ReadSample(AuvSensorInput* out) noexcept;
  // False when the queue to the writer thread is full (the command is dropped and counted) or on
  // the vehicle side.
  bool PushCommand(const robot::AuvCommand& command) noexcept;

  // ---- controller side; not for the tick ----
  // Waits until a sample newer than `after_version` has arrived; false on timeout.
  bool WaitForSample(std::uint64_t after_version, std::int64_t timeout_ns);
  Status PublishStatus(const robot::AuvControllerStatus& status);

  // ---- vehicle side (the simulator's thread) ----
  Status PublishSample(const robot::AuvSensorSample& sample);
  // The oldest command not yet taken; false when none is waiting.
  bool PopCommand(AuvCommandInput* out) noexcept;
  // As PopCommand, waiting up to `timeout_ns` for one to arrive.
  bool WaitForCommand(AuvCommandInput* out, std::int64_t timeout_ns);
  std::uint64_t ReadStatus(robot::AuvControllerStatus* out) noexcept;

  // ---- both sides ----
  // Waits until this side's main writer has a matched reader and its main reader a matched
  // writer (sensor/command topics): the peer is there and has discovered us.
  bool WaitForPeer(std::int64_t timeout_ns);
  // Waits until every remote reader has acknowledged what this side wrote (best effort, before
  // shutting down so that the last message is not lost).
  bool Flush(std::int64_t timeout_ns);
  AuvPeerView Peer() const noexcept;
  AuvLinkCounters counters() const noexcept;
  int domain_id() const noexcept;

  struct Impl;

 private:
  explicit AuvDdsLink(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::dds
