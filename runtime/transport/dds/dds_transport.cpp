#include "runtime/transport/dds/dds_transport.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>

#include "runtime/core/clock.hpp"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/dds_internal.hpp"

namespace pbppo::dds {

using robot::MessageDirection;
using Kind = robot::ValueTerm::Kind;

namespace {

bool Snapshotted(Kind k) noexcept {
  return k == Kind::kField || k == Kind::kCommand || k == Kind::kSamples;
}

// The terms any message may carry: constants, the tick, the mode, the clock and the message's
// sequence number; nullopt for the others.
std::optional<double> CommonTerm(const robot::ValueTerm& t, std::uint64_t tick, safety::Mode mode,
                                 std::uint64_t sequence) noexcept {
  switch (t.kind) {
    case Kind::kConstant: return t.value;
    case Kind::kTick: return static_cast<double>(tick);
    case Kind::kMode: return static_cast<double>(static_cast<std::uint8_t>(mode));
    case Kind::kClockNs: return static_cast<double>(MonotonicNs());
    case Kind::kSequence: return static_cast<double>(sequence);
    default: return std::nullopt;
  }
}

}  // namespace

Result<std::unique_ptr<DdsTransport>> DdsTransport::Open(const robot::RobotModel& model, const std::string& transport,
                                                         const DdsLinkOptions& options) {
  auto link = DdsLink::Open(model, transport, DdsSide::kRobot, options);
  if (!link) return std::move(link).error();
  std::unique_ptr<DdsTransport> t(new DdsTransport());
  t->link_ = std::move(*link);
  t->link_index_ = t->link_->spec().first_link;
  t->summary_name_ = transport;
  for (std::size_t i = 0; i < t->link_->message_count(); ++i) {
    const robot::DdsMessageSpec& m = t->link_->message(i);
    std::vector<std::byte> sample(CdrSampleBytes(m.type), std::byte{0});
    WriteCdrLayout(m.type, sample.data());
    if (m.direction == MessageDirection::kIn) {
      const double lost_s = m.lost_after_s > 0 && options.lost_after_s > 0 ? options.lost_after_s : m.lost_after_s;
      In in{i, std::move(sample), 0, static_cast<std::int64_t>(lost_s * 1e9), m.stream, m.streams, {}, {}, -1, 0};
      for (const robot::FieldLeaf& fl : m.fields) {
        const robot::IdlScalar type = m.type.leaves[fl.leaf].type;
        DecodeStep step;
        step.field = fl.field;
        step.offset = m.type.leaves[fl.leaf].cdr_offset;
        step.type = type;
        step.read = fl.read;
        step.bit = fl.bit;
        step.mask = fl.increase() ? robot::IdlCounterMask(type) : 0u;
        step.shaped = fl.shaped;
        step.axis = fl.axis;
        in.steps.push_back(step);
      }
      if (m.checksum.present) {
        in.checksum.emplace(m.type, m.checksum.leaf);
        in.checksum_field = m.checksum.field;
        in.checksum_stream = model.fields[static_cast<std::size_t>(m.checksum.field)].stream;
      }
      t->in_.push_back(std::move(in));
      continue;
    }
    Out out{i, std::move(sample), 0, {}, {}};
    if (m.checksum.present) out.checksum.emplace(m.type, m.checksum.leaf);
    for (const robot::LeafValue& v : m.values) {
      const robot::IdlLeaf& leaf = m.type.leaves[v.leaf];
      for (const robot::ValueTerm& term : v.terms)
        out.steps.push_back({term, leaf.cdr_offset, leaf.type, false,
                             term.kind == Kind::kCommand ? model.commands[term.index].motor : -1});
      if (v.terms.empty()) out.steps.push_back({robot::ValueTerm{}, leaf.cdr_offset, leaf.type, false});  // 0
      out.steps.back().last = true;
    }
    (m.direction == MessageDirection::kOut ? t->out_ : t->status_).push_back(std::move(out));
    if (m.direction != MessageDirection::kStatus) continue;
    for (const robot::LeafValue& v : m.values)
      for (const robot::ValueTerm& term : v.terms)
        if (Snapshotted(term.kind) &&
            std::none_of(t->snapshot_terms_.begin(), t->snapshot_terms_.end(),
                         [&](const robot::ValueTerm& s) { return s.kind == term.kind && s.index == term.index; }))
          t->snapshot_terms_.push_back(term);
  }
  t->snapshot_ = std::make_unique<std::atomic<double>[]>(t->snapshot_terms_.size());
  for (std::size_t k = 0; k < t->snapshot_terms_.size(); ++k) t->snapshot_[k].store(0.0);
  return t;
}

DdsTransport::~DdsTransport() = default;

template <typename TermValue>
void DdsTransport::Encode(Out& out, TermValue term) noexcept {
  double sum = 0;
  for (const EncodeStep& s : out.steps) {
    sum += term(s);
    if (!s.last) continue;
    EncodeScalar(s.type, s.offset, sum, out.sample.data());
    sum = 0;
  }
  if (out.checksum)
    EncodeScalar(robot::IdlScalar::kUint32, out.checksum->cdr_offset(), out.checksum->Compute(out.sample.data(), false),
                 out.sample.data());
}

void DdsTransport::Read(const robot::RobotModel&, robot::RobotData& d) noexcept {
  bool lost = false;
  const std::int64_t now = MonotonicNs();
  for (In& in : in_) {
    DdsReader& r = *link_->reader(in.message);
    const std::uint64_t v = r.Read(in.sample.data(), nullptr);
    bool big_endian = false;
    if (v != 0 && v != in.version && ReadCdrHeader(in.sample.data(), &big_endian)) {
      in.version = v;
      bool take = true;
      if (in.checksum) {
        // A sample whose checksum does not match is not trusted: its checksum field says 0 (the
        // sample check then names it) and no other field takes its values.
        const std::uint32_t sent = static_cast<std::uint32_t>(
            DecodeScalar(robot::IdlScalar::kUint32, in.checksum->cdr_offset(), in.sample.data(), big_endian));
        const bool match = in.checksum->Compute(in.sample.data(), big_endian) == sent;
        d.fields[static_cast<std::size_t>(in.checksum_field)] = match ? 1.0 : 0.0;
        if (!match) {
          d.fresh[in.checksum_stream] = 1;
          checksum_mismatches_.fetch_add(1, std::memory_order_relaxed);
          take = false;
        }
      }
      if (take) {
        for (DecodeStep& s : in.steps) {
          using Read = robot::FieldLeaf::Read;
          // float32(): four octets, little-endian whatever the sample's byte order.
          double value = s.read == Read::kFloat32
                             ? DecodeScalar(robot::IdlScalar::kFloat, s.offset, in.sample.data(), false)
                             : DecodeScalar(s.type, s.offset, in.sample.data(), big_endian);
          if (s.read == Read::kBit) value = static_cast<double>((static_cast<std::uint32_t>(value) >> s.bit) & 1u);
          if (s.read == Read::kIncrease) {
            // A counter: how much it grew since the sample before (modulo its range: a wrap is a
            // step, a restart from 0 a large one).
            const auto now_count = static_cast<std::uint32_t>(value);
            value = s.primed ? static_cast<double>((now_count - s.last) & s.mask) : 0.0;
            s.last = now_count;
            s.primed = true;
          }
          d.fields[s.field] = s.shaped ? robot::ShapeAxis(s.axis, value) : value;
        }
        for (const std::uint32_t s : in.streams) d.fresh[s] = 1;
      }
    }
    if (in.lost_after_ns > 0) {
      const std::int64_t last = r.last_receive_ns();
      lost = lost || (last >= 0 && (r.matched_writers() == 0 || now - last > in.lost_after_ns));
    }
  }
  const DdsLinkCounters c = link_->counters();
  safety::TransportHealth& h = d.transports[link_index_];
  h.lost = lost;
  h.degraded = c.malformed > malformed_ || c.push_dropped > dropped_;
  h.fault = false;
  malformed_ = c.malformed;
  dropped_ = c.push_dropped;
}

double DdsTransport::Term(const robot::ValueTerm& t, const robot::RobotData& d, std::uint64_t sequence) const noexcept {
  if (const auto v = CommonTerm(t, d.tick, d.mode, sequence)) return *v;
  switch (t.kind) {
    case Kind::kCommand: return d.command[t.index];
    case Kind::kMotorOn:
      return d.motors[t.index] == robot::MotorCommand::kEnable || d.motors[t.index] == robot::MotorCommand::kCommand
                 ? 1.0
                 : 0.0;
    case Kind::kField: return d.fields[t.index];
    case Kind::kSamples: return static_cast<double>(d.samples[t.index]);
    default: return 0;  // status terms: not in out messages (the robot file's reader refuses them)
  }
}

void DdsTransport::Write(const robot::RobotModel&, robot::RobotData& d) noexcept {
  for (Out& out : out_) {
    out.sequence += 1;
    Encode(out, [&](const EncodeStep& s) {
      const bool passive = s.motor >= 0 && d.motors[static_cast<std::size_t>(s.motor)] != robot::MotorCommand::kCommand;
      return passive ? 0.0 : Term(s.term, d, out.sequence);
    });
    if (!link_->writer(out.message)->Push(out.sample.data())) send_failures_.fetch_add(1, std::memory_order_relaxed);
  }
  for (std::size_t k = 0; k < snapshot_terms_.size(); ++k)
    snapshot_[k].store(Term(snapshot_terms_[k], d, 0), std::memory_order_relaxed);
}

Status DdsTransport::Connect(std::int64_t timeout_ns) {
  if (!link_->spec().dds.wait_for_peer || link_->WaitForPeer(timeout_ns)) return {};
  return MakeError(ErrorCode::kIo, "transport '" + link_->spec().name + "': no peer on DDS domain " +
                                       std::to_string(link_->domain_id()) + " within " +
                                       std::to_string(static_cast<double>(timeout_ns) * 1e-9) + " s");
}

bool DdsTransport::Paces(std::uint32_t stream) const noexcept {
  return std::any_of(in_.begin(), in_.end(), [&](const In& in) {
    return std::find(in.streams.begin(), in.streams.end(), stream) != in.streams.end();
  });
}

bool DdsTransport::WaitForSample(std::uint32_t stream, std::uint64_t* version, std::int64_t timeout_ns) {
  for (const In& in : in_) {
    if (std::find(in.streams.begin(), in.streams.end(), stream) == in.streams.end()) continue;
    DdsReader& r = *link_->reader(in.message);
    if (!r.WaitNewer(*version, timeout_ns)) return false;
    *version = r.version();
    return true;
  }
  return false;
}

double DdsTransport::StatusTerm(const robot::ValueTerm& t, const robot::ControllerStatus& s,
                                std::uint64_t sequence) const noexcept {
  if (const auto v = CommonTerm(t, s.tick, s.mode, sequence)) return *v;
  switch (t.kind) {
    case Kind::kPhase: return s.phase;
    case Kind::kCause: return s.cause;
    case Kind::kCount: return static_cast<double>(s.counts.n[t.index]);
    case Kind::kDeadlineMisses: return static_cast<double>(s.deadline_misses);
    case Kind::kTickMedianUs: return s.tick_median_us;
    case Kind::kTickMaxUs: return s.tick_max_us;
    case Kind::kCommand:
    case Kind::kField:
    case Kind::kSamples:
      for (std::size_t k = 0; k < snapshot_terms_.size(); ++k)
        if (snapshot_terms_[k].kind == t.kind && snapshot_terms_[k].index == t.index)
          return snapshot_[k].load(std::memory_order_relaxed);
      return 0;
    default: return 0;  // the common terms, above
  }
}

void DdsTransport::PublishStatus(const robot::ControllerStatus& s) {
  for (Out& out : status_) {
    out.sequence += 1;
    Encode(out, [&](const EncodeStep& step) { return StatusTerm(step.term, s, out.sequence); });
    (void)link_->writer(out.message)->Write(out.sample.data());  // counted by the writer
  }
}

void DdsTransport::Finish(const robot::ControllerStatus& s) {
  PublishStatus(s);  // the final state
  (void)link_->Flush(1'000'000'000);
}

std::string DdsTransport::Summary() const {
  const DdsLinkCounters c = link_->counters();
  char line[256];
  std::snprintf(line, sizeof line,
                "transport %s (dds): received %llu (malformed %llu), sent %llu (failed %llu), send failures %llu",
                summary_name_.c_str(), static_cast<unsigned long long>(c.received),
                static_cast<unsigned long long>(c.malformed), static_cast<unsigned long long>(c.written),
                static_cast<unsigned long long>(c.write_failed),
                static_cast<unsigned long long>(send_failures_.load(std::memory_order_relaxed)));
  std::string out = line;
  if (std::any_of(in_.begin(), in_.end(), [](const In& in) { return in.checksum.has_value(); }))
    out += ", checksum mismatches " + std::to_string(checksum_mismatches());
  return out;
}

}  // namespace pbppo::dds
