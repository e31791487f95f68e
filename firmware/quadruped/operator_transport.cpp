#include "firmware/quadruped/operator_transport.hpp"

#include <algorithm>
#include <chrono>

namespace pbppo::quadruped {

Result<std::unique_ptr<OperatorTransport>> OperatorTransport::Create(const robot::RobotModel& m,
                                                                     dds::OperatorDdsLink& link) {
  std::unique_ptr<OperatorTransport> t(new OperatorTransport(link));
  const int s = m.StreamIndex("velocity_command");
  if (s < 0) return MakeError(ErrorCode::kMismatch, m.path + ": no stream 'velocity_command' for the operator");
  t->stream_ = static_cast<std::uint32_t>(s);
  std::uint32_t* slots[3] = {&t->vx_, &t->vy_, &t->yaw_rate_};
  const char* names[3] = {"command_vx", "command_vy", "command_yaw_rate"};
  for (int i = 0; i < 3; ++i) {
    const int f = m.FieldIndex(names[i]);
    if (f < 0 || m.fields[static_cast<std::size_t>(f)].stream != t->stream_)
      return MakeError(ErrorCode::kMismatch,
                       m.path + ": stream 'velocity_command' has no field '" + names[i] + "' for the operator");
    *slots[i] = static_cast<std::uint32_t>(f);
  }
  return t;
}

void OperatorTransport::Read(const robot::RobotModel&, robot::RobotData& d) noexcept {
  const std::uint64_t v = link_.ReadCommand(&in_);
  if (v == 0 || v == version_) return;
  version_ = v;
  d.fields[vx_] = in_.value.vx_mps;
  d.fields[vy_] = in_.value.vy_mps;
  d.fields[yaw_rate_] = in_.value.yaw_rate_radps;
  d.fresh[stream_] = 1;
  vx_now_.store(in_.value.vx_mps, std::memory_order_relaxed);
  vy_now_.store(in_.value.vy_mps, std::memory_order_relaxed);
  yaw_rate_now_.store(in_.value.yaw_rate_radps, std::memory_order_relaxed);
  seq_.store(in_.value.seq, std::memory_order_relaxed);
  commands_.fetch_add(1, std::memory_order_relaxed);
}

robot::VelocityCommand OperatorTransport::last() const noexcept {
  robot::VelocityCommand c;
  c.seq = seq_.load(std::memory_order_relaxed);
  c.vx_mps = vx_now_.load(std::memory_order_relaxed);
  c.vy_mps = vy_now_.load(std::memory_order_relaxed);
  c.yaw_rate_radps = yaw_rate_now_.load(std::memory_order_relaxed);
  return c;
}

robot::QuadrupedStatus StatusOf(const loop::LoopData& l, const OperatorTransport* op) {
  const loop::LoopStatus st = l.Status();
  robot::QuadrupedStatus s;
  s.tick = st.tick;
  s.phase = static_cast<std::uint8_t>(st.phase);
  s.mode = static_cast<std::uint8_t>(st.mode);
  s.cause = st.any_latched ? 1u << static_cast<unsigned>(st.latched) : 0u;
  const robot::VelocityCommand c = op != nullptr ? op->last() : robot::VelocityCommand{};
  s.commands_received = op != nullptr ? op->commands() : 0;
  s.command_vx_mps = c.vx_mps;
  s.command_vy_mps = c.vy_mps;
  s.command_yaw_rate_radps = c.yaw_rate_radps;
  s.deadline_misses = l.profiler().deadline_misses();
  s.stale_samples = st.counts[safety::Cause::kStaleSample];
  const rt::LatencyStats t = l.profiler().histogram(rt::Stage::kTick).Snapshot().Stats();
  s.tick_median_us = static_cast<double>(t.p50_ns) / 1000.0;
  s.tick_max_us = static_cast<double>(t.max_ns) / 1000.0;
  return s;
}

StatusPublisher::StatusPublisher(dds::OperatorDdsLink& link, const loop::LoopData& loop, const OperatorTransport* op,
                                 std::int64_t period_ns)
    : thread_([this, &link, &loop, op, period_ns] {
        const auto period = std::chrono::nanoseconds(period_ns);
        auto next = std::chrono::steady_clock::now();
        while (!stop_.load()) {
          (void)link.PublishStatus(StatusOf(loop, op));
          next += period;
          while (!stop_.load() && std::chrono::steady_clock::now() < next)
            std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(
                std::chrono::milliseconds(10), next - std::chrono::steady_clock::now()));
        }
        (void)link.PublishStatus(StatusOf(loop, op));  // the final state
      }) {}

StatusPublisher::~StatusPublisher() {
  stop_.store(true);
  thread_.join();
}

}  // namespace pbppo::quadruped
