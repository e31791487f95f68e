// The DDS transport (Fast DDS 2.9), for any robot's messages: a participant, and readers and
// writers of plain fixed-size C++ message structs. Fast DDS types never appear in this header;
// a robot's binding (firmware/<robot>/) says which generated type carries each struct by
// specialising DdsType<T> (see dds_endpoint_impl.hpp) and instantiates the templates.
//
//   DdsReader<T>  a Fast DDS listener thread converts each message, checks it (a robot-given
//                 check returning flag bits; flags in the reject mask drop it) and stores it
//                 with its flags and arrival time in a latest-value mailbox (kLatest: the
//                 real-time tick reads the newest, no allocation, lock or block) or a bounded
//                 queue (kQueue: every message in arrival order, for a lock-step simulator).
//   DdsWriter<T>  Write() writes from the caller's (non-real-time) thread; with a queue, Push()
//                 hands the message to a writer thread of its own (the tick never calls DDS:
//                 a reliable write allocates), dropped and counted when the queue is full.
//
// Reliable, transient-local QoS (a message written right after matching is not lost), no
// data-sharing; the participant's transport comes from the XML profile.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/result.hpp"

namespace pbppo::dds {

// How topics and types are named on the wire. kNative: the IDL's type names
// (pbppo_idl::quadruped::VelocityCommand) on the robot's topics (pbppo/quadruped/velocity_command).
// kRos2: ROS 2's conventions, so that ROS 2 tools and other DDS implementations that follow them
// see the same topics: "rt/" before the topic name, types named pbppo_msgs::msg::dds_::<Type>_
// (the ROS 2 message pbppo_msgs/msg/<Type> with the IDL's fields).
enum class DdsNaming : std::uint8_t { kNative, kRos2 };
// "native" or "ros2"; the error names the value.
Result<DdsNaming> ParseDdsNaming(const std::string& text);
const char* ToString(DdsNaming naming) noexcept;
// The topic as written on the wire: `topic` (kNative) or "rt/" + `topic` (kRos2).
std::string WireTopic(DdsNaming naming, const std::string& topic);
// The type name: "" (kNative: the IDL's own) or "pbppo_msgs::msg::dds_::" + ros2_message + "_".
std::string WireTypeName(DdsNaming naming, const std::string& ros2_message);

// DDS Security (Fast DDS's builtin plugins: PKI-DH authentication, Access-Permissions, AES-GCM-GMAC)
// from a folder made by tools/security/make_dds_security.sh (docs/security.md): ca.pem,
// governance.p7s, <identity>.pem, <identity>_key.pem, <identity>_permissions.p7s. Empty `dir`: no
// security (the participant talks to anyone on the domain).
struct DdsSecurity {
  std::string dir;
  std::string identity;  // the participant's certificate and permissions
  bool enabled() const noexcept { return !dir.empty(); }
};

// Checks a security folder before Fast DDS sees it, so that a bad file is refused at start with a
// message naming it: every file present; the certificate signed by the CA, within its validity,
// matching its key; governance and permissions signed (S/MIME) by the CA, unaltered.
Status CheckDdsSecurity(const DdsSecurity& security);

struct DdsOptions {
  std::string profile_xml;                             // Fast DDS XML profiles, as text (a robot's document)
  std::string profile_file;                            // ... or a file to read them from (profile_xml empty)
  std::string participant_profile = "pbppo_loopback";  // a <participant profile_name=...> in them
  int domain_id = 0;                                   // 0 ... 232
  DdsSecurity security;                                // none by default
};

// One DDS participant with a publisher and a subscriber.
class DdsParticipant {
 public:
  // Errors name the option and its value (a profile that does not load, an unknown profile name).
  static Result<std::unique_ptr<DdsParticipant>> Create(const DdsOptions& options);
  ~DdsParticipant();
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;

  int domain_id() const noexcept;
  struct Impl;
  Impl& impl() noexcept { return *impl_; }

