#include "firmware/auv/auv_transport.hpp"

#include <chrono>

#include "runtime/core/clock.hpp"
#include "runtime/loop/runner.hpp"

namespace pbppo::auv {

robot::AuvControllerStatus StatusOf(const loop::LoopData& l) {
  const loop::LoopStatus st = l.Status();
  robot::AuvControllerStatus s;
  s.tick = st.tick;
  s.mode = static_cast<std::uint8_t>(st.mode);
  s.cause = st.any_latched ? 1u << static_cast<unsigned>(st.latched) : 0u;
  s.deadline_misses = l.profiler().deadline_misses();
  s.stale_samples = st.counts[safety::Cause::kStaleSample];
  s.invalid_samples = st.counts[safety::Cause::kInvalidSample];
  s.limited_commands = st.counts[safety::Cause::kCommandLimit] + st.counts[safety::Cause::kRateLimit];
  const rt::LatencyStats t = l.profiler().histogram(rt::Stage::kTick).Snapshot().Stats();
  s.tick_median_us = static_cast<double>(t.p50_ns) / 1000.0;
  s.tick_max_us = static_cast<double>(t.max_ns) / 1000.0;
  return s;
}

Result<std::unique_ptr<AuvTransport>> AuvTransport::Create(const robot::RobotModel& m, const std::string& transport,
                                                           dds::AuvDdsLink& link, std::int64_t lost_after_ns) {
  std::unique_ptr<AuvTransport> t(new AuvTransport(link, lost_after_ns));
  const int ti = m.TransportIndex(transport);
  if (ti < 0) return MakeError(ErrorCode::kMismatch, m.path + ": no transport '" + transport + "'");
  t->link_index_ = m.transports[static_cast<std::size_t>(ti)].first_link;
  auto fields = SampleFields::Create(m);
  if (!fields) return std::move(fields).error();
  t->fields_ = *fields;
  const int v = m.CommandIndex("surge_speed"), w = m.CommandIndex("yaw_rate");
  if (v < 0 || w < 0) return MakeError(ErrorCode::kMismatch, m.path + ": no command surge_speed or yaw_rate");
  t->surge_command_ = static_cast<std::uint32_t>(v);
  t->yaw_command_ = static_cast<std::uint32_t>(w);
  return t;
}

void AuvTransport::Read(const robot::RobotModel&, robot::RobotData& d) noexcept {
  if (link_.ReadSample(&in_) != 0) {
    const robot::AuvSensorSample& s = in_.value;
    if (!have_ || s.tick != last_tick_ || s.stamp_ns != last_stamp_) {
      have_ = true;
      last_tick_ = s.tick;
      last_stamp_ = s.stamp_ns;
      fields_.Write(s, d.fields);
      d.fresh[fields_.stream()] = 1;
    }
  }
  const dds::AuvPeerView p = link_.Peer();
  const dds::AuvLinkCounters c = link_.counters();
  safety::TransportHealth& h = d.transports[link_index_];
  h.lost = p.last_receive_age_ns >= 0 && (p.matched_writers == 0 || p.last_receive_age_ns > lost_after_ns_);
  h.degraded = c.rejected > rejected_ || c.dropped_full > dropped_;
  h.fault = false;
  rejected_ = c.rejected;
  dropped_ = c.dropped_full;
}

void AuvTransport::Write(const robot::RobotModel&, robot::RobotData& d) noexcept {
  robot::AuvCommand c;
  c.tick = d.tick;
  c.stamp_ns = MonotonicNs();
  c.answers = static_cast<std::uint64_t>(d.fields[fields_.tick_field()]);
  c.surge_speed_mps = d.command[surge_command_];
  c.yaw_rate_radps = d.command[yaw_command_];
  c.mode = static_cast<std::uint8_t>(d.mode);
  if (!link_.PushCommand(c)) ++send_failures_;
}

}  // namespace pbppo::auv

namespace pbppo::auv {

std::thread PaceLockStep(dds::AuvDdsLink& link, rt::LockStepClock& clock, const std::atomic<bool>& done,
                         std::int64_t timeout_ns, std::atomic<bool>* episode_end) {
  return std::thread([&link, &clock, &done, timeout_ns, episode_end] {
    std::uint64_t version = 0;
    dds::AuvSensorInput in;
    while (!done.load()) {
      const std::uint64_t started = clock.started();
      const bool fresh = link.WaitForSample(version, timeout_ns);
      if (done.load()) break;
      if (fresh) version = link.ReadSample(&in);
      clock.Advance();
      // Wait for the loop to take this tick before allowing the next one.
      while (clock.started() == started && !done.load()) std::this_thread::yield();
      if (fresh && in.value.episode_end) {
        episode_end->store(true);
        // Let the tick that answers the final sample finish, then stop.
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        loop::RequestStop();
        break;
      }
    }
  });
}

}  // namespace pbppo::auv
