// MIT codec: bit layout, exhaustive round trips over every code, clamping, non-finite input,
// special frames and the command that would look like one.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>

#include "runtime/transport/can/mit_codec.hpp"
#include "runtime/transport/can/quantize.hpp"

using namespace pbppo::can;

namespace {
MitRange Ak70() {
  MitRange r;
  r.p_min = -12.5, r.p_max = 12.5, r.v_min = -50, r.v_max = 50, r.kp_min = 0, r.kp_max = 500;
  r.kd_min = 0, r.kd_max = 5, r.t_min = -25, r.t_max = 25;
  return r;
}
// An asymmetric range: nothing special about zero.
MitRange Odd() {
  MitRange r;
  r.p_min = -3.0, r.p_max = 9.7, r.v_min = -7, r.v_max = 41, r.kp_min = 2, r.kp_max = 333;
  r.kd_min = 0.1, r.kd_max = 4.2, r.t_min = -18, r.t_max = 30;
  return r;
}
}  // namespace

TEST_CASE("command bit layout: fields packed big-endian as documented") {
  MitCommandCodes c{0xABCD, 0x123, 0x456, 0x789, 0xABC};
  std::uint8_t b[8];
  PackMitCommand(c, b);
  const std::uint8_t expect[8] = {0xAB, 0xCD, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC};
  CHECK(std::memcmp(b, expect, 8) == 0);
  const MitCommandCodes u = UnpackMitCommand(b);
  CHECK(u.p == c.p);
  CHECK(u.v == c.v);
  CHECK(u.kp == c.kp);
  CHECK(u.kd == c.kd);
  CHECK(u.t == c.t);
}

TEST_CASE("reply bit layout: id byte - then p16 v12 t12") {
  MitReplyCodes c{0x07, 0xBEEF, 0x123, 0x456};
  std::uint8_t b[6];
  PackMitReply(c, b);
  const std::uint8_t expect[6] = {0x07, 0xBE, 0xEF, 0x12, 0x34, 0x56};
  CHECK(std::memcmp(b, expect, 6) == 0);
  const MitReplyCodes u = UnpackMitReply(b);
  CHECK(u.motor_id == 7);
  CHECK(u.p == 0xBEEF);
  CHECK(u.v == 0x123);
  CHECK(u.t == 0x456);
}

TEST_CASE("quantisation: decode then encode is exact - encode then decode within half a step - every code") {
  for (const MitRange& r : {Ak70(), Odd()}) {
    struct Field {
      double lo, hi;
      unsigned bits;
    };
    for (const Field f : {Field{r.p_min, r.p_max, 16}, Field{r.v_min, r.v_max, 12}, Field{r.kp_min, r.kp_max, 12},
                          Field{r.kd_min, r.kd_max, 12}, Field{r.t_min, r.t_max, 12}}) {
      const double step = QuantizationStep(f.lo, f.hi, f.bits);
      for (std::uint32_t code = 0; code <= MaxCode(f.bits); ++code) {
        const double x = CodeToValue(code, f.lo, f.hi, f.bits);
        REQUIRE(x >= f.lo - 1e-12);
        REQUIRE(x <= f.hi + 1e-12);
        const QuantizeResult q = ValueToCode(x, f.lo, f.hi, f.bits);
        REQUIRE(q.code == code);
        REQUIRE_FALSE(q.non_finite);
        // Values between codes: the nearest code, error at most half a step.
        for (double frac : {0.25, 0.49, -0.49}) {
          const double y = std::fmin(std::fmax(x + frac * step, f.lo), f.hi);
          const double back = CodeToValue(ValueToCode(y, f.lo, f.hi, f.bits).code, f.lo, f.hi, f.bits);
          REQUIRE(std::fabs(back - y) <= 0.5 * step * (1 + 1e-9));
        }
      }
    }
  }
}

