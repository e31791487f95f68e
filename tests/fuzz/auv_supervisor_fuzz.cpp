// libFuzzer target: the supervisor's invariant on an AUV's model (two rate-limited speed set-points
// that ramp to zero in safe-stop, one sensor stream, one DDS link) for any input. Bytes become a
// model (kept if it validates), a previous state and a sequence of ticks (commands with NaN and
// Inf, sample findings, ages, deadline misses, a lost peer, e-stop requests, a failed inference).
#include <cmath>

#include "tests/fuzz/supervisor_fuzz_common.hpp"
#include "tests/support/auv_supervisor_model.hpp"

using namespace pbppo::safety;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  pbppo::fuzz::Bytes b(data, size);
  SupervisorModel m = pbppo::test::AuvLikeSupervisorModel();
  if (b.U8() & 1) {  // a perturbed model, used only if it validates
    SupervisorModel p = m;
    p.commands[0].min = p.commands[0].degraded_min = -std::abs(b.Real());
    p.commands[0].max = b.Real();
    p.commands[0].degraded_max = std::min(p.commands[0].max, std::abs(b.Real()));
    p.commands[1].max = p.commands[1].degraded_max = b.Real();
    p.commands[1].min = p.commands[1].degraded_min = -p.commands[1].max;
    p.commands[0].rate = b.Real();
    p.commands[0].stop_rate = b.Real();
    p.streams[0].stale_degraded_ticks = b.U8() % 8;
    p.streams[0].stale_safe_stop_ticks = b.U8() % 16;
    p.command_limit_degrades = (b.U8() & 1) != 0;
    if (ValidateSupervisorModel(p)) m = p;
  }
  SupervisorState s = MakeSupervisorState(m);
  if (b.U8() & 1) {
    s.mode = static_cast<Mode>(b.U8() % 5);
    s.previous = {b.Real(), b.Real()};
  }
  std::vector<double> out(2), inputs(2, 0.0);
  for (int tick = 0; tick < 256 && !b.empty(); ++tick) {
    const double command[2] = {b.Real(), b.Real()};
    const std::uint8_t flags = b.U8();
    StreamState stream;
    stream.seen = (flags & 2) != 0;
    stream.age_ticks = (flags & 4) ? b.U32() : b.U8() % 8;
    if (flags & 1) {
      stream.invalid_input = b.U8() % 2;
      stream.invalid_value = b.Real();
    }
    TransportHealth link;
    link.lost = (flags & 8) != 0 && (b.U8() & 1);
    SupervisorInput in;
    in.command = command;
    in.inputs = inputs;
    in.streams = {&stream, 1};
    in.transports = {&link, 1};
    in.consecutive_deadline_misses = (flags & 16) ? b.U8() % 8 : 0;
    in.estop_request = (flags & 32) != 0 && (b.U8() % 16 == 0);
    in.inference_failed = (flags & 64) != 0 && (b.U8() % 8 == 0);
    in.inference_status = "non-finite action";
    const std::vector<double> previous = s.previous;
    const Mode before = static_cast<std::uint8_t>(s.mode) > 3 ? Mode::kEStop : s.mode;
    Supervise(m, in, static_cast<std::uint64_t>(tick), s, out);
    pbppo::fuzz::CheckTick("auv_supervisor_fuzz", m, in, previous, before, s, out, tick);
  }
  return 0;
}
