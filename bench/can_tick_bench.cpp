// CAN tick benchmark: per tick the controller drains and decodes 12 MIT replies and encodes and
// sends 12 commands over two SocketCAN buses (vcan0/vcan1 by default); emulated motors on their
// own sockets send the replies and read the commands outside the timed part. Reports median,
// p99, p99.9 and max of the timed part, plus the pure codec cost, and counts allocations.
// Needs AF_CAN and the interfaces: run natively where vcan exists, or inside tests/vm/vcan-vm
// (timings there are ~10x slower than native: software-emulated CPU).
//
// usage: pbppo_bench_can_tick [--ticks N] [--map models/quadruped/can_map.yaml] [--if0 vcan0] [--if1 vcan1]
//                             [--codec-only 1]   (no sockets: the codec part alone, runs anywhere)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/socketcan.hpp"

using namespace pbppo::can;
using Clock = std::chrono::steady_clock;

namespace {

struct Summary {
  double median_us, p99_us, p999_us, max_us, min_us;
};

Summary Summarise(std::vector<double>& ns) {
  std::sort(ns.begin(), ns.end());
  auto at = [&](double q) {
    return ns[std::min(ns.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ns.size())))] / 1e3;
  };
  return {at(0.5), at(0.99), at(0.999), ns.back() / 1e3, ns.front() / 1e3};
}

void Print(const char* what, Summary s) {
  std::printf("%-34s min %8.2f  median %8.2f  p99 %8.2f  p99.9 %8.2f  max %8.2f us\n", what, s.min_us, s.median_us,
              s.p99_us, s.p999_us, s.max_us);
}

}  // namespace