TEST_CASE("commands and replies round-trip through whole frames over the range") {
  const MitRange r = Odd();
  for (int i = 0; i <= 1000; ++i) {
    const double s = i / 1000.0;
    MitCommand c{r.p_min + s * (r.p_max - r.p_min), r.v_max - s * (r.v_max - r.v_min),
                 r.kp_min + s * (r.kp_max - r.kp_min), r.kd_min + (1 - s) * (r.kd_max - r.kd_min),
                 r.t_min + s * s * (r.t_max - r.t_min)};
    std::uint16_t flags = 0xFFFF;
    const CanFrame f = MakeMitCommandFrame(5, r, c, &flags);
    CHECK(f.id == 5);
    CHECK(f.len == 8);
    MitCommand d;
    REQUIRE(DecodeMitCommand(r, f.data, f.len, &d));
    const bool special_guard = (flags & kMitClampedTorque) != 0;
    CHECK((flags & ~kMitClampedTorque) == 0);
    CHECK(std::fabs(d.q_rad - c.q_rad) <= 0.5 * QuantizationStep(r.p_min, r.p_max, 16) + 1e-12);
    CHECK(std::fabs(d.dq_rad_s - c.dq_rad_s) <= 0.5 * QuantizationStep(r.v_min, r.v_max, 12) + 1e-12);
    CHECK(std::fabs(d.kp_nm_rad - c.kp_nm_rad) <= 0.5 * QuantizationStep(r.kp_min, r.kp_max, 12) + 1e-12);
    CHECK(std::fabs(d.kd_nm_s_rad - c.kd_nm_s_rad) <= 0.5 * QuantizationStep(r.kd_min, r.kd_max, 12) + 1e-12);
    if (!special_guard)
      CHECK(std::fabs(d.tau_ff_nm - c.tau_ff_nm) <= 0.5 * QuantizationStep(r.t_min, r.t_max, 12) + 1e-12);

    MitReply rep{9, c.q_rad, c.dq_rad_s, c.tau_ff_nm};
    const CanFrame g = MakeMitReplyFrame(0x109, r, rep);
    CHECK(g.len == 6);
    MitReply back;
    REQUIRE(DecodeMitReply(r, g.data, g.len, &back));
    CHECK(back.motor_id == 9);
    CHECK(std::fabs(back.q_rad - rep.q_rad) <= 0.5 * QuantizationStep(r.p_min, r.p_max, 16) + 1e-12);
    CHECK(std::fabs(back.dq_rad_s - rep.dq_rad_s) <= 0.5 * QuantizationStep(r.v_min, r.v_max, 12) + 1e-12);
    CHECK(std::fabs(back.tau_nm - rep.tau_nm) <= 0.5 * QuantizationStep(r.t_min, r.t_max, 12) + 1e-12);
    // decode then encode gives the same bytes
    std::uint8_t again[6];
    EncodeMitReply(r, back, again);
    CHECK(std::memcmp(again, g.data, 6) == 0);
  }
}

TEST_CASE("out-of-range values are clamped and flagged - non-finite values encode as the code nearest zero") {
  const MitRange r = Ak70();
  std::uint8_t b[8];
  MitCommand c{100, -100, 1000, -1, 26};
  const std::uint16_t f = EncodeMitCommand(r, c, b);
  CHECK(f == (kMitClampedPosition | kMitClampedVelocity | kMitClampedKp | kMitClampedKd | kMitClampedTorque));
  MitCommand d;
  REQUIRE(DecodeMitCommand(r, b, 8, &d));
  CHECK(d.q_rad == doctest::Approx(12.5));
  CHECK(d.dq_rad_s == doctest::Approx(-50));
  CHECK(d.kp_nm_rad == doctest::Approx(500));
  CHECK(d.kd_nm_s_rad == doctest::Approx(0));
  CHECK(d.tau_ff_nm == doctest::Approx(25));

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  MitCommand bad{nan, inf, nan, -inf, nan};
  const std::uint16_t g = EncodeMitCommand(r, bad, b);
  CHECK(g == (kMitNonFinitePosition | kMitNonFiniteVelocity | kMitNonFiniteKp | kMitNonFiniteKd | kMitNonFiniteTorque));
  REQUIRE(DecodeMitCommand(r, b, 8, &d));
  CHECK(std::fabs(d.q_rad) <= 0.5 * QuantizationStep(r.p_min, r.p_max, 16));
  CHECK(d.kp_nm_rad == 0.0);  // gains: zero is the range's minimum, exactly representable
  CHECK(d.kd_nm_s_rad == 0.0);
  CHECK(std::fabs(d.tau_ff_nm) <= 0.5 * QuantizationStep(r.t_min, r.t_max, 12));
}

