// Shared by the supervisor fuzz targets: bytes become values (NaN, Inf, small and raw doubles),
// and every tick's command is checked against the supervisor's invariant, whatever the model:
// finite, inside its limits (and its degraded limits when degraded), within the rate limit of the
// previous command below safe-stop, the safe-stop rule of each command (a ramp towards zero at
// most its stop rate, a fixed value, the held input), zero in e-stop, and a mode that never falls.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "runtime/safety/supervisor.hpp"

namespace pbppo::fuzz {

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

[[noreturn]] inline void Fail(const char* target, const char* what, int line, int tick, std::size_t k) {
  std::fprintf(stderr, "%s:%d: invariant failed at tick %d, command %zu: %s\n", target, line, tick, k, what);
  std::abort();
}

// Checks one tick's output `out` against the model, given the previous command and mode.
inline void CheckTick(const char* target, const safety::SupervisorModel& m, const safety::SupervisorInput& in,
                      const std::vector<double>& previous, safety::Mode before, const safety::SupervisorState& s,
                      const std::vector<double>& out, int tick) {
  using safety::Mode;
  using safety::StopKind;
#define PBPPO_REQUIRE(cond) ((cond) ? (void)0 : Fail(target, #cond, __LINE__, tick, k))
  const double eps = 1e-9;
  std::size_t k = 0;
  PBPPO_REQUIRE(s.mode >= before);
  for (; k < m.commands.size(); ++k) {
    const safety::CommandLimit& c = m.commands[k];
    const double v = out[k];
    const double prev = std::clamp(std::isfinite(previous[k]) ? previous[k] : 0.0, c.min, c.max);
    PBPPO_REQUIRE(std::isfinite(v) && v >= c.min && v <= c.max);
    PBPPO_REQUIRE(s.previous[k] == v);
    switch (s.mode) {
      case Mode::kNominal: PBPPO_REQUIRE(std::abs(v - prev) <= c.rate + eps); break;
      case Mode::kDegraded:
        PBPPO_REQUIRE(std::abs(v - prev) <= c.rate + eps);
        PBPPO_REQUIRE(v <= std::max(prev, c.degraded_max) && v >= std::min(prev, c.degraded_min));
        break;
      case Mode::kSafeStop:
        if (c.stop == StopKind::kRamp) {
          PBPPO_REQUIRE(std::abs(v) <= std::abs(prev) && std::abs(v - prev) <= c.stop_rate + eps);
        } else if (c.stop == StopKind::kValue) {
          PBPPO_REQUIRE(v == c.stop_value);
        } else {
          const double x = in.inputs[static_cast<std::size_t>(c.hold_input)];
          PBPPO_REQUIRE(v == std::clamp(std::isfinite(x) ? x : 0.0, c.min, c.max));
        }
        break;
      case Mode::kEStop: PBPPO_REQUIRE(v == std::clamp(0.0, c.min, c.max)); break;
    }
  }
  char text[256];
  PBPPO_REQUIRE(safety::Describe(m, s.last, text, sizeof text) < sizeof text);
#undef PBPPO_REQUIRE
}

}  // namespace pbppo::fuzz
