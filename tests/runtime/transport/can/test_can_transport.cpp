// SocketCAN transport over vcan (label `vcan`): needs a kernel with AF_CAN and the interfaces
// vcan0 and vcan1 (tests/vm/vcan-vm provides both). Without them these tests fail, loudly.
#include <doctest/doctest.h>

#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/candump_log.hpp"
#include "runtime/transport/can/socketcan.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::can;

namespace {

std::string Vcan(int i) {
  const char* env = std::getenv(i == 0 ? "PBPPO_VCAN0" : "PBPPO_VCAN1");
  return env != nullptr ? env : (i == 0 ? "vcan0" : "vcan1");
}

std::unique_ptr<SocketCanBus> OpenBus(SocketCanOptions o) {
  auto r = SocketCanBus::Open(o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  return std::move(*r);
}

SocketCanOptions Opts(int iface, bool fd, std::vector<std::uint32_t> ids) {
  SocketCanOptions o;
  o.interface = Vcan(iface);
  o.fd = fd;
  o.rx_ids = std::move(ids);
  return o;
}

pbppo::robot::CanMap Quadruped() {
  auto m = pbppo::robot::LoadCanMap(pbppo::test::SourcePath("models/quadruped/can_map.yaml"));
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  return *m;
}

// Receives until `want` frames have arrived or a second has passed (vcan delivers from a softirq).
std::size_t ReceiveAtLeast(SocketCanBus& bus, std::span<CanFrame> out, std::size_t want) {
  std::size_t got = 0;
  timespec t0{}, t{};
  clock_gettime(CLOCK_MONOTONIC, &t0);
  while (true) {
    got += bus.Receive(out.subspan(got));
    if (got >= want) return got;
    clock_gettime(CLOCK_MONOTONIC, &t);
    if (t.tv_sec - t0.tv_sec > 1) return got;
  }
}

CanFrame Classic(std::uint32_t id, std::uint8_t len, std::uint8_t fill) {
  CanFrame f;
  f.id = id;
  f.len = len;
  std::memset(f.data, fill, len);
  return f;
}

}  // namespace

TEST_CASE("kernel filters pass only the ids in use - classic and FD frames - own frames not looped back") {
  auto rx = OpenBus(Opts(0, true, {0x101, 0x088}));
  auto tx = OpenBus(Opts(0, true, {}));
  std::vector<CanFrame> out(16);
  CHECK(rx->Receive(out) == 0);  // nothing pending

  CanFrame fd;
  fd.id = 0x088;
  fd.len = 24;
  fd.flags = kFlagFd | kFlagBrs;
  for (std::uint8_t i = 0; i < 24; ++i) fd.data[i] = static_cast<std::uint8_t>(0xA0 + i);
  CanFrame ext = Classic(0x101, 2, 0x11);
  ext.flags = kFlagExtended;  // extended 0x101 is a different identifier
  const std::vector<CanFrame> frames = {Classic(0x555, 8, 1), Classic(0x101, 6, 2), Classic(0x102, 6, 3), ext, fd,
                                        Classic(0x7FF, 0, 0)};
  CHECK(tx->Send(frames) == frames.size());
  CHECK(tx->stats().tx_frames == frames.size());

  const std::size_t n = rx->Receive(out);
  REQUIRE(n == 2);
  CHECK(out[0].id == 0x101);
  CHECK(out[0].len == 6);
  CHECK(out[0].data[5] == 2);
  CHECK_FALSE(out[0].fd());
  CHECK(out[0].timestamp_ns > 0);
  CHECK(out[1].id == 0x088);
  CHECK(out[1].fd());
  CHECK((out[1].flags & kFlagBrs) != 0);
  REQUIRE(out[1].len == 24);
  CHECK(std::memcmp(out[1].data, fd.data, 24) == 0);
  CHECK(rx->stats().rx_frames == 2);
  CHECK(tx->Receive(out) == 0);  // the sender does not see its own frames
}

TEST_CASE("buses are separate: vcan1 traffic never reaches vcan0") {
  auto rx0 = OpenBus(Opts(0, false, {0x107}));
  auto rx1 = OpenBus(Opts(1, false, {0x107}));
  auto tx1 = OpenBus(Opts(1, false, {}));
  const CanFrame f = Classic(0x107, 6, 7);
  CHECK(tx1->Send({&f, 1}) == 1);
  std::vector<CanFrame> out(4);
  CHECK(rx0->Receive(out) == 0);
  CHECK(rx1->Receive(out) == 1);
}

TEST_CASE("a classic socket refuses FD frames - counted - the rest of the batch goes out") {
  auto tx = OpenBus(Opts(0, false, {}));
  auto rx = OpenBus(Opts(0, true, {0x100, 0x101}));
  CanFrame fd = Classic(0x100, 12, 1);
  fd.flags = kFlagFd;
  const std::vector<CanFrame> frames = {fd, Classic(0x101, 8, 2), Classic(0x100, 9, 3)};
  CHECK(tx->Send(frames) == 1);
  CHECK(tx->stats().tx_errors == 2);
  std::vector<CanFrame> out(4);
  REQUIRE(rx->Receive(out) == 1);
  CHECK(out[0].id == 0x101);
}

TEST_CASE("batched send and drain: 200 frames in 64-frame batches - drained until EAGAIN - in order") {
  SocketCanOptions ro = Opts(0, false, {0x200});
  ro.rx_batch = 16;
  ro.rcvbuf_bytes = 1 << 20;
  auto rx = OpenBus(ro);
  auto tx = OpenBus(Opts(0, false, {}));
  std::vector<CanFrame> frames;
  for (int i = 0; i < 200; ++i) {
    CanFrame f = Classic(0x200, 8, 0);
    f.data[0] = static_cast<std::uint8_t>(i);
    f.data[1] = static_cast<std::uint8_t>(i >> 8);
    frames.push_back(f);
  }
  CHECK(tx->Send(frames) == 200);
  std::vector<CanFrame> small(150), big(256);
  CHECK(rx->Receive(small) == 150);
  CHECK(rx->stats().rx_buffer_full == 1);
  const std::size_t rest = rx->Receive(big);
  REQUIRE(rest == 50);
  for (int i = 0; i < 150; ++i)
    CHECK((small[static_cast<std::size_t>(i)].data[0] | small[static_cast<std::size_t>(i)].data[1] << 8) == i);
  for (int i = 0; i < 50; ++i)
    CHECK((big[static_cast<std::size_t>(i)].data[0] | big[static_cast<std::size_t>(i)].data[1] << 8) == 150 + i);
  CHECK(rx->stats().rx_frames == 200);
  CHECK(rx->stats().rx_dropped_kernel == 0);
}

TEST_CASE("a reader that falls behind loses frames in the kernel - the loss is counted") {
  SocketCanOptions ro = Opts(0, false, {0x201});
  ro.rcvbuf_bytes = 1;  // the kernel's minimum
  auto rx = OpenBus(ro);
  auto tx = OpenBus(Opts(0, false, {}));
  std::vector<CanFrame> frames(500, Classic(0x201, 8, 5));
  CHECK(tx->Send(frames) == 500);
  std::vector<CanFrame> out(600);
  const std::size_t got = rx->Receive(out);
  CHECK(got > 0);
  CHECK(got < 500);
  // The kernel reports its drop count with the next frame it queues.
  const CanFrame probe = Classic(0x201, 1, 9);
  CHECK(tx->Send({&probe, 1}) == 1);
  REQUIRE(rx->Receive(out) == 1);
  CHECK(rx->stats().rx_dropped_kernel == 500 - got);
  CHECK(rx->stats().rx_frames == got + 1);
}

TEST_CASE("a CAN tick over vcan: 12 replies decoded - unknown ids and wrong lengths ignored - no allocation") {
  const auto map = Quadruped();
  auto ctl = BuildCodecTable(map, CanRole::kController);
  auto dev = BuildCodecTable(map, CanRole::kDevices);
  REQUIRE(ctl.ok());
  REQUIRE(dev.ok());
  std::vector<std::unique_ptr<SocketCanBus>> controller, devices;
  for (int b = 0; b < 2; ++b) {
    SocketCanOptions c = Opts(b, true, ctl->rx_ids[static_cast<std::size_t>(b)]);
    c.rx_ids.push_back(0x3F0);  // in the kernel filter but not in the table: counted as unknown
    controller.push_back(OpenBus(c));
    devices.push_back(OpenBus(Opts(b, true, dev->rx_ids[static_cast<std::size_t>(b)])));
  }
  CanRxData ctl_data = MakeCanRxData(*ctl);
  CanRxData dev_data = MakeCanRxData(*dev);
  BusStats dev_stats[2];
  std::vector<CanFrame> rx(64), tx_cmd[2], tx_rep[2];
  for (auto& v : tx_cmd) v.reserve(16);
  for (auto& v : tx_rep) v.reserve(16);

  const std::string log_path = pbppo::test::ScratchDir("vcan_tick") + "/candump.log";
  auto logger = CandumpLogger::Open(log_path, {Vcan(0), Vcan(1)}, 8192);
  REQUIRE(logger.ok());
  std::uint64_t logged = 0;

  pbppo::AllocationScope scope;
  const int kTicks = 200;
  for (int tick = 0; tick < kTicks; ++tick) {
    // Devices: reply with the state, plus one stray id and one short reply per bus.
    for (int b = 0; b < 2; ++b) tx_rep[b].clear();
    for (std::size_t i = 0; i < ctl->motor_count(); ++i) {
      MitReply r{static_cast<std::uint8_t>(ctl->motor_id[i]), 0.01 * tick, 0.5, -1.0};
      tx_rep[ctl->motor_bus[i]].push_back(MakeMitReplyFrame(ctl->reply_id[i], ctl->range[i], r));
    }
    for (int b = 0; b < 2; ++b) {
      tx_rep[b].push_back(Classic(0x3F0, 8, 0));
      CanFrame short_reply = tx_rep[b][0];
      short_reply.len = 4;
      tx_rep[b].push_back(short_reply);
      REQUIRE(devices[static_cast<std::size_t>(b)]->Send(tx_rep[b]) == tx_rep[b].size());
    }
    // Controller: drain, decode, command.
    for (std::uint32_t b = 0; b < 2; ++b) {
      const std::size_t n = ReceiveAtLeast(*controller[b], rx, 8);
      for (std::size_t k = 0; k < n; ++k) {
        DispatchFrame(*ctl, b, rx[k], ctl_data, controller[b]->stats());
        logged += (*logger)->Push(b, rx[k]) ? 1 : 0;
      }
      tx_cmd[b].clear();
    }
    for (std::size_t i = 0; i < ctl->motor_count(); ++i) {
      const MitReply& s = ctl_data.reply[i];
      MitCommand c{s.q_rad, 0.0, 20.0, 0.5, 0.0};
      tx_cmd[ctl->motor_bus[i]].push_back(MakeMitCommandFrame(ctl->motor_id[i], ctl->range[i], c));
    }
    for (std::uint32_t b = 0; b < 2; ++b) {
      REQUIRE(controller[b]->Send(tx_cmd[b]) == 6);
      const std::size_t n = ReceiveAtLeast(*devices[b], rx, 6);
      REQUIRE(n == 6);
      for (std::size_t k = 0; k < n; ++k) DispatchFrame(*dev, b, rx[k], dev_data, dev_stats[b]);
    }
  }
  const std::uint64_t allocations = scope.count();
  CHECK(allocations == 0);
  for (std::uint32_t b = 0; b < 2; ++b) {
    const BusStats& s = controller[b]->stats();
    CHECK(s.rx_frames == kTicks * 8);
    CHECK(s.decoded == kTicks * 6);
    CHECK(s.unknown_ids == kTicks);
    CHECK(s.wrong_lengths == kTicks);
    CHECK(s.tx_frames == kTicks * 6);
    CHECK(dev_stats[b].decoded == kTicks * 6);
  }
  for (std::size_t i = 0; i < ctl->motor_count(); ++i) {
    CHECK(ctl_data.reply_count[i] == kTicks);
    CHECK(dev_data.command_count[i] == kTicks);
    CHECK(dev_data.command[i].kp_nm_rad == doctest::Approx(20.0).epsilon(0.01));
    CHECK(dev_data.command[i].q_rad == doctest::Approx(0.01 * (kTicks - 1)).epsilon(1e-3));
  }

  // The candump log holds every received frame and parses back.
  (*logger)->Stop();
  CHECK((*logger)->dropped() == 0);
  CHECK(logged == kTicks * 16);
  std::ifstream in(log_path);
  std::string line;
  std::uint64_t lines = 0, replies = 0;
  while (std::getline(in, line)) {
    CandumpRecord r;
    REQUIRE_MESSAGE(ParseCandumpLine(line, &r), line);
    const std::string iface = r.iface;
    CHECK((iface == Vcan(0) || iface == Vcan(1)));
    CHECK(r.time_ns > 0);
    if (r.frame.len == 6 && r.frame.id >= 0x101 && r.frame.id <= 0x10C) ++replies;
    ++lines;
  }
  CHECK(lines == logged);
  CHECK(replies == kTicks * 12);
}

TEST_CASE("error frames injected on vcan are received and decoded (bus-off - controller error-passive - restarted)") {
  auto rx = OpenBus(Opts(0, false, {0x123}));
  auto tx = OpenBus(Opts(0, false, {}));
  CanFrame e;
  e.flags = kFlagError;
  e.id = 0x40 | 0x04;  // CAN_ERR_BUSOFF | CAN_ERR_CRTL
  e.len = 8;
  e.data[1] = 0x20;  // CAN_ERR_CRTL_TX_PASSIVE
  const std::size_t sent = tx->Send({&e, 1});
  INFO("tx errno ", tx->stats().last_errno);
  REQUIRE(sent == 1);
  rx->keep_error_frames = true;
  std::vector<CanFrame> out(4);
  REQUIRE(rx->Receive(out) == 1);
  CHECK(out[0].error());
  CHECK(rx->stats().error_frames == 1);
  CHECK(rx->stats().bus_off == 1);
  CHECK(rx->stats().error_passive == 1);
  CHECK(rx->stats().rx_frames == 0);
  char text[96];
  DescribeErrorFrame(out[0].id, out[0].data, text, sizeof text);
  CHECK(std::string(text) == "controller: tx error-passive, bus-off");
  CHECK(rx->stats().is_bus_off);
  // The controller restarted: the bus is on again (what lets a robot file's recovery rule re-arm).
  CanFrame restarted;
  restarted.flags = kFlagError;
  restarted.id = 0x100;  // CAN_ERR_RESTARTED
  restarted.len = 8;
  REQUIRE(tx->Send({&restarted, 1}) == 1);
  REQUIRE(rx->Receive(out) == 1);
  CHECK(rx->stats().restarted == 1);
  CHECK_FALSE(rx->stats().is_bus_off);
  CHECK(rx->stats().bus_off == 1);
}

TEST_CASE("opening a missing interface names it") {
  SocketCanOptions o;
  o.interface = "nosuchcan7";
  auto r = SocketCanBus::Open(o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("can bus 'nosuchcan7'") == 0);
}
