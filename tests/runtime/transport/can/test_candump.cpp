#include <doctest/doctest.h>

#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/transport/can/candump_log.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::can;

namespace {
std::string Line(std::uint64_t t, const char* iface, const CanFrame& f) {
  char b[kCandumpLineMax];
  const std::size_t n = FormatCandumpLine(t, iface, f, b, sizeof b);
  REQUIRE(n > 0);
  return std::string(b, n);
}
CanFrame Frame(std::uint32_t id, std::uint8_t flags, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.flags = flags;
  for (std::uint8_t b : bytes) f.data[f.len++] = b;
  return f;
}
}  // namespace

TEST_CASE("lines in candump -L format: classic - extended - remote - FD - error") {
  CHECK(Line(1700000000123456789ull, "vcan0", Frame(0x123, 0, {0xDE, 0xAD, 0xBE, 0xEF})) ==
        "(1700000000.123456) vcan0 123#DEADBEEF\n");
  CHECK(Line(5000001000ull, "can1", Frame(0x1F334455, kFlagExtended, {0x11, 0x22})) ==
        "(5.000001) can1 1F334455#1122\n");
  CHECK(Line(0, "vcan0", Frame(0x7FF, kFlagRtr, {})) == "(0.000000) vcan0 7FF#R\n");
  CHECK(Line(0, "vcan0", Frame(0x001, 0, {})) == "(0.000000) vcan0 001#\n");
  CanFrame fd = Frame(0x088, kFlagFd | kFlagBrs, {});
  fd.len = 12;
  for (std::uint8_t i = 0; i < 12; ++i) fd.data[i] = i;
  CHECK(Line(0, "vcan1", fd) == "(0.000000) vcan1 088##1000102030405060708090A0B\n");
  CanFrame err = Frame(0x40, kFlagError, {0, 0, 0, 0, 0, 0, 0, 0});
  CHECK(Line(0, "vcan0", err) == "(0.000000) vcan0 20000040#0000000000000000\n");
}

TEST_CASE("lines parse back to the same frames") {
  std::vector<CanFrame> frames = {Frame(0x123, 0, {1, 2, 3}), Frame(0x1ABCDEF0, kFlagExtended, {0xFF}),
                                  Frame(0x101, 0, {}), Frame(0x40, kFlagError, {0, 4, 0, 0, 0, 0, 0, 0})};
  CanFrame fd = Frame(0x088, kFlagFd | kFlagBrs | kFlagEsi, {});
  fd.len = 64;
  for (std::uint8_t i = 0; i < 64; ++i) fd.data[i] = static_cast<std::uint8_t>(i * 7);
  frames.push_back(fd);
  for (const CanFrame& f : frames) {
    const std::string l = Line(1234567890987654000ull, "vcan1", f);
    CandumpRecord r;
    REQUIRE_MESSAGE(ParseCandumpLine(l, &r), l);
    CHECK(r.time_ns == 1234567890987654000ull);
    CHECK(std::string(r.iface) == "vcan1");
    CHECK(r.frame.id == f.id);
    CHECK(r.frame.flags == f.flags);
    CHECK(r.frame.len == f.len);
    CHECK(std::memcmp(r.frame.data, f.data, f.len) == 0);
  }
  CandumpRecord r;
  CHECK(ParseCandumpLine("(1.5) can0 7FF#R", &r));
  CHECK((r.frame.flags & kFlagRtr) != 0);
  CHECK_FALSE(ParseCandumpLine(std::string_view("(1.0) vc\0n0 123#00", 18), &r));  // NUL in the interface name
  for (const char* bad :
       {"", "(1.0)", "(1.0) vcan0", "(1.0) vcan0 123", "(1.0) vcan0 800#00", "(x.0) vcan0 123#00", "(1.0) vcan0 123#0",
        "(1.0) vcan0 123#001122334455667788", "(1.0) vcan0 123##1001122334455667788", "(1.0) vcan0 123##4",
        "(1.0) vcan0 12#00", "1.0 vcan0 123#00", "(1.0) vcan0 123#GG"}) {
    CHECK_MESSAGE(!ParseCandumpLine(bad, &r), bad);
  }
}

TEST_CASE("the logger writes candump lines from its own thread - pushing never allocates") {
  const std::string path = pbppo::test::ScratchDir("candump") + "/log.txt";
  auto logger = CandumpLogger::Open(path, {"vcan0", "vcan1"}, 1024);
  REQUIRE_MESSAGE(logger.ok(), logger.error().message);
  std::vector<CanFrame> sent;
  sent.reserve(500);
  {
    pbppo::AllocationScope scope;
    for (std::uint32_t i = 0; i < 500; ++i) {
      CanFrame f = Frame(0x100 + (i % 16), 0, {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i >> 8)});
      f.timestamp_ns = 1000000000ull * 1700000000ull + i * 1000ull;
      if ((*logger)->Push(i % 2, f)) sent.push_back(f);
    }
    CHECK(scope.count() == 0);
  }
  (*logger)->Stop();
  CHECK((*logger)->written() == sent.size());
  std::ifstream in(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    CandumpRecord r;
    REQUIRE_MESSAGE(ParseCandumpLine(line, &r), line);
    REQUIRE(n < sent.size());
    CHECK(r.frame.id == sent[n].id);
    CHECK(r.time_ns == sent[n].timestamp_ns);
    CHECK(std::string(r.iface) == (n % 2 == 0 ? "vcan0" : "vcan1"));
    ++n;
  }
  CHECK(n == sent.size());
}

TEST_CASE("a full logger queue drops instead of blocking") {
  const std::string path = pbppo::test::ScratchDir("candump_full") + "/log.txt";
  auto logger = CandumpLogger::Open(path, {"vcan0"}, 2);
  REQUIRE(logger.ok());
  const CanFrame f = Frame(0x123, 0, {1});
  std::uint64_t accepted = 0;
  for (int i = 0; i < 100000; ++i) accepted += (*logger)->Push(0, f) ? 1 : 0;
  (*logger)->Stop();
  CHECK(accepted + (*logger)->dropped() == 100000);
  CHECK((*logger)->written() == accepted);
}
