// A robot's transports as robot.yaml declares them (part of RobotModel, runtime/robot/
// robot_model.hpp). A transport has a kind: "can" (the buses and devices of the CAN map) or "dds"
// (messages declared once, in IDL files, each mapped onto the robot's streams, fields and
// commands here). Which code serves a kind is the transport table's business
// (runtime/transport/bindings.hpp); this is data only.
//
//   transports:
//     - name: dds
//       kind: dds
//       participant_profile: pbppo_loopback   # a profile of files.dds_profile
//       topic_prefix: pbppo/auv/              # default pbppo/<robot>/; ROS 2 naming puts rt/ before it
//       wait_for_peer: true                   # the controller waits for the other side before arming
//       when: policy                          # open it only when a policy commands (default: always)
//       messages:
//         - topic: sensor_state               # <prefix>sensor_state
//           idl: idl/AuvSensorState.idl       # the message's one declaration
//           type: pbppo_idl::auv::SensorState # the struct (default: the file's last)
//           direction: in                     # in: the robot reads it; out: writes it every tick;
//                                             # status: writes it from the status thread
//           stream: sensor                    # in: the stream whose fields its leaves fill
//           fields: {"sonar_{i}_m": "sonar_m[{i}]"}  # field: leaf; a field named like a leaf
//                                             # needs no entry; every field of the stream is filled
//           peer: {stamp_ns: clock_ns}        # in: what the other side writes in leaves no field reads
//           lost_after_s: 2.0                 # in: the link is lost when its writer is gone or silent
//           durability: transient_local       # in: or volatile (matches ROS 2's default publishers)
//         - topic: command
//           idl: idl/AuvCommand.idl
//           direction: out
//           values: {tick: tick, answers: field.tick, surge_speed_mps: command.surge_speed, mode: mode}
//
// Values a leaf of an outgoing or status message takes (several joined by " + " are added):
//   a number; tick; mode (0 nominal ... 3 e-stop); clock_ns (CLOCK_MONOTONIC); sequence (1, 2 ...
//   per message written); command.<name>; field.<name>; samples.<stream> (samples taken);
//   status messages also: phase (runtime/loop's phase index), cause (1 << the latched cause, 0:
//   none), count.<cause> (the supervisor's count of a cause: stale_sample, invalid_sample, ...),
//   deadline_misses, tick_median_us, tick_max_us.
// Leaves of an outgoing message that no value names are sent as 0.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/robot/idl.hpp"

namespace pbppo::robot {

struct ValueTerm {
  enum class Kind : std::uint8_t {
    kConstant,
    kTick,
    kMode,
    kClockNs,
    kSequence,
    kCommand,  // index: the command
    kField,    // index: the field
    kSamples,  // index: the stream
    // Status messages only:
    kPhase,
    kCause,
    kCount,  // index: the safety::Cause
    kDeadlineMisses,
    kTickMedianUs,
    kTickMaxUs,
  };
  Kind kind = Kind::kConstant;
  std::uint32_t index = 0;
  double value = 0;  // kConstant
};

// A leaf of an outgoing message and the sum that fills it.
struct LeafValue {
  std::uint32_t leaf = 0;
  std::vector<ValueTerm> terms;
};

// A field of an incoming message's stream and the leaf that fills it.
struct FieldLeaf {
  std::uint32_t field = 0;
  std::uint32_t leaf = 0;
};

// What the other side writes in a leaf that no field reads (a simulator or an operator speaking
// for the robot's peer).
struct PeerLeaf {
  enum class Kind : std::uint8_t { kClockNs, kSequence };
  std::uint32_t leaf = 0;
  Kind kind = Kind::kClockNs;
};

enum class MessageDirection : std::uint8_t { kIn, kOut, kStatus };
const char* ToString(MessageDirection direction) noexcept;

struct DdsMessageSpec {
  std::string topic;  // after the transport's prefix
  MessageDirection direction = MessageDirection::kIn;
  IdlMessage type;
  std::string type_stem;  // the IDL file's name without .idl (the ROS 2 message name)
  // kIn:
  std::uint32_t stream = 0;
  std::vector<FieldLeaf> fields;
  std::vector<PeerLeaf> peer;
  double lost_after_s = 0;  // > 0: the link's health follows this message
  // Transient-local (gets what its writer wrote just before matching; such writers only) or
  // volatile (matches any writer, as ROS 2 publishers are by default).
  bool transient_local = true;
  // kOut and kStatus:
  std::vector<LeafValue> values;
};

struct DdsTransportSpec {
  std::string participant_profile = "pbppo_loopback";
  std::string topic_prefix;  // default "pbppo/<robot>/"
  bool wait_for_peer = false;
  std::vector<DdsMessageSpec> messages;
};

struct TransportSpec {
  std::string name, kind;    // kind: "can" or "dds"
  bool policy_only = false;  // when: policy (a transport whose streams only a policy reads)
  DdsTransportSpec dds;      // kind dds
  // Its links, whose health the supervisor watches: one per CAN bus ("can/front"), else itself.
  std::uint32_t first_link = 0, link_count = 1;
};

}  // namespace pbppo::robot
