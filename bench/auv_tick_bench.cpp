// Latency of the AUV controller's tick (observe -> infer -> supervise) with the shipped
// configuration and IO layout and a random-weight policy of the given hidden widths.
//
//   auv_tick_bench [--ticks N] [--hidden 64,64] [--json FILE] [--plot FILE.png]
//
// Prints the per-stage table of the controller's own profiler (median, p99, ..., max) and the
// allocations seen over the timed ticks.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "firmware/auv/auv_controller.hpp"
#include "report/plots.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/rt/tick_clock.hpp"

using namespace pbppo;

int main(int argc, char** argv) {
  long ticks = 100000;
  std::string hidden = "64,64", json, plot;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--ticks")
      ticks = std::atol(argv[i + 1]);
    else if (a == "--hidden")
      hidden = argv[i + 1];
    else if (a == "--json")
      json = argv[i + 1];
    else if (a == "--plot")
      plot = argv[i + 1];
    else {
      std::fprintf(stderr, "auv_tick_bench: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  const std::string src = PBPPO_SOURCE_DIR;
  auto config = firmware::LoadAuvControllerConfig(src + "/models/auv/auv.yaml");
  auto layout = robot::LoadIoLayout(src + "/models/auv/io_layout.yaml");
  if (!config || !layout) {
    std::fprintf(stderr, "auv_tick_bench: %s\n", (!config ? config.error() : layout.error()).message.c_str());
    return 1;
  }
  std::vector<std::uint32_t> widths{layout->observation_size()};
  std::stringstream ss(hidden);
  for (std::string w; std::getline(ss, w, ',');) widths.push_back(static_cast<std::uint32_t>(std::stoul(w)));
  widths.push_back(layout->action_size());
  policy::PolicySpec spec = policy::MakeRandomSpec(widths, policy::Activation::kTanh, 1);
  robot::ApplyLayoutToSpec(*layout, spec);
  auto model = policy::PolicyModel::FromSpec(spec);
  if (!model) return 1;
  auto c = firmware::AuvController::Create(*config, *layout, std::move(*model));
  if (!c) {
    std::fprintf(stderr, "auv_tick_bench: %s\n", c.error().message.c_str());
    return 1;
  }
  auto& ctl = **c;
  ctl.Arm();
  robot::AuvSensorSample s;
  s.sonar_beams = 16;
  s.depth_m = 5.0;
  s.target_distance_m = 20.0;
  robot::AuvCommand cmd;
  for (long k = 0; k < 1000; ++k) {  // warm-up, then measure from a clean profiler
    s.tick = static_cast<std::uint64_t>(k);
    ctl.Tick(&s, s.tick, cmd);
  }
  ctl.profiler().Reset();
  AllocationScope scope;
  for (long k = 0; k < ticks; ++k) {
    s.tick = static_cast<std::uint64_t>(k + 1000);
    for (std::uint32_t b = 0; b < 16; ++b) s.sonar_m[b] = static_cast<float>((k + b) % 15);
    s.yaw_rad = 0.001 * static_cast<double>(k % 3000) - 1.5;
    const std::int64_t t0 = rt::MonotonicNs();
    ctl.Tick(&s, s.tick, cmd);
    ctl.profiler().Record(rt::Stage::kTick, rt::MonotonicNs() - t0);
  }
  const std::uint64_t allocs = scope.count();
  const rt::ProfileReport r = rt::TakeReport(ctl.profiler());
  std::printf("AUV controller tick, policy %s, %ld ticks, allocations %llu\n%s", hidden.c_str(), ticks,
              static_cast<unsigned long long>(allocs), rt::FormatText(r).c_str());
  if (!json.empty()) std::ofstream(json) << rt::FormatJson(r);
  if (!plot.empty()) {
    if (auto st = report::PlotLatency(r, plot, "AUV controller tick"); !st)
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
  }
  return allocs == 0 ? 0 : 1;
}
