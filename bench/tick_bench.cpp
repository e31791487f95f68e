// Latency of one robot's loop tick (read -> check -> observe -> infer -> supervise -> write) over
// an in-memory transport, with the robot's own model: a random-weight policy of the given hidden
// widths when the robot has an IO layout, else its stand trajectory (or the default pose).
//
//   pbppo_bench_tick [--robot models/auv/robot.yaml] [--ticks N] [--hidden 64,64] [--json FILE]
//                    [--plot FILE.png]
//
// Every tick delivers a sample on every stream: motors answer with the commanded position (the
// default pose before), other fields vary inside their sample-check bounds (orientations
// upright). Prints the per-stage table of the loop's own profiler (median, p99, ..., max) and the
// allocations seen over the timed ticks (non-zero: exit 1); with a policy, its memory-read floor
// (its parameters streamed once, bench/read_floor.hpp) and the infer stage's median against it.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "bench/read_floor.hpp"
#include "report/plots.hpp"
#include "runtime/core/aligned_arena.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/clock.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/loop/trajectory_source.hpp"
#include "runtime/policy/blob.hpp"
#include "tests/support/scripted_transport.hpp"

using namespace pbppo;

namespace {

// A plausible value of every field at tick k: inside its bounds, an orientation upright.
void Inputs(const robot::RobotModel& m, const test::ScriptedTransport& t, std::uint64_t k, std::vector<double>& v) {
  for (std::size_t i = 0; i < m.fields.size(); ++i) {
    const robot::FieldSpec& f = m.fields[i];
    const bool quat = f.name.ends_with("_qx") || f.name.ends_with("_qy") || f.name.ends_with("_qz");
    const double x = f.name.ends_with("_qw") ? 1.0 : quat ? 0.0 : 0.5 * std::sin(0.001 * static_cast<double>(k) + i);
    v[i] = std::clamp(x, f.min, f.max);
  }
  for (std::size_t j = 0; j < m.motors.size(); ++j) {
    const robot::MotorSpec& mo = m.motors[j];
    const bool commanded = t.writes > 0 && t.motors[j] == robot::MotorCommand::kCommand;
    v[mo.q_field] = commanded ? t.command[mo.q] : mo.default_q_rad;
  }
}

// The time to stream `bytes` of parameters once with the faster plain reader: the median over
// 1001 samples of 16 reads each, timed with the clock the loop's profiler uses.
double ReadFloorNs(std::uint64_t bytes) {
  const std::size_t n = (bytes / sizeof(float) + 31) / 32 * 32;
  AlignedBlock block(n * sizeof(float));
  auto* p = reinterpret_cast<float*>(block.data());
  for (std::size_t i = 0; i < n; ++i) p[i] = 1e-3f;
  double best = 0;
  for (bench::StreamFn read : bench::StreamReaders()) {
    volatile float sink = 0;
    for (int w = 0; w < 1000; ++w) sink = sink + read(p, n);
    std::vector<double> ns(1001);
    for (double& t : ns) {
      const std::int64_t t0 = MonotonicNs();
      for (int r = 0; r < 16; ++r) sink = sink + read(p, n);
      t = static_cast<double>(MonotonicNs() - t0) / 16.0;
    }
    std::nth_element(ns.begin(), ns.begin() + 500, ns.end());
    if (best == 0 || ns[500] < best) best = ns[500];
  }
  return best;
}

int Fail(const std::string& msg) {
  std::fprintf(stderr, "pbppo_bench_tick: %s\n", msg.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbppo_bench_tick: one robot's loop tick over an in-memory transport"};
  std::string robot_path = std::string(PBPPO_SOURCE_DIR) + "/models/auv/robot.yaml", json, plot;
  std::vector<std::uint32_t> hidden{64, 64};
  std::uint64_t ticks = 100000;
  app.add_option("--robot", robot_path, "The robot (models/<robot>/robot.yaml)");
  app.add_option("--ticks", ticks, "Timed ticks")->check(CLI::Range(1, 100000000));
  app.add_option("--hidden", hidden, "Hidden widths of the random policy")->delimiter(',');
  app.add_option("--json", json, "Write the profile as JSON");
  app.add_option("--plot", plot, "Draw the latency histograms as PNG");
  CLI11_PARSE(app, argc, argv);

  auto loaded = robot::LoadRobotModel(robot_path);
  if (!loaded) return Fail(loaded.error().message);
  const robot::RobotModel& m = *loaded;
  std::unique_ptr<policy::PolicyModel> policy;
  std::unique_ptr<loop::CommandSource> source;
  std::string what = "no command source";
  if (m.io) {
    std::vector<std::uint32_t> widths{m.io->observation_size()};
    widths.insert(widths.end(), hidden.begin(), hidden.end());
    widths.push_back(m.io->action_size());
    policy::PolicySpec spec = policy::MakeRandomSpec(widths, policy::Activation::kTanh, 1);
    robot::ApplyLayoutToSpec(*m.io, spec);
    auto p = policy::PolicyModel::FromSpec(spec);
    if (!p) return Fail(p.error().message);
    policy = std::make_unique<policy::PolicyModel>(std::move(*p));
    auto s = loop::PolicySource::Create(m, *policy);
    if (!s) return Fail(s.error().message);
    source = std::move(*s);
    what = "a random policy";
  } else if (auto t = loop::RobotTrajectory(m); t) {
    t->duration_s = 1e9;  // the whole run
    source = std::make_unique<loop::TrajectorySource>(m, std::move(*t));
    what = "its stand trajectory";
  }
  robot::RobotData data = robot::MakeRobotData(m);
  auto l = loop::MakeLoopData(m, source.get());
  test::ScriptedTransport transport(m);
  robot::Transport* transports[] = {&transport};
  std::vector<double> values(m.fields.size(), 0.0);
  auto tick = [&](std::uint64_t k) {
    Inputs(m, transport, k, values);
    for (std::uint32_t s = 0; s < m.streams.size(); ++s) {
      const robot::StreamSpec& spec = m.streams[s];
      transport.Put(m, s, {values.data() + spec.first_field, spec.field_count});
    }
    rt::TickTiming timing;
    timing.tick = k;
    timing.wake_ns = timing.deadline_ns = MonotonicNs();
    (void)loop::Tick(m, data, *l, transports, timing);
  };
  l->Arm();
  std::uint64_t k = 0;
  for (; k < 5000 && l->phase() != loop::Phase::kRun; ++k) tick(k);  // arming, stand-up, hold
  if (l->phase() != loop::Phase::kRun) return Fail("the loop never reached the run phase");
  for (std::uint64_t end = k + 1000; k < end; ++k) tick(k);  // warm-up, then a clean profiler
  l->profiler().Reset();
  AllocationScope scope;
  for (std::uint64_t end = k + ticks; k < end; ++k) tick(k);
  const std::uint64_t allocs = scope.count();
  const rt::ProfileReport r = rt::TakeReport(l->profiler());
  const safety::SupervisorState& sup = l->supervisor();
  std::printf("%s loop tick with %s, %llu ticks, mode %s%s, allocations %llu\n%s", m.name.c_str(), what.c_str(),
              static_cast<unsigned long long>(ticks), safety::ToString(sup.mode),
              sup.mode == safety::Mode::kNominal
                  ? ""
                  : (" (" + safety::Describe(m.supervisor_model, sup.entered[static_cast<std::size_t>(sup.mode)]) + ")")
                        .c_str(),
              static_cast<unsigned long long>(allocs), rt::FormatText(r).c_str());
  if (policy) {
    const double floor_ns = ReadFloorNs(policy->parameter_bytes());
    const double infer_ns = static_cast<double>(r.stats[static_cast<std::size_t>(rt::Stage::kInfer)].p50_ns);
    std::printf(
        "infer stage median %.2f us; the policy's %.1f KB of parameters read once: %.2f us (the read floor); "
        "infer at %.1fx the floor\n",
        infer_ns / 1e3, static_cast<double>(policy->parameter_bytes()) / 1024.0, floor_ns / 1e3, infer_ns / floor_ns);
  }
  if (!json.empty()) std::ofstream(json) << rt::FormatJson(r);
  if (!plot.empty()) {
    if (auto st = report::PlotLatency(r, plot, m.name + " loop tick"); !st)
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
  }
  return allocs == 0 ? 0 : 1;
}
