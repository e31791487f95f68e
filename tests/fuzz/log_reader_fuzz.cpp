// libFuzzer target: the record/replay log reader (runtime/loop/log.hpp) on any bytes: it returns
// a log or an error naming the offset and the field, never reads out of bounds; a log it accepts
// formats back without trouble; read as a recording cut short, a log without its end says where
// it ends.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "runtime/loop/log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Read as a recording cut short may be: the same, or a log that says where it ends.
  auto cut =
      pbppo::loop::ParseLog(std::span<const std::uint8_t>(data, size), "fuzz.log", pbppo::loop::LogTail::kAcceptCut);
  if (!cut) {
    if (cut.error().message.rfind("fuzz.log: offset ", 0) != 0) std::abort();
  } else if (!cut->complete && (cut->cut_reason.empty() || cut->cut_at > size)) {
    std::abort();
  }
  auto log = pbppo::loop::ParseLog(std::span<const std::uint8_t>(data, size), "fuzz.log");
  if (!log) {
    if (log.error().message.rfind("fuzz.log: offset ", 0) != 0) std::abort();
    return 0;
  }
  if (!log->complete) std::abort();
  for (const auto& r : log->records) {
    if (r.type == 2 && r.outputs.commands.size() != log->header.commands) std::abort();
    if (r.type == 1 && r.inputs.links.size() > log->header.links) std::abort();
  }
  return 0;
}
