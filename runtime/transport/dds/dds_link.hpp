// A robot's DDS transport (a robot.yaml transport of kind dds: runtime/robot/transport_spec.hpp)
// as one link, from either side: a participant and a reader or a writer per declared message.
//
//   kRobot  the controller: reads `in` messages (newest sample), writes `out` messages through a
//           writer thread (the tick pushes) and `status` messages directly (the status thread).
//   kPeer   what the robot talks to (a simulator, an operator, a test): writes `in` messages,
//           reads `out` messages in arrival order (a lock-step simulator sees every one) and
//           `status` messages (newest).
//
// Topics are the transport's prefix (pbppo/<robot>/ by default) and each message's topic; types
// are named by the IDL (native) or ROS 2's way (dds_endpoint.hpp). Samples are plain CDR bytes
// (cdr.hpp); DdsSample gives peers and tests access by leaf. Set-up allocates; the tick-side
// calls the transport makes (runtime/transport/dds/dds_transport.hpp) do not.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/dds/checksum.hpp"
#include "runtime/transport/dds/dds_endpoint.hpp"

namespace pbppo::dds {

enum class DdsSide : std::uint8_t { kRobot, kPeer };

struct DdsLinkOptions : DdsOptions {
  DdsNaming naming = DdsNaming::kNative;  // both sides must use the same
  std::size_t out_queue_capacity = 16;    // kRobot: tick -> writer thread, per out message
  std::size_t peer_inbox_capacity = 256;  // kPeer: listener -> simulator, per out message
  // kRobot: how the writer threads learn of a pushed sample. 0: Push wakes them (a futex system
  // call in the tick, lowest delivery latency); > 0: they poll every writer_poll_us and the tick
  // makes no system call (delivery up to that much later).
  std::int64_t writer_poll_us = 0;
  // kRobot: > 0 replaces the robot file's lost_after_s of every message that has one.
  double lost_after_s = 0;
};

// One sample of a message, with access by leaf (peers and tests; allocates at construction).
class DdsSample {
 public:
  explicit DdsSample(const robot::IdlMessage& type);
  const robot::IdlMessage& type() const noexcept { return *type_; }
  // The leaf's value (0 when the bytes are not a plain CDR sample).
  double Get(std::uint32_t leaf) const noexcept;
  void Set(std::uint32_t leaf, double value) noexcept;
  // By path ("x_m", "sonar_m[3]"); the error names the path and the type.
  Result<double> Get(const std::string& path) const;
  Status Set(const std::string& path, double value);
  std::byte* bytes() noexcept { return bytes_.data(); }
  const std::byte* bytes() const noexcept { return bytes_.data(); }

 private:
  const robot::IdlMessage* type_;
  std::vector<std::byte> bytes_;
};

struct DdsLinkCounters {
  std::uint64_t received = 0, malformed = 0, dropped = 0;         // readers: taken, refused, queue full
  std::uint64_t written = 0, write_failed = 0, push_dropped = 0;  // writers
};

class DdsLink {
 public:
  // The transport named `transport` of `model` (kind dds), which must outlive the link. Errors
  // name the transport, the message and the option.
  static Result<std::unique_ptr<DdsLink>> Open(const robot::RobotModel& model, const std::string& transport,
                                               DdsSide side, const DdsLinkOptions& options);
  ~DdsLink();
  DdsLink(const DdsLink&) = delete;
  DdsLink& operator=(const DdsLink&) = delete;

  const robot::TransportSpec& spec() const noexcept { return *spec_; }
  DdsSide side() const noexcept { return side_; }
  std::size_t message_count() const noexcept { return spec_->dds.messages.size(); }
  const robot::DdsMessageSpec& message(std::size_t i) const noexcept { return spec_->dds.messages[i]; }
  // The message whose topic is `topic`; the error names the topics there are.
  Result<std::size_t> MessageIndex(const std::string& topic) const;
  // The reader or writer of message i on this side (null where this side has the other).
  DdsReader* reader(std::size_t i) noexcept { return readers_[i].get(); }
  DdsWriter* writer(std::size_t i) noexcept { return writers_[i].get(); }
  // The topic as written on the wire.
  const std::string& wire_topic(std::size_t i) const noexcept { return topics_[i]; }

  // Waits until the other side is there: every reader of an in (kRobot) or out (kPeer) message
  // has a matched writer and every writer of an out (kRobot) or in (kPeer) message a matched
  // reader (status messages, which nobody need read, aside). False on timeout.
  bool WaitForPeer(std::int64_t timeout_ns);
  // Waits until what every writer wrote was acknowledged (best effort, before leaving).
  bool Flush(std::int64_t timeout_ns);
  DdsLinkCounters counters() const noexcept;
  int domain_id() const noexcept;

  // kPeer: fills an in message's leaves from the fields of its streams (the robot file's mapping)
  // and its peer leaves (sequence: 1, 2 ... per call; clock_ns: CLOCK_MONOTONIC), then seals it.
  void FillFromFields(std::size_t message, std::span<const double> fields, DdsSample* sample) noexcept;
  // Writes message i's checksum (robot.yaml checksum) into the sample; nothing without one. A peer
  // that sets leaves itself seals before it writes.
  void Seal(std::size_t message, DdsSample* sample) noexcept;
  // Whether a sample of message i carries its checksum (true without one; false for a sample that
  // is not plain CDR).
  bool ChecksumMatches(std::size_t message, const DdsSample& sample) noexcept;
  // The leaf of message i that carries exactly `term` (status and out values: tick, phase,
  // field.<name> ...); -1 when none does.
  int LeafOf(std::size_t message, robot::ValueTerm::Kind kind, std::uint32_t index = 0) const noexcept;

 private:
  DdsLink() = default;
  const robot::TransportSpec* spec_ = nullptr;
  DdsSide side_ = DdsSide::kRobot;
  std::unique_ptr<DdsParticipant> participant_;  // first: its readers and writers go before it
  std::vector<std::unique_ptr<DdsReader>> readers_;
  std::vector<std::unique_ptr<DdsWriter>> writers_;
  std::vector<std::string> topics_;
  std::vector<std::uint64_t> sequence_;                      // kPeer: per in message
  std::vector<std::unique_ptr<MessageChecksum>> checksums_;  // per message, null without one
};

// A DDS transport's participant options from the robot (its dds_profile document, the
// transport's participant_profile) and the caller's (domain, security; a profile file instead).
Result<DdsOptions> ParticipantOptions(const robot::RobotModel& model, const robot::TransportSpec& transport,
                                      DdsOptions caller);

}  // namespace pbppo::dds
