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
//           stream: sensor                    # in: the stream whose fields its leaves fill, or a
//                                             # list of them ("motors": every motor's stream)
//           fields: {"sonar_{i}_m": "sonar_m[{i}]"}  # field: leaf; a field named like a leaf
//                                             # needs no entry; every field of the streams is filled;
//                                             # "{joint}" and "{motor}" repeat an entry per motor
//                                             # (its joint's name, its index in the robot's order);
//                                             # the leaf may be read through a function (below)
//           axes: {command_vx: {scale: 1.0, dead_zone: 0.1}}  # in: a field shaped as a stick
//                                             # (AxisShape below: range [-1, 1] unless given)
//           peer: {stamp_ns: clock_ns}        # in: what the other side writes in leaves no field reads
//           lost_after_s: 2.0                 # in: the link is lost when its writer is gone or silent
//           durability: transient_local       # in: or volatile (matches ROS 2's default publishers)
//           checksum: {leaf: crc, field: crc_ok}  # in: the sample's checksum (below); field: 1 when
//                                             # it matches, 0 when not (then no other field is taken)
//         - topic: command
//           idl: idl/AuvCommand.idl
//           direction: out
//           values: {tick: tick, answers: field.tick, surge_speed_mps: command.surge_speed, mode: mode}
//           checksum: {leaf: crc}             # out: computed into the leaf before each write
//
// Values a leaf of an outgoing or status message takes (several joined by " + " are added):
//   a number; tick; mode (0 nominal ... 3 e-stop); clock_ns (CLOCK_MONOTONIC); sequence (1, 2 ...
//   per message written); command.<name>; field.<name>; samples.<stream> (samples taken);
//   status messages also: phase (runtime/loop's phase index), cause (1 << the latched cause, 0:
//   none), count.<cause> (the supervisor's count of a cause: stale_sample, invalid_sample, ...),
//   deadline_misses, tick_median_us, tick_max_us; out messages also motor.<joint> (1 while the loop
//   switches the motor on or commands it, 0 while it is off). A motor's commands (command.q_des_<joint>
//   ...) are sent as 0 while the loop does not command the motor (before arming, at arming, after
//   shutdown): a message that carries motors holds them passive then.
// Leaves of an outgoing message that no value names are sent as 0.
//
// Checksums (`checksum.algorithm`, default crc32_mpeg2_words): CRC-32/MPEG-2 (polynomial
// 0x04C11DB7, initial 0xFFFFFFFF, no reflection, no final XOR) over the message laid out as a
// little-endian C struct with natural alignment (IdlLeaf::c_offset; padding zero), taken as 32-bit
// words, each fed most significant bit first, every word but the last; the last word is the
// checksum leaf itself (a uint32 at the end of the struct), as some robots' low-level messages
// carry it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/robot/axis_shape.hpp"
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
    // Out messages only:
    kMotorOn,  // index: the motor
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

// A field of an incoming message's stream and the leaf that fills it, as the robot file maps it:
//   LEAF                  its value
//   increase(LEAF)        an unsigned leaf of at most 32 bits (a device's counter): how much it grew
//                         since the previous sample, modulo its range (a wrap is a step; 0 at the first)
//   bit(LEAF, N)          bit N (0: the least significant) of an unsigned leaf: 0 or 1 (a remote's key)
//   float32(LEAF)         the little-endian float32 in four octets from LEAF (an octet of an array,
//                         as a remote's stick inside a byte record), whatever the sample's byte order
// and, when the message's axes section names the field, shaped by `axis` (AxisShape).
struct FieldLeaf {
  enum class Read : std::uint8_t { kValue, kIncrease, kBit, kFloat32 };
  std::uint32_t field = 0;
  std::uint32_t leaf = 0;
  Read read = Read::kValue;
  std::uint8_t bit = 0;  // kBit
  bool shaped = false;
  AxisShape axis;
  bool increase() const noexcept { return read == Read::kIncrease; }
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

// A message's checksum (crc32_mpeg2_words, the only algorithm so far).
struct ChecksumSpec {
  bool present = false;
  std::uint32_t leaf = 0;   // the uint32 leaf that carries it, the C struct's last word
  std::int32_t field = -1;  // in: the field that takes 1 (match) or 0 (mismatch)
};

struct DdsMessageSpec {
  std::string topic;  // after the transport's prefix
  MessageDirection direction = MessageDirection::kIn;
  IdlMessage type;
  std::string type_stem;  // the IDL file's name without .idl (the ROS 2 message name)
  ChecksumSpec checksum;
  // kIn: the streams its leaves fill (the first as `stream`).
  std::uint32_t stream = 0;
  std::vector<std::uint32_t> streams;
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

// A gamepad or joystick read through Linux evdev (kind evdev): its absolute axes and buttons
// fill the fields of one stream every tick the device is there.
//
//   transports:
//     - name: gamepad
//       kind: evdev
//       device: /dev/input/by-id/usb-045e_Controller-event-joystick  # or a recorded event file
//       reopen_s: 0.5                     # a missing or lost device is looked for this often
//       stream: velocity_command          # every field of it is an axis or a button below
//       axes:                             # field: {code, range (the device's raw [min, max]), scale,
//                                         # dead_zone (of the normalised value), rate_per_s}
//         command_vx: {code: ABS_Y, range: [-32768, 32767], scale: -1.0, dead_zone: 0.1, rate_per_s: 2.0}
//       buttons: {deadman: BTN_TL, arm: BTN_START}  # field: code, 1 while pressed
//
// An axis's raw value v in [min, max] is normalised to n = (2 v - min - max) / (max - min) in
// [-1, 1]; inside the dead zone it is 0, outside it is rescaled so that it leaves the dead zone
// from 0 (sign(n) (|n| - dz) / (1 - dz)); then times scale, then at most rate_per_s x the tick
// period away from the field's value before. A raw value outside [min, max] is given unlimited
// (n beyond 1): the sample check finds it outside the field's range, names it and stops the robot.
struct EvdevAxisSpec {
  std::uint32_t field = 0;
  int code = 0;
  AxisShape shape;
  double rate_per_s = 0;  // 0: unlimited
};
struct EvdevButtonSpec {
  std::uint32_t field = 0;
  int code = 0;
};
struct EvdevTransportSpec {
  std::string device;  // a character device (read live) or a regular file (recorded events, played on the tick clock)
  std::uint32_t stream = 0;
  double reopen_s = 0.5;
  std::vector<EvdevAxisSpec> axes;
  std::vector<EvdevButtonSpec> buttons;
};

struct TransportSpec {
  std::string name, kind;    // kind: "can", "dds" or "evdev"
  bool policy_only = false;  // when: policy (a transport whose streams only a policy reads)
  DdsTransportSpec dds;      // kind dds
  EvdevTransportSpec evdev;  // kind evdev
  // Its links, whose health the supervisor watches: one per CAN bus ("can/front"), else itself.
  std::uint32_t first_link = 0, link_count = 1;
};

}  // namespace pbppo::robot
