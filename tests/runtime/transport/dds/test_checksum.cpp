// A message's checksum (runtime/transport/dds/checksum.hpp) against an implementation written
// independently, in Python, from the algorithm's definition (tests/data/go2/crc_oracle.py): the
// Go2's LowCmd_ and LowState_ filled from seeds by the oracle, their C layout and CRC compared
// byte for byte; the CRC-32/MPEG-2 check value; a sample in the other byte order.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "runtime/robot/idl.hpp"
#include "runtime/robot/text_file.hpp"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/checksum.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;

namespace {

robot::IdlMessage Parse(const std::string& name) {
  const std::string path = test::SourcePath("models/go2/idl/" + name + ".idl");
  auto m = robot::ParseIdlMessage(test::ReadText(path), path, "",
                                  [](const std::string& p) -> Result<std::string> { return test::ReadText(p); });
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  return *m;
}

// The oracle's message for `seed`, as JSON.
nlohmann::json Oracle(const std::string& type, int seed) {
  const std::string out = test::ScratchDir("checksum_oracle") + "/" + type + "_" + std::to_string(seed) + ".json";
  const std::string cmd = "/usr/bin/python3 " + test::SourcePath("tests/data/go2/crc_oracle.py") + " --idl-dir " +
                          test::SourcePath("models/go2/idl") + " --type " + type + " --seed " + std::to_string(seed) +
                          " --out " + out + " > /dev/null";
  REQUIRE_MESSAGE(std::system(cmd.c_str()) == 0, cmd);
  return nlohmann::json::parse(test::ReadText(out));
}

}  // namespace

TEST_CASE("checksum: CRC-32/MPEG-2 fed by words equals the byte-wise CRC of each word's bytes from the top") {
  // "123456789" byte-wise: the catalogue's check value 0x0376E6E7. As words: "1234" is the word
  // 0x31323334 fed from its top byte, and so on; 9 bytes do not fill words, so the check runs on
  // "12345678" padded by nothing: compare against the byte-wise CRC computed here the slow way.
  const auto bytewise = [](const unsigned char* p, std::size_t n) {
    std::uint32_t crc = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < n; ++i) {
      crc ^= static_cast<std::uint32_t>(p[i]) << 24;
      for (int k = 0; k < 8; ++k) crc = (crc & 0x80000000u) != 0 ? (crc << 1) ^ 0x04C11DB7u : crc << 1;
    }
    return crc;
  };
  const unsigned char check[] = "123456789";
  CHECK(bytewise(check, 9) == 0x0376E6E7u);
  const std::uint32_t words[2] = {0x31323334u, 0x35363738u};
  CHECK(dds::Crc32Mpeg2Words(words) == bytewise(check, 8));
  CHECK(dds::Crc32Mpeg2Words({}) == 0xFFFFFFFFu);
}

TEST_CASE("checksum: the Go2's LowCmd_ and LowState_ against the Python oracle, layout and CRC") {
  for (const std::string type : {"LowCmd_", "LowState_"}) {
    const robot::IdlMessage msg = Parse(type);
    CHECK(msg.c_size == (type == "LowCmd_" ? 812u : 1180u));
    const int crc_leaf = msg.LeafIndex("crc");
    REQUIRE(crc_leaf >= 0);
    dds::MessageChecksum checksum(msg, static_cast<std::uint32_t>(crc_leaf));
    for (int seed = 1; seed <= 4; ++seed) {
      CAPTURE(type);
      CAPTURE(seed);
      const nlohmann::json o = Oracle(type, seed);
      REQUIRE(o["c_size"].get<std::uint32_t>() == msg.c_size);
      REQUIRE(o["members"].size() == msg.leaves.size());
      dds::DdsSample sample(msg);
      for (const auto& [path, value] : o["members"].items()) {
        auto st = sample.Set(path, value.get<double>());
        REQUIRE_MESSAGE(st.ok(), st.error().message);
      }
      const std::uint32_t crc = checksum.Compute(sample.bytes(), false);
      CHECK(crc == o["members"]["crc"].get<std::uint32_t>());
      CHECK(crc == std::stoul(o["crc"].get<std::string>(), nullptr, 16));
      // The C layout, word for word, is the oracle's packed struct.
      std::string hex;
      char b[3];
      const auto words = checksum.c_words();
      const auto* bytes = reinterpret_cast<const unsigned char*>(words.data());
      for (std::size_t i = 0; i + 4 < words.size() * 4; ++i) {
        std::snprintf(b, sizeof b, "%02x", bytes[i]);
        hex += b;
      }
      CHECK(hex == o["packed_hex"].get<std::string>().substr(0, hex.size()));
      // One bit changed anywhere changes it.
      const double q = sample.Get(
          static_cast<std::uint32_t>(msg.LeafIndex(type == "LowCmd_" ? "motor_cmd[5].kp" : "motor_state[5].q")));
      REQUIRE(sample.Set(type == "LowCmd_" ? "motor_cmd[5].kp" : "motor_state[5].q", q + 1.0).ok());
      CHECK(checksum.Compute(sample.bytes(), false) != crc);
    }
  }
}

TEST_CASE("checksum: a big-endian CDR sample has the same checksum as its little-endian twin") {
  const robot::IdlMessage msg = Parse("LowCmd_");
  dds::MessageChecksum checksum(msg, static_cast<std::uint32_t>(msg.LeafIndex("crc")));
  dds::DdsSample le(msg);
  REQUIRE(le.Set("motor_cmd[0].q", 0.75).ok());
  REQUIRE(le.Set("sn[1]", 123456.0).ok());
  REQUIRE(le.Set("bandwidth", 513.0).ok());
  const std::uint32_t want = checksum.Compute(le.bytes(), false);
  // The same sample big-endian: every leaf's bytes reversed in place, header CDR_BE.
  std::vector<std::byte> be(le.bytes(), le.bytes() + dds::CdrSampleBytes(msg));
  be[1] = std::byte{0x00};  // CDR_BE
  for (const robot::IdlLeaf& l : msg.leaves) {
    std::byte* p = be.data() + dds::kCdrHeaderBytes + l.cdr_offset;
    std::reverse(p, p + robot::IdlScalarSize(l.type));
  }
  bool big = false;
  REQUIRE(dds::ReadCdrHeader(be.data(), &big));
  REQUIRE(big);
  CHECK(checksum.Compute(be.data(), true) == want);
}
