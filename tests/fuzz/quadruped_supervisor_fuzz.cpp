// libFuzzer target: the supervisor's invariant on a quadruped's model (joints with q, dq, kp, kd
// and tau commands whose safe-stop damps: the measured position held, no stiffness, the damping
// gain; one reply stream per joint and an IMU stream; two CAN buses; a body-tilt limit) for any
// input. Bytes become the joints' limits (kept if the model validates), a previous state and a
// sequence of ticks (commands and measurements with NaN and Inf, reply ages, sample findings,
// bus faults, deadline misses, the tilt, e-stop requests).
#include <cmath>
#include <string>

#include "tests/fuzz/supervisor_fuzz_common.hpp"

namespace {

using namespace pbppo::safety;

constexpr std::size_t kJoints = 4;

SupervisorModel Quadruped(pbppo::fuzz::Bytes& b) {
  SupervisorModel m;
  for (std::size_t j = 0; j < kJoints; ++j) {
    const std::string n = std::to_string(j);
    const double q = 0.5 + std::abs(static_cast<double>(static_cast<std::int8_t>(b.U8()))) / 16.0;
    const double v = 1.0 + b.U8() % 40, tau = 1.0 + b.U8() % 40, kd = 0.5 + (b.U8() % 16) / 4.0;
    const auto input = static_cast<std::int32_t>(j);
    m.commands.push_back({"q_" + n, -q, q, -q, q, HUGE_VAL, StopKind::kHoldInput, 0, 0, input});
    m.commands.push_back({"dq_" + n, -v, v, -v, v, HUGE_VAL, StopKind::kValue, 0, 0, -1});
    m.commands.push_back({"kp_" + n, 0, 500, 0, 500, HUGE_VAL, StopKind::kValue, 0, 0, -1});
    m.commands.push_back({"kd_" + n, 0, 5, 0, 5, HUGE_VAL, StopKind::kValue, 0, std::min(kd, 5.0), -1});
    m.commands.push_back({"tau_" + n, -tau, tau, -tau, tau, HUGE_VAL, StopKind::kValue, 0, 0, -1});
    m.streams.push_back({n, 1, 2, 499, 1});
    m.input_names.push_back("q_" + n);
  }
  m.streams.push_back({"imu", 2, 10, 499, 1});
  m.transport_names = {"can/front", "can/hind"};
  m.signal_limits.push_back({"projected_gravity_z", 0, static_cast<std::uint32_t>(kJoints), -1.01, -0.5});
  m.command_limit_degrades = true;
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pbppo::fuzz::Bytes b(data, size);
  SupervisorModel m = Quadruped(b);
  if (!ValidateSupervisorModel(m)) return 0;
  SupervisorState s = MakeSupervisorState(m);
  if (b.U8() & 1) {
    s.mode = static_cast<Mode>(b.U8() % 5);
    for (double& p : s.previous) p = b.Real();
  }
  const std::size_t n = m.commands.size();
  std::vector<double> command(n), out(n), inputs(kJoints);
  std::vector<StreamState> streams(m.streams.size());
  for (auto& st : streams) st.seen = true;
  std::vector<TransportHealth> buses(2);
  for (int tick = 0; tick < 128 && !b.empty(); ++tick) {
    const std::uint8_t flags = b.U8();
    for (std::size_t k = 0; k < n; ++k)
      command[k] = (flags & 1) ? b.Real() : static_cast<double>(b.U8() % 64) / 8.0 - 4;
    for (double& x : inputs) x = (flags & 2) ? b.Real() : static_cast<double>(b.U8() % 64) / 32.0 - 1;
    for (auto& st : streams) {
      st.age_ticks = (flags & 4) ? b.U8() : (b.U8() % 16 == 0 ? 3u : 0u);
      st.invalid_input = (flags & 8) && b.U8() % 8 == 0 ? static_cast<std::int32_t>(b.U8() % kJoints) : -1;
      st.invalid_value = st.invalid_input >= 0 ? b.Real() : 0.0;
    }
    for (auto& h : buses) {
      const std::uint8_t x = (flags & 16) ? b.U8() : 0;
      h.degraded = (x & 1) != 0;
      h.fault = (x & 2) != 0;
    }
    const double gravity_z = (flags & 32) ? b.Real() : -1.0;
    SupervisorInput in;
    in.command = command;
    in.inputs = inputs;
    in.streams = streams;
    in.signals = {&gravity_z, 1};
    in.transports = buses;
    in.consecutive_deadline_misses = (flags & 64) ? b.U8() % 8 : 0;
    in.estop_request = (flags & 128) != 0 && (b.U8() % 16 == 0);
    const std::vector<double> previous = s.previous;
    const Mode before = static_cast<std::uint8_t>(s.mode) > 3 ? Mode::kEStop : s.mode;
    Supervise(m, in, static_cast<std::uint64_t>(tick), s, out);
    pbppo::fuzz::CheckTick("quadruped_supervisor_fuzz", m, in, previous, before, s, out, tick);
  }
  return 0;
}