 private:
  explicit DdsParticipant(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A message as the reader received it: its check flags and its arrival (CLOCK_MONOTONIC).
template <typename T>
struct DdsReceived {
  T value{};
  std::uint32_t flags = 0;
  std::int64_t received_ns = 0;
};

enum class DdsReaderMode : std::uint8_t { kLatest, kQueue };

struct DdsReaderOptions {
  DdsReaderMode mode = DdsReaderMode::kLatest;
  std::size_t queue_capacity = 256;  // kQueue
  std::int32_t history_depth = 32;   // KEEP_LAST depth
  std::uint32_t reject_mask = 0;     // check flags that drop a message instead of delivering it
  std::string type_name;             // the type's name on the wire ("": the IDL's; see WireTypeName)
  // Transient-local (a late reader gets the writer's last messages; matches transient-local
  // writers only) or volatile (matches any writer: ROS 2 publishers are volatile by default).
  bool transient_local = true;
};

struct DdsReaderCounters {
  std::uint64_t received = 0;  // messages taken from DDS
  std::uint64_t invalid = 0;   // of those, delivered with non-zero check flags
  std::uint64_t rejected = 0;  // of those, not delivered (flags in the reject mask)
  std::uint64_t dropped = 0;   // kQueue: not delivered, the queue was full
};

template <typename T>
class DdsReader {
 public:
  using Check = std::uint32_t (*)(const T&);
  static Result<std::unique_ptr<DdsReader>> Create(DdsParticipant& participant, const std::string& topic,
                                                   const DdsReaderOptions& options, Check check = nullptr);
  ~DdsReader();
  DdsReader(const DdsReader&) = delete;
  DdsReader& operator=(const DdsReader&) = delete;

  // kLatest, real-time safe: the newest message and its version (1, 2 ... in arrival order); 0
  // while none has arrived.
  std::uint64_t Read(DdsReceived<T>* out) noexcept;
  // The same for the message alone: *out is left as it was while none has arrived.
  std::uint64_t ReadValue(T* out) noexcept;
  std::uint64_t version() const noexcept;
  // kLatest, not for the tick: waits until a message newer than `after_version` arrived.
  bool WaitNewer(std::uint64_t after_version, std::int64_t timeout_ns);
  // kQueue: the oldest message not yet taken (false: none); WaitPop waits for one.
  bool Pop(DdsReceived<T>* out) noexcept;
  bool WaitPop(DdsReceived<T>* out, std::int64_t timeout_ns);

  std::int32_t matched_writers() const noexcept;
  std::int64_t last_receive_ns() const noexcept;  // -1: nothing received yet
  DdsReaderCounters counters() const noexcept;

  struct Impl;

 private:
  explicit DdsReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
  std::unique_ptr<Impl> impl_;
};

struct DdsWriterOptions {
  std::int32_t history_depth = 32;
  std::size_t queue_capacity = 0;  // > 0: Push() through a writer thread
  // The writer thread learns of a pushed message: 0, Push wakes it (a futex system call in the
  // caller, lowest latency); > 0, it polls the queue every poll_us and Push makes no system call.
  std::int64_t poll_us = 0;
  std::string type_name;  // the type's name on the wire ("": the IDL's; see WireTypeName)
};

struct DdsWriterCounters {
  std::uint64_t written = 0;  // DDS writes that succeeded
  std::uint64_t failed = 0;   // DDS writes that failed
  std::uint64_t dropped = 0;  // pushes dropped on a full queue
};

template <typename T>
class DdsWriter {
 public:
  static Result<std::unique_ptr<DdsWriter>> Create(DdsParticipant& participant, const std::string& topic,
                                                   const DdsWriterOptions& options);
  ~DdsWriter();  // writes what was pushed, then joins the writer thread
  DdsWriter(const DdsWriter&) = delete;
  DdsWriter& operator=(const DdsWriter&) = delete;

  // From any non-real-time thread (serialised inside).
  Status Write(const T& message);
  // Real-time safe (needs queue_capacity > 0): false when the queue is full (dropped, counted).
  bool Push(const T& message) noexcept;
  // Waits until every matched reader acknowledged what was written (best effort, at shutdown).
  bool Flush(std::int64_t timeout_ns);

  std::int32_t matched_readers() const noexcept;
  DdsWriterCounters counters() const noexcept;

  struct Impl;

 private:
  explicit DdsWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::dds
