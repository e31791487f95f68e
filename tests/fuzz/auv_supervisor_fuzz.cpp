// libFuzzer target: the AUV supervisor's invariant for any input. Bytes become a configuration
// (kept if it validates), a previous state and a sequence of ticks (commands, samples with any
// field values including NaN and Inf, ages, deadline misses, peer and e-stop flags). Every tick's
// command must be finite, inside the limits, within the rate limits of the previous command
// (safe-stop: towards zero by at most the stop rates; e-stop: zero), and the mode never falls.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "runtime/safety/auv_supervisor.hpp"

namespace {

using namespace pbppo::safety;

class Bytes {
 public:
  Bytes(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  bool empty() const { return n_ == 0; }
  std::uint8_t U8() {
    if (n_ == 0) return 0;
    --n_;
    return *d_++;
  }
  std::uint32_t U32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v = (v << 8) | U8();
    return v;
  }
  // A double from a small table of special values or raw bits.
  double Real() {
    const std::uint8_t k = U8();
    switch (k % 8) {
      case 0: return std::nan("");
      case 1: return (k & 8) ? INFINITY : -INFINITY;
      case 2: return 0.0;
      case 3: return static_cast<double>(static_cast<std::int8_t>(U8())) / 16.0;
      case 4: return static_cast<double>(static_cast<std::int16_t>(U32())) / 100.0;
      default: {
        std::uint64_t bits = (static_cast<std::uint64_t>(U32()) << 32) | U32();
        double v;
        std::memcpy(&v, &bits, sizeof v);
        return v;
      }
    }
  }

 private:
  const std::uint8_t* d_;
  std::size_t n_;
};

// Aborts with the failed condition, its line and the tick's numbers, so a crash input explains
// itself when replayed.
struct TickTrace {
  int tick = 0;
  double v_prev = 0.0, w_prev = 0.0, v = 0.0, w = 0.0, in_v = 0.0, in_w = 0.0;
  int mode_before = 0, mode_after = 0;
};
TickTrace g_trace;

void Fail(const char* what, int line) {
  const TickTrace& t = g_trace;
  std::fprintf(stderr,
               "auv_supervisor_fuzz:%d: invariant failed: %s\n  tick %d mode %d -> %d, input v=%.17g "
               "w=%.17g, previous v=%.17g w=%.17g, command v=%.17g w=%.17g\n",
               line, what, t.tick, t.mode_before, t.mode_after, t.in_v, t.in_w, t.v_prev, t.w_prev, t.v, t.w);
  std::abort();
}

#define Require(cond) ((cond) ? (void)0 : Fail(#cond, __LINE__))

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes b(data, size);
  AuvSupervisorConfig c;
  if (b.U8() & 1) {  // a perturbed configuration, used only if it validates
    AuvSupervisorConfig p = c;
    p.v_min_mps = -std::abs(b.Real());
    p.v_max_mps = b.Real();
    p.w_max_radps = b.Real();
    p.dv_max_mps = b.Real();
    p.stop_dv_mps = b.Real();
    p.stale_degraded_ticks = b.U8() % 8;
    p.stale_safe_stop_ticks = b.U8() % 16;
    char why[256];
    if (ValidateAuvSupervisorConfig(p, why, sizeof why)) c = p;
  }
  AuvSupervisorState s;
  if (b.U8() & 1) {
    s.mode = static_cast<AuvMode>(b.U8() % 5);
    s.v_mps = b.Real();
    s.w_radps = b.Real();
  }
  pbppo::robot::AuvSensorSample sample;
  sample.sonar_beams = c.sonar_beams;
  for (int tick = 0; tick < 256 && !b.empty(); ++tick) {
    AuvSupervisorInput in;
    in.v_mps = b.Real();
    in.w_radps = b.Real();
    const std::uint8_t flags = b.U8();
    if (flags & 1) {
      double* fields[] = {&sample.x_m,        &sample.depth_m,        &sample.yaw_rad,
                          &sample.surge_mps,  &sample.yaw_rate_radps, &sample.target_distance_m,
                          &sample.clearance_m};
      *fields[b.U8() % 7] = b.Real();
      sample.sonar_m[b.U8() % pbppo::robot::kAuvMaxSonarBeams] = static_cast<float>(b.Real());
      if (flags & 64) sample.sonar_beams = b.U8();
    }
    in.sample = (flags & 2) ? &sample : nullptr;
    in.sample_age_ticks = (flags & 4) ? b.U32() : b.U8() % 8;
    in.peer_lost = (flags & 8) != 0 && (b.U8() & 1);
    in.consecutive_deadline_misses = (flags & 16) ? b.U8() % 8 : 0;
    in.estop_request = (flags & 32) != 0 && (b.U8() % 16 == 0);

    const double v_prev = std::isfinite(s.v_mps) ? std::fmin(std::fmax(s.v_mps, c.v_min_mps), c.v_max_mps) : 0.0;
    const double w_prev =
        std::isfinite(s.w_radps) ? std::fmin(std::fmax(s.w_radps, -c.w_max_radps), c.w_max_radps) : 0.0;
    const AuvMode before = static_cast<std::uint8_t>(s.mode) > 3 ? AuvMode::kEStop : s.mode;
    const AuvDecision d = SuperviseAuv(c, in, s);
    g_trace = {tick,
               v_prev,
               w_prev,
               d.v_mps,
               d.w_radps,
               in.v_mps,
               in.w_radps,
               static_cast<int>(before),
               static_cast<int>(d.state.mode)};
    Require(std::isfinite(d.v_mps) && std::isfinite(d.w_radps));
    Require(d.v_mps >= c.v_min_mps && d.v_mps <= c.v_max_mps);
    Require(d.w_radps >= -c.w_max_radps && d.w_radps <= c.w_max_radps);
    Require(d.state.mode >= before);
    Require(d.state.v_mps == d.v_mps && d.state.w_radps == d.w_radps);
    const double eps = 1e-9;
    switch (d.state.mode) {
      case AuvMode::kNominal:
      case AuvMode::kDegraded:
        Require(std::abs(d.v_mps - v_prev) <= c.dv_max_mps + eps);
        Require(std::abs(d.w_radps - w_prev) <= c.dw_max_radps + eps);
        break;
      case AuvMode::kSafeStop:
        Require(std::abs(d.v_mps) <= std::abs(v_prev) && std::abs(d.v_mps - v_prev) <= c.stop_dv_mps + eps);
        Require(std::abs(d.w_radps) <= std::abs(w_prev) && std::abs(d.w_radps - w_prev) <= c.stop_dw_radps + eps);
        break;
      case AuvMode::kEStop: Require(d.v_mps == 0.0 && d.w_radps == 0.0); break;
    }
    char text[160];
    Require(DescribeAuv(d, text, sizeof text) < sizeof text);
    s = d.state;
  }
  return 0;
}
