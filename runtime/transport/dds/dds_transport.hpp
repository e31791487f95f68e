// The controller's side of a robot's DDS transport as a robot::Transport: the link (dds_link.hpp)
// mapped onto the robot model by the robot file's declarations alone.
//
//   Read   per in message, the newest sample: a new one (another version than the last read)
//          writes its stream's fields and marks the stream fresh; the link's health: lost when a
//          message with lost_after_s has lost its writer or been silent that long (after its
//          first sample), degraded when samples were refused (malformed) or pushes dropped since
//          the last tick.
//   Write  per out message, its values (commands, fields, tick, mode, clock, sequence) encoded
//          and pushed to the writer thread (dropped and counted when full).
//   PublishStatus / Finish  the status messages, from the status thread.
//
// Read and Write allocate nothing and never block.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/dds/checksum.hpp"
#include "runtime/transport/dds/dds_link.hpp"

namespace pbppo::dds {

class DdsTransport final : public robot::Transport {
 public:
  // The transport named `transport` of `model` (kind dds); errors name the transport and the topic.
  static Result<std::unique_ptr<DdsTransport>> Open(const robot::RobotModel& model, const std::string& transport,
                                                    const DdsLinkOptions& options);
  ~DdsTransport() override;

  void Read(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  void Write(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  Status Connect(std::int64_t timeout_ns) override;
  bool Paces(std::uint32_t stream) const noexcept override;
  bool WaitForSample(std::uint32_t stream, std::uint64_t* version, std::int64_t timeout_ns) override;
  void PublishStatus(const robot::ControllerStatus& status) override;
  void Finish(const robot::ControllerStatus& status) override;
  std::string Summary() const override;

  DdsLink& link() noexcept { return *link_; }
  std::uint64_t send_failures() const noexcept { return send_failures_.load(std::memory_order_relaxed); }
  // Samples of in messages whose checksum did not match (taken as invalid: the checksum's field 0).
  std::uint64_t checksum_mismatches() const noexcept { return checksum_mismatches_.load(std::memory_order_relaxed); }

 private:
  // The messages' mappings flattened at Open, so that a tick reads a few contiguous cache lines
  // rather than the robot file's nested declarations.
  struct DecodeStep {  // a field of an in message's stream from its leaf (robot::FieldLeaf)
    std::uint32_t field = 0;
    std::uint32_t offset = 0;  // the leaf's CDR offset
    robot::IdlScalar type = robot::IdlScalar::kDouble;
    robot::FieldLeaf::Read read = robot::FieldLeaf::Read::kValue;
    std::uint8_t bit = 0;
    // A counter's increase: the leaf's range as a mask, its previous value.
    std::uint32_t mask = 0;
    std::uint32_t last = 0;
    bool primed = false;  // a previous value was taken
    bool shaped = false;
    robot::AxisShape axis;
  };
  struct EncodeStep {  // a term of an out or status message's value; `last` closes the sum
    robot::ValueTerm term;
    std::uint32_t offset = 0;  // the value's leaf
    robot::IdlScalar type = robot::IdlScalar::kDouble;
    bool last = false;
    std::int32_t motor = -1;  // a motor's command: sent as 0 while the loop does not command the motor
  };
  struct In {
    std::size_t message = 0;
    std::vector<std::byte> sample;
    std::uint64_t version = 0;
    std::int64_t lost_after_ns = 0;
    std::uint32_t stream = 0;
    std::vector<std::uint32_t> streams;  // every stream it fills (the first: `stream`)
    std::vector<DecodeStep> steps;
    std::optional<MessageChecksum> checksum;
    std::int32_t checksum_field = -1;
    std::uint32_t checksum_stream = 0;  // the checksum field's: fresh when the checksum does not match
  };
  struct Out {
    std::size_t message = 0;
    std::vector<std::byte> sample;
    std::uint64_t sequence = 0;
    std::vector<EncodeStep> steps;
    std::optional<MessageChecksum> checksum;
  };
  DdsTransport() = default;
  // Each value of `out` (the sum of its terms; term(t) gives one) encoded into its sample.
  template <typename TermValue>
  static void Encode(Out& out, TermValue term) noexcept;
  double Term(const robot::ValueTerm& t, const robot::RobotData& d, std::uint64_t sequence) const noexcept;
  double StatusTerm(const robot::ValueTerm& t, const robot::ControllerStatus& s, std::uint64_t sequence) const noexcept;

  std::unique_ptr<DdsLink> link_;
  std::uint32_t link_index_ = 0;
  std::vector<In> in_;
  std::vector<Out> out_, status_;
  // The fields, commands and stream sample counts status messages name, as the tick last wrote
  // them (for the status thread): snapshot_terms_ says which, snapshot_ holds them.
  std::vector<robot::ValueTerm> snapshot_terms_;
  std::unique_ptr<std::atomic<double>[]> snapshot_;
  std::uint64_t malformed_ = 0, dropped_ = 0;
  std::atomic<std::uint64_t> checksum_mismatches_{0};
  std::atomic<std::uint64_t> send_failures_{0};
  std::string summary_name_;
};

}  // namespace pbppo::dds
