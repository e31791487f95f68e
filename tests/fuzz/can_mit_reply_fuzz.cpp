// libFuzzer target: MIT reply decoder. Input: one selector byte (which range), then the payload.
// A payload of 6 bytes decodes to values inside the range whose re-encoding gives the same bytes;
// any other length is refused.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/can_mit_fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  fuzz::MitInput in;
  if (!fuzz::SplitMitInput(data, size, &in)) return 0;
  const can::MitRange& r = in.range;
  can::MitReply rep;
  const bool ok = can::DecodeMitReply(r, in.payload, in.len, &rep);
  fuzz::Require(ok == (in.len == can::kMitReplyLen));
  if (!ok) return 0;
  fuzz::Require(rep.motor_id == in.payload[0]);
  fuzz::Require(fuzz::InsideRange(r, rep));
  std::uint8_t again[6];
  fuzz::Require(can::EncodeMitReply(r, rep, again) == 0);
  fuzz::Require(std::memcmp(again, in.payload, 6) == 0);
  return 0;
}
