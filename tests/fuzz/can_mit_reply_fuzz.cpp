// libFuzzer target: MIT reply decoder. Input: one selector byte (which range), then the payload.
// A payload of 6 bytes decodes to values inside the range whose re-encoding gives the same bytes;
// any other length is refused.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "tests/fuzz/can_mit_fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  if (size < 1 || size > 1 + can::kFdMaxLen) return 0;
  const can::MitRange r = fuzz::FuzzRange(data[0]);
  const auto len = static_cast<std::uint8_t>(size - 1);
  std::uint8_t payload[can::kFdMaxLen] = {};
  std::memcpy(payload, data + 1, len);
  can::MitReply rep;
  const bool ok = can::DecodeMitReply(r, payload, len, &rep);
  fuzz::Require(ok == (len == can::kMitReplyLen));
  if (!ok) return 0;
  fuzz::Require(rep.motor_id == payload[0]);
  fuzz::Require(fuzz::Within(rep.q_rad, r.p_min, r.p_max));
  fuzz::Require(fuzz::Within(rep.dq_rad_s, r.v_min, r.v_max));
  fuzz::Require(fuzz::Within(rep.tau_nm, r.t_min, r.t_max));
  std::uint8_t again[6];
  fuzz::Require(can::EncodeMitReply(r, rep, again) == 0);
  fuzz::Require(std::memcmp(again, payload, 6) == 0);
  return 0;
}