TEST_CASE("zero is not a code of the symmetric AK70-10 ranges (docs/can.md)") {
  const MitRange r = Ak70();
  // 16 bits over [-12.5, 12.5]: codes 32767 and 32768 straddle zero.
  const double below = CodeToValue(32767, r.p_min, r.p_max, 16);
  const double above = CodeToValue(32768, r.p_min, r.p_max, 16);
  CHECK(below < 0.0);
  CHECK(above > 0.0);
  CHECK(below == doctest::Approx(-12.5 / 65535).epsilon(1e-9));
  // 12-bit torque over [-25, 25]: zero lands between 2047 and 2048, 6.1 mNm away.
  CHECK(CodeToValue(2047, r.t_min, r.t_max, 12) == doctest::Approx(-25.0 / 4095).epsilon(1e-9));
}

TEST_CASE("special frames: enter - exit - zero - other bytes are not special") {
  for (MitSpecial k : {MitSpecial::kEnterMotorMode, MitSpecial::kExitMotorMode, MitSpecial::kSetZero}) {
    const CanFrame f = MakeMitSpecialFrame(3, k);
    CHECK(f.data[0] == 0xFF);
    CHECK(f.data[7] == static_cast<std::uint8_t>(k));
    MitSpecial got{};
    REQUIRE(DecodeMitSpecial(f.data, f.len, &got));
    CHECK(got == k);
    MitCommand c;
    CHECK_FALSE(DecodeMitCommand(MitRange{}, f.data, f.len, &c));
  }
  std::uint8_t b[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFB};
  MitSpecial got{};
  CHECK_FALSE(DecodeMitSpecial(b, 8, &got));
  b[7] = 0xFC;
  CHECK_FALSE(DecodeMitSpecial(b, 7, &got));
  b[3] = 0xFE;
  CHECK_FALSE(DecodeMitSpecial(b, 8, &got));
}

TEST_CASE("a command at the top of every range never goes out as a special frame") {
  MitRange r = Ak70();
  std::uint8_t b[8];
  for (std::uint32_t t = 0xFF8; t <= 0xFFF; ++t) {
    MitCommand c{r.p_max, r.v_max, r.kp_max, r.kd_max, CodeToValue(t, r.t_min, r.t_max, 12)};
    const std::uint16_t f = EncodeMitCommand(r, c, b);
    MitSpecial got{};
    CHECK_FALSE(DecodeMitSpecial(b, 8, &got));
    const bool guarded = t >= 0xFFC && t <= 0xFFE;
    CHECK(((f & kMitClampedTorque) != 0) == guarded);
    CHECK(UnpackMitCommand(b).t == (guarded ? 0xFFB : t));
  }
}

TEST_CASE("decoders refuse wrong lengths") {
  std::uint8_t b[8] = {};
  MitCommand c;
  MitReply r;
  CHECK_FALSE(DecodeMitCommand(Ak70(), b, 7, &c));
  CHECK_FALSE(DecodeMitReply(Ak70(), b, 8, &r));
  CHECK_FALSE(DecodeMitReply(Ak70(), b, 5, &r));
}
