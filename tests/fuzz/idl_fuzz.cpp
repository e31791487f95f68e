// libFuzzer target: the IDL reader (runtime/robot/idl.hpp) on any text, and the CDR codec
// (runtime/transport/dds/cdr.hpp) on what it accepts. The reader returns a message or an error
// naming the file and line, never crashes; a message it accepts has every leaf aligned and inside
// its CDR and C sizes, and each leaf takes and gives back a value through a sample; a message with
// strings or sequences reads its own layout back as itself and any bytes as a received sample
// without reading past them.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "runtime/robot/idl.hpp"
#include "runtime/transport/dds/cdr.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // An include reads the same text again (as another file): includes and their limits are fuzzed too.
  auto read = [&](const std::string& path) -> pbppo::Result<std::string> {
    if (path.size() > 64) return pbppo::MakeError(pbppo::ErrorCode::kIo, path + ": cannot open");
    return text;
  };
  auto m = pbppo::robot::ParseIdlMessage(text, "fuzz.idl", "", read);
  if (!m) {
    if (m.error().message.empty()) std::abort();
    return 0;
  }
  // A message with sequences: each grows to hold an element named by the input's size.
  for (std::size_t k = 0; k < m->items.size(); ++k)
    if (m->items[k].kind == pbppo::robot::IdlItem::Kind::kSequence)
      (void)m->Element(m->items[k].path + "[" + std::to_string(size % 7) + "]");
  std::vector<std::byte> sample(pbppo::dds::CdrSampleBytes(*m));
  pbppo::dds::WriteCdrLayout(*m, sample.data());
  for (const pbppo::robot::IdlLeaf& l : m->leaves) {
    const std::uint32_t n = pbppo::robot::IdlScalarSize(l.type);
    if (l.cdr_offset % n != 0 || l.cdr_offset + n > m->cdr_size) std::abort();
    if (!m->variable() && (l.c_offset % n != 0 || l.c_offset + n > m->c_size)) std::abort();
    pbppo::dds::EncodeLeaf(l, 1.0, sample.data());
    if (pbppo::dds::DecodeLeaf(l, sample.data(), false) != 1.0) std::abort();
  }
  if (!m->variable()) return 0;
  // The layout, as a received sample, reads back as itself; the input's bytes as a received sample
  // are read or refused, never read past their end (the sanitizers watch).
  std::vector<std::byte> out(sample.size());
  if (!pbppo::dds::NormalizeCdrSample(*m, sample.data(), sample.size(), out.data()) || out != sample) std::abort();
  const std::vector<std::byte> wire(reinterpret_cast<const std::byte*>(data),
                                    reinterpret_cast<const std::byte*>(data) + size);
  (void)pbppo::dds::NormalizeCdrSample(*m, wire.data(), wire.size(), out.data());
  return 0;
}
