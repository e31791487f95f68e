// libFuzzer target: MIT command and special-frame decoders (the motor side). Input: one selector
// byte (which range), then the payload. An 8-byte payload is either a special frame or a command
// inside the range whose re-encoding gives the same bytes; other lengths are refused.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/can_mit_fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  fuzz::MitInput in;
  if (!fuzz::SplitMitInput(data, size, &in)) return 0;
  const can::MitRange& r = in.range;
  can::MitSpecial special{};
  const bool is_special = can::DecodeMitSpecial(in.payload, in.len, &special);
  can::MitCommand c;
  const bool is_command = can::DecodeMitCommand(r, in.payload, in.len, &c);
  fuzz::Require(!(is_special && is_command));
  fuzz::Require((is_special || is_command) == (in.len == can::kMitCommandLen));
  if (is_special) {
    std::uint8_t again[8];
    can::EncodeMitSpecial(special, again);
    fuzz::Require(std::memcmp(again, in.payload, 8) == 0);
    return 0;
  }
  if (!is_command) return 0;
  fuzz::Require(fuzz::InsideRange(r, c));
  std::uint8_t again[8];
  fuzz::Require(can::EncodeMitCommand(r, c, again) == 0);
  fuzz::Require(std::memcmp(again, in.payload, 8) == 0);
  return 0;
}