int main(int argc, char** argv) {
  int ticks = 20000;
  std::string map_path = "models/quadruped/can_map.yaml";
  std::string iface[2] = {"vcan0", "vcan1"};
  bool codec_only = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--ticks") {
      ticks = std::atoi(argv[i + 1]);
    } else if (a == "--map") {
      map_path = argv[i + 1];
    } else if (a == "--if0") {
      iface[0] = argv[i + 1];
    } else if (a == "--codec-only") {
      codec_only = std::atoi(argv[i + 1]) != 0;
    } else if (a == "--if1") {
      iface[1] = argv[i + 1];
    } else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (ticks < 100) ticks = 100;
  auto map = pbppo::robot::LoadCanMap(map_path);
  if (!map) {
    std::fprintf(stderr, "%s\n", map.error().message.c_str());
    return 1;
  }
  if (map->buses.size() != 2) {
    std::fprintf(stderr, "%s: the bench expects two buses\n", map_path.c_str());
    return 1;
  }
  auto ctl = BuildCodecTable(*map, CanRole::kController);
  auto dev = BuildCodecTable(*map, CanRole::kDevices);
  if (!ctl || !dev) {
    std::fprintf(stderr, "%s\n", (!ctl ? ctl.error() : dev.error()).message.c_str());
    return 1;
  }
  if (codec_only) {
    // The codec part of a tick without sockets: decode 12 replies, encode 12 commands.
    CanRxData data = MakeCanRxData(*ctl);
    BusStats st;
    std::vector<CanFrame> reply(ctl->motor_count()), command(ctl->motor_count());
    std::vector<double> ns;
    ns.reserve(static_cast<std::size_t>(ticks));
    pbppo::AllocationScope scope;
    for (int t = 0; t < ticks + 1000; ++t) {
      for (std::size_t i = 0; i < reply.size(); ++i) {
        const MitReply r{static_cast<std::uint8_t>(ctl->motor_id[i]), 0.001 * (t % 1000), 0.2, -0.5};
        reply[i] = MakeMitReplyFrame(ctl->reply_id[i], ctl->range[i], r);
      }
      const auto c0 = Clock::now();
      for (std::size_t i = 0; i < reply.size(); ++i) DispatchFrame(*ctl, ctl->motor_bus[i], reply[i], data, st);
      for (std::size_t i = 0; i < reply.size(); ++i) {
        const MitCommand c{data.reply[i].q_rad, 0.0, 30.0, 0.8, 0.1};
        command[i] = MakeMitCommandFrame(ctl->motor_id[i], ctl->range[i], c);
      }
      asm volatile("" : : "r"(command.data()) : "memory");
      const auto c1 = Clock::now();
      if (t >= 1000)
        ns.push_back(static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(c1 - c0).count()));
    }
    const std::uint64_t allocations = scope.count();
    std::printf("CAN codec bench (no sockets): %d ticks, %zu motors (%s)\n", ticks, reply.size(), map_path.c_str());
    Print("codec only (12 decode + 12 encode)", Summarise(ns));
    std::printf("heap allocations in the loop: %llu\n", static_cast<unsigned long long>(allocations));
    return allocations == 0 && st.decoded == static_cast<std::uint64_t>(ticks + 1000) * reply.size() ? 0 : 1;
  }
  std::unique_ptr<SocketCanBus> cbus[2], dbus[2];
  for (int b = 0; b < 2; ++b) {
    SocketCanOptions o;
    o.interface = iface[b];
    o.fd = map->buses[static_cast<std::size_t>(b)].fd;
    o.rx_ids = ctl->rx_ids[static_cast<std::size_t>(b)];
    auto c = SocketCanBus::Open(o);
    o.rx_ids = dev->rx_ids[static_cast<std::size_t>(b)];
    auto d = SocketCanBus::Open(o);
    if (!c || !d) {
      std::fprintf(stderr, "%s\n", (!c ? c.error() : d.error()).message.c_str());
      return 1;
    }
    cbus[b] = std::move(*c);
    dbus[b] = std::move(*d);
  }
  CanRxData cdata = MakeCanRxData(*ctl), ddata = MakeCanRxData(*dev);
  BusStats dstats[2];
  const std::size_t n_motors = ctl->motor_count();
  std::vector<CanFrame> rx(64), replies[2], commands[2], reply_of(n_motors), command_of(n_motors);
  BusStats scratch;
  for (int b = 0; b < 2; ++b) {
    replies[b].reserve(n_motors);
    commands[b].reserve(n_motors);
  }
  std::vector<double> tick_ns, codec_ns;
  tick_ns.reserve(static_cast<std::size_t>(ticks));
  codec_ns.reserve(static_cast<std::size_t>(ticks));
  std::uint64_t incomplete = 0, lost_commands = 0;

  pbppo::AllocationScope scope;
  for (int t = 0; t < ticks + 1000; ++t) {  // the first 1000 ticks warm up
    // Motors: reply (not timed).
    for (auto& r : replies) r.clear();
    for (std::size_t i = 0; i < n_motors; ++i) {
      const MitReply r{static_cast<std::uint8_t>(ctl->motor_id[i]), 0.001 * (t % 1000), 0.2, -0.5};
      reply_of[i] = MakeMitReplyFrame(ctl->reply_id[i], ctl->range[i], r);
      replies[ctl->motor_bus[i]].push_back(reply_of[i]);
    }
    for (int b = 0; b < 2; ++b) dbus[b]->Send(replies[b]);

    // Controller tick (timed): drain + decode, encode + send.
    const auto t0 = Clock::now();
    std::uint64_t decoded = 0;
    for (std::uint32_t b = 0; b < 2; ++b) {
      const std::size_t n = cbus[b]->Receive(rx);
      for (std::size_t k = 0; k < n; ++k)
        decoded += DispatchFrame(*ctl, b, rx[k], cdata, cbus[b]->stats()) == DispatchResult::kDecoded ? 1 : 0;
    }
    for (auto& c : commands) c.clear();
    for (std::size_t i = 0; i < n_motors; ++i) {
      const MitReply& s = cdata.reply[i];
      const MitCommand c{s.q_rad, 0.0, 30.0, 0.8, 0.1};
      commands[ctl->motor_bus[i]].push_back(MakeMitCommandFrame(ctl->motor_id[i], ctl->range[i], c));
    }
    std::size_t sent = 0;
    for (int b = 0; b < 2; ++b) sent += cbus[b]->Send(commands[b]);
    const auto t1 = Clock::now();

    // Motors: read commands (not timed).
    std::size_t got = 0;
    for (std::uint32_t b = 0; b < 2; ++b) {
      const std::size_t n = dbus[b]->Receive(rx);
      for (std::size_t k = 0; k < n; ++k) DispatchFrame(*dev, b, rx[k], ddata, dstats[b]);
      got += n;
    }
    if (t < 1000) continue;
    if (decoded != n_motors) ++incomplete;
    if (sent != n_motors || got != n_motors) ++lost_commands;
    tick_ns.push_back(static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()));

    // The pure codec part alone: decode 12 replies, encode 12 commands (no sockets).
    const auto c0 = Clock::now();
    for (std::size_t i = 0; i < n_motors; ++i) DispatchFrame(*ctl, ctl->motor_bus[i], reply_of[i], cdata, scratch);
    for (std::size_t i = 0; i < n_motors; ++i) {
      const MitCommand c{cdata.reply[i].q_rad, 0.0, 30.0, 0.8, 0.1};
      command_of[i] = MakeMitCommandFrame(ctl->motor_id[i], ctl->range[i], c);
    }
    asm volatile("" : : "r"(command_of.data()) : "memory");
    const auto c1 = Clock::now();
    codec_ns.push_back(static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(c1 - c0).count()));
  }
  const std::uint64_t allocations = scope.count();

  std::printf("CAN tick bench: %d ticks, %zu motors on %s + %s (%s)\n", ticks, n_motors, iface[0].c_str(),
              iface[1].c_str(), map_path.c_str());
  Print("tick (drain+decode, encode+send)", Summarise(tick_ns));
  Print("codec only (12 decode + 12 encode)", Summarise(codec_ns));
  std::printf("ticks with fewer than %zu replies decoded: %llu; ticks with commands lost: %llu\n", n_motors,
              static_cast<unsigned long long>(incomplete), static_cast<unsigned long long>(lost_commands));
  for (int b = 0; b < 2; ++b) {
    const BusStats& s = cbus[b]->stats();
    std::printf("%s: rx %llu tx %llu tx_dropped %llu rx_dropped %llu errors %llu unknown %llu wrong_len %llu\n",
                iface[b].c_str(), static_cast<unsigned long long>(s.rx_frames),
                static_cast<unsigned long long>(s.tx_frames), static_cast<unsigned long long>(s.tx_dropped),
                static_cast<unsigned long long>(s.rx_dropped_kernel),
                static_cast<unsigned long long>(s.error_frames + s.tx_errors + s.rx_errors),
                static_cast<unsigned long long>(s.unknown_ids), static_cast<unsigned long long>(s.wrong_lengths));
  }
  std::printf("heap allocations in the loop: %llu\n", static_cast<unsigned long long>(allocations));
  return allocations == 0 && lost_commands == 0 ? 0 : 1;
}
