#include "runtime/transport/dds/dds_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "runtime/core/clock.hpp"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/dds_internal.hpp"

namespace pbppo::dds {

using robot::MessageDirection;

DdsSample::DdsSample(const robot::IdlMessage& type) : type_(&type), bytes_(CdrSampleBytes(type), std::byte{0}) {
  WriteCdrLayout(type, bytes_.data());
}

double DdsSample::Get(std::uint32_t leaf) const noexcept {
  bool big_endian = false;
  if (leaf >= type_->leaves.size() || !ReadCdrHeader(bytes_.data(), &big_endian)) return 0;
  return DecodeLeaf(type_->leaves[leaf], bytes_.data(), big_endian);
}

void DdsSample::Set(std::uint32_t leaf, double value) noexcept {
  bool big_endian = false;
  if (leaf >= type_->leaves.size()) return;
  if (!ReadCdrHeader(bytes_.data(), &big_endian) || big_endian) {
    // A sample read in another byte order is rewritten little-endian, leaf by leaf, first.
    std::vector<double> values;
    for (std::uint32_t k = 0; k < type_->leaves.size(); ++k) values.push_back(Get(k));
    WriteCdrLayout(*type_, bytes_.data());
    for (std::uint32_t k = 0; k < type_->leaves.size(); ++k) EncodeLeaf(type_->leaves[k], values[k], bytes_.data());
  }
  EncodeLeaf(type_->leaves[leaf], value, bytes_.data());
}

Result<double> DdsSample::Get(const std::string& path) const {
  const int leaf = type_->LeafIndex(path);
  if (leaf < 0) return DdsError("'" + path + "' is not a member of " + type_->type_name);
  return Get(static_cast<std::uint32_t>(leaf));
}

Status DdsSample::Set(const std::string& path, double value) {
  const int leaf = type_->LeafIndex(path);
  if (leaf < 0) return DdsError("'" + path + "' is not a member of " + type_->type_name);
  Set(static_cast<std::uint32_t>(leaf), value);
  return {};
}

Result<DdsOptions> ParticipantOptions(const robot::RobotModel& model, const robot::TransportSpec& transport,
                                      DdsOptions caller) {
  caller.participant_profile = transport.dds.participant_profile;
  if (caller.profile_file.empty() && caller.profile_xml.empty()) {
    if (!model.dds_profile)
      return DdsError(model.path + ": transport '" + transport.name + "' of kind dds, but files names no dds_profile");
    caller.profile_xml = model.dds_profile->text;  // read with the robot
  }
  return caller;
}

Result<std::unique_ptr<DdsLink>> DdsLink::Open(const robot::RobotModel& model, const std::string& transport,
                                               DdsSide side, const DdsLinkOptions& o) {
  const int t = model.TransportIndex(transport);
  if (t < 0 || model.transports[static_cast<std::size_t>(t)].kind != "dds")
    return DdsError(model.path + ": no transport '" + transport + "' of kind dds");
  if (o.out_queue_capacity < 1 || o.out_queue_capacity > 65536)
    return DdsError("out_queue_capacity " + std::to_string(o.out_queue_capacity) + " is outside 1..65536");
  if (o.peer_inbox_capacity < 1 || o.peer_inbox_capacity > 65536)
    return DdsError("peer_inbox_capacity " + std::to_string(o.peer_inbox_capacity) + " is outside 1..65536");
  std::unique_ptr<DdsLink> link(new DdsLink());
  link->spec_ = &model.transports[static_cast<std::size_t>(t)];
  link->side_ = side;
  auto options = ParticipantOptions(model, *link->spec_, o);
  if (!options) return std::move(options).error();
  auto participant = DdsParticipant::Create(*options);
  if (!participant) return std::move(participant).error();
  link->participant_ = std::move(*participant);
  DdsParticipant& p = *link->participant_;
  const bool robot_side = side == DdsSide::kRobot;
  for (const robot::DdsMessageSpec& m : link->spec_->dds.messages) {
    const std::string topic = WireTopic(o.naming, link->spec_->dds.topic_prefix + m.topic);
    const std::string type_name = WireTypeName(o.naming, m.type.type_name, m.type_stem);
    const bool status = m.direction == MessageDirection::kStatus;
    // This side reads what the other side writes.
    const bool reads = (m.direction == MessageDirection::kIn) == robot_side;
    std::unique_ptr<DdsReader> reader;
    std::unique_ptr<DdsWriter> writer;
    if (reads) {
      DdsReaderOptions r;
      r.type_name = type_name;
      r.history_depth = status ? 4 : 32;
      r.transient_local = m.direction != MessageDirection::kIn || m.transient_local;
      if (!robot_side && m.direction == MessageDirection::kOut) {
        r.mode = DdsReaderMode::kQueue;
        r.queue_capacity = o.peer_inbox_capacity;
      }
      auto made = DdsReader::Create(p, topic, m.type, r);
      if (!made) return DdsError(transport + ": topic '" + topic + "': " + made.error().message);
      reader = std::move(*made);
    } else {
      DdsWriterOptions w;
      w.type_name = type_name;
      w.history_depth = status ? 4 : 32;
      if (robot_side && m.direction == MessageDirection::kOut) {
        w.queue_capacity = o.out_queue_capacity;
        w.poll_us = o.writer_poll_us;
      }
      auto made = DdsWriter::Create(p, topic, m.type, w);
      if (!made) return DdsError(transport + ": topic '" + topic + "': " + made.error().message);
      writer = std::move(*made);
    }
    link->readers_.push_back(std::move(reader));
    link->writers_.push_back(std::move(writer));
    link->topics_.push_back(topic);
    link->sequence_.push_back(0);
    link->checksums_.push_back(m.checksum.present ? std::make_unique<MessageChecksum>(m.type, m.checksum.leaf)
                                                  : nullptr);
  }
  return link;
}

DdsLink::~DdsLink() {
  // Readers and writers go before their participant.
  readers_.clear();
  writers_.clear();
}

Result<std::size_t> DdsLink::MessageIndex(const std::string& topic) const {
  std::string known;
  for (std::size_t i = 0; i < message_count(); ++i) {
    if (message(i).topic == topic) return i;
    known += (known.empty() ? "" : ", ") + message(i).topic;
  }
  return DdsError(spec_->name + ": no message on topic '" + topic + "' (topics: " + known + ")");
}

bool DdsLink::WaitForPeer(std::int64_t timeout_ns) {
  const std::int64_t deadline = MonotonicNs() + timeout_ns;
  for (;;) {
    bool all = true;
    for (std::size_t i = 0; i < message_count(); ++i) {
      if (message(i).direction == MessageDirection::kStatus) continue;
      if (readers_[i] && readers_[i]->matched_writers() == 0) all = false;
      if (writers_[i] && writers_[i]->matched_readers() == 0) all = false;
    }
    if (all) return true;
    if (MonotonicNs() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

bool DdsLink::Flush(std::int64_t timeout_ns) {
  bool ok = true;
  for (auto& w : writers_)
    if (w && !w->Flush(timeout_ns)) ok = false;
  return ok;
}

DdsLinkCounters DdsLink::counters() const noexcept {
  DdsLinkCounters c;
  for (const auto& reader : readers_) {
    if (!reader) continue;
    const DdsReaderCounters r = reader->counters();
    c.received += r.received;
    c.malformed += r.malformed;
    c.dropped += r.dropped;
  }
  for (const auto& writer : writers_) {
    if (!writer) continue;
    const DdsWriterCounters w = writer->counters();
    c.written += w.written;
    c.write_failed += w.failed;
    c.push_dropped += w.dropped;
  }
  return c;
}

int DdsLink::domain_id() const noexcept {
  return participant_->domain_id();
}

void DdsLink::FillFromFields(std::size_t message, std::span<const double> fields, DdsSample* sample) noexcept {
  const robot::DdsMessageSpec& m = spec_->dds.messages[message];
  for (const robot::FieldLeaf& fl : m.fields) {
    const double value = fl.shaped ? robot::UnshapeAxis(fl.axis, fields[fl.field]) : fields[fl.field];
    if (fl.read == robot::FieldLeaf::Read::kValue) {
      sample->Set(fl.leaf, value);
      continue;
    }
    if (fl.read == robot::FieldLeaf::Read::kBit) {  // the leaf's other bits kept
      const auto word = static_cast<std::uint32_t>(sample->Get(fl.leaf));
      const std::uint32_t bit = 1u << fl.bit;
      sample->Set(fl.leaf, static_cast<double>(value >= 0.5 ? word | bit : word & ~bit));
      continue;
    }
    if (fl.read == robot::FieldLeaf::Read::kFloat32) {  // four octets, little-endian
      const auto f = static_cast<float>(value);
      std::uint32_t bits = 0;
      std::memcpy(&bits, &f, sizeof bits);
      for (std::uint32_t k = 0; k < 4; ++k) sample->Set(fl.leaf + k, static_cast<double>((bits >> (8 * k)) & 0xffu));
      continue;
    }
    // A counter's increase: added to the count the sample holds (modulo the leaf's range).
    const std::uint32_t mask = robot::IdlCounterMask(m.type.leaves[fl.leaf].type);
    const double add = fields[fl.field];
    const std::uint32_t step =
        std::isfinite(add) && add > 0 ? static_cast<std::uint32_t>(std::min(add, static_cast<double>(mask))) : 0;
    sample->Set(fl.leaf, static_cast<double>((static_cast<std::uint32_t>(sample->Get(fl.leaf)) + step) & mask));
  }
  if (!m.peer.empty()) {
    const std::uint64_t seq = ++sequence_[message];
    for (const robot::PeerLeaf& p : m.peer)
      sample->Set(p.leaf, p.kind == robot::PeerLeaf::Kind::kSequence ? static_cast<double>(seq)
                                                                     : static_cast<double>(MonotonicNs()));
  }
  Seal(message, sample);
}

void DdsLink::Seal(std::size_t message, DdsSample* sample) noexcept {
  MessageChecksum* c = checksums_[message].get();
  if (c == nullptr) return;
  sample->Set(spec_->dds.messages[message].checksum.leaf, static_cast<double>(c->Compute(sample->bytes(), false)));
}

bool DdsLink::ChecksumMatches(std::size_t message, const DdsSample& sample) noexcept {
  MessageChecksum* c = checksums_[message].get();
  if (c == nullptr) return true;
  bool big_endian = false;
  if (!ReadCdrHeader(sample.bytes(), &big_endian)) return false;
  return c->Compute(sample.bytes(), big_endian) ==
         static_cast<std::uint32_t>(sample.Get(spec_->dds.messages[message].checksum.leaf));
}

int DdsLink::LeafOf(std::size_t message, robot::ValueTerm::Kind kind, std::uint32_t index) const noexcept {
  for (const robot::LeafValue& v : spec_->dds.messages[message].values)
    if (v.terms.size() == 1 && v.terms[0].kind == kind && v.terms[0].index == index) return static_cast<int>(v.leaf);
  return -1;
}

}  // namespace pbppo::dds
