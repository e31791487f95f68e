// The DDS transport's endpoints (Fast DDS 2.9), for any robot's messages: a participant, and
// readers and writers of samples whose type a robot's IDL declares (runtime/robot/idl.hpp). A
// sample is its plain CDR bytes (runtime/transport/dds/cdr.hpp); Fast DDS types never appear in
// this header, and no code is generated per message.
//
//   DdsReader  a Fast DDS listener thread copies each sample (refused, counted as malformed: one
//              of another size or encoding) with its arrival time into a latest-value mailbox
//              (kLatest: the real-time tick reads the newest, no allocation, lock or block) or a
//              bounded queue (kQueue: every sample in arrival order, for a lock-step simulator).
//   DdsWriter  Write() writes from the caller's (non-real-time) thread; with a queue, Push()
//              hands the sample to a writer thread of its own (the tick never calls DDS: a
//              reliable write allocates), dropped and counted when the queue is full.
//
// Reliable QoS, transient-local writers (a sample written right after matching is not lost),
// transient-local or volatile readers, no data-sharing; the participant's transport comes from
// the XML profile.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/result.hpp"
#include "runtime/robot/idl.hpp"

namespace pbppo::dds {

// How topics and types are named on the wire. kNative: the IDL's type names
// (pbppo_idl::quadruped::VelocityCommand) on the robot's topics (pbppo/quadruped/velocity_command).
// kRos2: ROS 2's conventions, so that ROS 2 tools and other DDS implementations that follow them
// see the same topics: "rt/" before the topic name, types named pbppo_msgs::msg::dds_::<Type>_
// (the ROS 2 message pbppo_msgs/msg/<Type> with the IDL's fields; <Type>: the IDL file's name).
enum class DdsNaming : std::uint8_t { kNative, kRos2 };
// "native" or "ros2"; the error names the value.
Result<DdsNaming> ParseDdsNaming(const std::string& text);
const char* ToString(DdsNaming naming) noexcept;
// The topic as written on the wire: `topic` (kNative) or "rt/" + `topic` (kRos2).
std::string WireTopic(DdsNaming naming, const std::string& topic);
// The type name: `idl_name` (kNative) or "pbppo_msgs::msg::dds_::" + ros2_message + "_".
std::string WireTypeName(DdsNaming naming, const std::string& idl_name, const std::string& ros2_message);

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

enum class DdsReaderMode : std::uint8_t { kLatest, kQueue };

struct DdsReaderOptions {
  DdsReaderMode mode = DdsReaderMode::kLatest;
  std::size_t queue_capacity = 256;  // kQueue
  std::int32_t history_depth = 32;   // KEEP_LAST depth
  std::string type_name;             // the type's name on the wire ("": the IDL's; see WireTypeName)
  // Transient-local (a late reader gets the writer's last samples; matches transient-local
  // writers only) or volatile (matches any writer: ROS 2 publishers are volatile by default).
  bool transient_local = true;
};

struct DdsReaderCounters {
  std::uint64_t received = 0;   // samples taken from DDS
  std::uint64_t malformed = 0;  // of those, not delivered: another size or encoding than the IDL's
  std::uint64_t dropped = 0;    // kQueue: not delivered, the queue was full
};

class DdsReader {
 public:
  // `type` must outlive the reader (the robot model's).
  static Result<std::unique_ptr<DdsReader>> Create(DdsParticipant& participant, const std::string& topic,
                                                   const robot::IdlMessage& type, const DdsReaderOptions& options);
  ~DdsReader();
  DdsReader(const DdsReader&) = delete;
  DdsReader& operator=(const DdsReader&) = delete;

  // The bytes of one sample (CdrSampleBytes of its type): what Read and Pop copy out.
  std::size_t sample_bytes() const noexcept;

  // kLatest, real-time safe: the newest sample into `out` and its arrival (CLOCK_MONOTONIC); its
  // version (1, 2 ... in arrival order), 0 (nothing copied) while none has arrived.
  std::uint64_t Read(std::byte* out, std::int64_t* received_ns) noexcept;
  std::uint64_t version() const noexcept;
  // kLatest, not for the tick: waits until a sample newer than `after_version` arrived.
  bool WaitNewer(std::uint64_t after_version, std::int64_t timeout_ns);
  // kQueue: the oldest sample not yet taken (false: none); WaitPop waits for one.
  bool Pop(std::byte* out, std::int64_t* received_ns) noexcept;
  bool WaitPop(std::byte* out, std::int64_t* received_ns, std::int64_t timeout_ns);

  std::int32_t matched_writers() const noexcept;
  std::int64_t last_receive_ns() const noexcept;  // -1: nothing received yet
  DdsReaderCounters counters() const noexcept;

  struct Impl;

 private:
  explicit DdsReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

struct DdsWriterOptions {
  std::int32_t history_depth = 32;
  std::size_t queue_capacity = 0;  // > 0: Push() through a writer thread
  // The writer thread learns of a pushed sample: 0, Push wakes it (a futex system call in the
  // caller, lowest latency); > 0, it polls the queue every poll_us and Push makes no system call.
  std::int64_t poll_us = 0;
  std::string type_name;  // the type's name on the wire ("": the IDL's; see WireTypeName)
};

struct DdsWriterCounters {
  std::uint64_t written = 0;  // DDS writes that succeeded
  std::uint64_t failed = 0;   // DDS writes that failed
  std::uint64_t dropped = 0;  // pushes dropped on a full queue
};

class DdsWriter {
 public:
  // `type` must outlive the writer (the robot model's).
  static Result<std::unique_ptr<DdsWriter>> Create(DdsParticipant& participant, const std::string& topic,
                                                   const robot::IdlMessage& type, const DdsWriterOptions& options);
  ~DdsWriter();  // writes what was pushed, then joins the writer thread
  DdsWriter(const DdsWriter&) = delete;
  DdsWriter& operator=(const DdsWriter&) = delete;

  std::size_t sample_bytes() const noexcept;
  // From any non-real-time thread (serialised inside): one sample (sample_bytes(), header first).
  Status Write(const std::byte* sample);
  // Real-time safe (needs queue_capacity > 0): false when the queue is full (dropped, counted).
  bool Push(const std::byte* sample) noexcept;
  // Waits until every matched reader acknowledged what was written (best effort, at shutdown).
  bool Flush(std::int64_t timeout_ns);

  std::int32_t matched_readers() const noexcept;
  DdsWriterCounters counters() const noexcept;

  struct Impl;

 private:
  explicit DdsWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::dds
