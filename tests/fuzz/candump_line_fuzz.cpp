// libFuzzer target: candump line parser. A line that parses formats back to a line that parses
// to the same frame (times at microsecond resolution).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "runtime/transport/can/candump_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo::can;
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  CandumpRecord r;
  if (!ParseCandumpLine(line, &r)) return 0;
  char buf[kCandumpLineMax];
  const std::uint64_t t_us = r.time_ns / 1000 * 1000;
  const std::size_t n = FormatCandumpLine(t_us, r.iface, r.frame, buf, sizeof buf);
  if (n == 0) std::abort();
  CandumpRecord back;
  if (!ParseCandumpLine(std::string_view(buf, n), &back)) std::abort();
  if (back.time_ns != t_us || back.frame.id != r.frame.id || back.frame.flags != r.frame.flags) std::abort();
  const bool rtr = (r.frame.flags & kFlagRtr) != 0;
  if (!rtr && (back.frame.len != r.frame.len || std::memcmp(back.frame.data, r.frame.data, r.frame.len) != 0))
    std::abort();
  if (std::strcmp(back.iface, r.iface) != 0) std::abort();
  return 0;
}
