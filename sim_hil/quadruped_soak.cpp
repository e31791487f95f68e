#include "sim_hil/quadruped_soak.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/random.hpp"
#include "runtime/loop/schedule.hpp"
#include "sim_hil/quadruped_rig.hpp"
#include "sim_hil/quadruped_scenario.hpp"

namespace pbppo::sim {
namespace {

using safety::Cause;
using safety::Mode;

constexpr std::size_t kKeptViolations = 100;

// Velocity commands: a stand, then phases of random commands (a fifth of them standing), long
// enough for the run.
std::string CommandSchedule(const SoakOptions& o, double total_s, Rng& rng, std::uint64_t* phases) {
  std::string s = "stream: velocity_command\nphases:\n  - {name: stand, duration_s: 2.0}\n";
  double t = 2.0;
  char line[200];
  for (std::uint64_t k = 0; t < total_s + 10.0; ++k) {
    const double d = rng.Uniform(o.command_phase_s[0], o.command_phase_s[1]);
    const bool stand = rng.Uniform() < 0.2;
    const double vx = stand ? 0.0 : rng.Uniform(-0.2, 0.5), vy = stand ? 0.0 : rng.Uniform(-0.2, 0.2),
                 wz = stand ? 0.0 : rng.Uniform(-0.4, 0.4);
    std::snprintf(line, sizeof line,
                  "  - {name: p%llu, duration_s: %.3f, command_vx: %.3f, command_vy: %.3f, command_yaw_rate: %.3f}\n",
                  static_cast<unsigned long long>(k), d, vx, vy, wz);
    s += line;
    t += d;
    ++*phases;
  }
  return s;
}

std::uint64_t Ticks(double s, double tick_s) {
  return static_cast<std::uint64_t>(std::llround(s / tick_s));
}

// The faults, and the HIL's events that start and end them (drawn at once: the schedule is data).
std::vector<SoakFault> DrawFaults(const robot::RobotModel& m, const SoakOptions& o, Rng& rng,
                                  std::vector<HilFault>* events) {
  const double tick_s = m.tick_period_s;
  const auto& sm = m.supervisor_model;
  const auto motor_stream = sm.streams[m.motors[0].stream];  // every motor has the robot file's motor limits
  const auto imu_stream = sm.streams[static_cast<std::size_t>(m.StreamIndex("base_imu"))];
  const auto op_index = static_cast<std::size_t>(m.StreamIndex("velocity_command"));
  const auto op_stream = sm.streams[op_index];
  const std::uint64_t op_period = Ticks(m.streams[op_index].period_s, tick_s);
  const std::size_t motors = m.can->motors.size(), buses = m.can->buses.size();
  std::vector<SoakFault> faults;
  // The kinds come from a bag of one of each, shuffled when empty: every kind once in every 7 faults.
  std::array<SoakFaultKind, kSoakFaultKinds> bag{};
  std::size_t left = 0;
  for (double t = o.first_fault_s; Ticks(t, tick_s) < o.ticks; t += rng.Uniform(o.spacing_s[0], o.spacing_s[1])) {
    if (left == 0) {
      for (std::size_t k = 0; k < bag.size(); ++k) bag[k] = static_cast<SoakFaultKind>(k);
      for (std::size_t k = bag.size() - 1; k > 0; --k) std::swap(bag[k], bag[rng.Next() % (k + 1)]);
      left = bag.size();
    }
    SoakFault f;
    f.kind = bag[--left];
    f.start = Ticks(t, tick_s);
    double d = 0.0;
    HilFault on, off;
    on.tick = f.start;
    switch (f.kind) {
      case SoakFaultKind::kSilentMotor:
        d = rng.Uniform(0.01, 0.3);
        f.subject = static_cast<int>(rng.Next() % motors);
        on.kind = HilFaultKind::kSilentMotor;
        off.kind = HilFaultKind::kMotorBack;
        on.motor = off.motor = f.subject;
        f.bound = motor_stream.stale_safe_stop_ticks + 1 + 3;
        break;
      case SoakFaultKind::kImuSilent:
        d = rng.Uniform(0.03, 0.3);
        on.kind = HilFaultKind::kImuSilent;
        off.kind = HilFaultKind::kImuBack;
        f.bound = imu_stream.stale_safe_stop_ticks + 1 + 3;
        break;
      case SoakFaultKind::kBusOff:
        d = rng.Uniform(0.01, 0.3);
        f.subject = static_cast<int>(rng.Next() % buses);
        on.kind = HilFaultKind::kBusOff;
        off.kind = HilFaultKind::kBusRestored;
        on.bus = off.bus = f.subject;
        f.bound = 3;
        break;
      case SoakFaultKind::kBadReplies:
        d = rng.Uniform(0.005, 0.1);
        f.subject = static_cast<int>(rng.Next() % motors);
        on.kind = HilFaultKind::kBadReplies;
        off.kind = HilFaultKind::kGoodReplies;
        on.motor = off.motor = f.subject;
        f.bound = 1 + 3;  // the reply of the next tick is checked
        break;
      case SoakFaultKind::kOperatorSilent:
        // Short silences (a few lost samples) only degrade; long ones stop the robot.
        if (rng.Uniform() < 0.3) {
          d = rng.Uniform(0.1, 0.35);
        } else {
          d = rng.Uniform(0.8, 2.5);
          f.bound = op_stream.stale_safe_stop_ticks + op_period + 3;
        }
        break;
      case SoakFaultKind::kDropFrames:
        d = rng.Uniform(1.0, 3.0);
        on.kind = off.kind = HilFaultKind::kDropFrames;
        on.probability = 0.1;
        on.max_burst = 2;
        off.probability = 0.0;
        break;
      case SoakFaultKind::kPush: {
        const double a = rng.Uniform(0.0, 6.283185307179586), v = rng.Uniform(0.2, 0.4);
        on.kind = HilFaultKind::kPush;
        on.velocity_mps[0] = v * std::cos(a);
        on.velocity_mps[1] = v * std::sin(a);
        d = tick_s;
        break;
      }
    }
    f.end = f.start + std::max<std::uint64_t>(1, Ticks(d, tick_s));
    off.tick = f.end;
    if (f.kind != SoakFaultKind::kOperatorSilent) events->push_back(on);
    if (f.kind != SoakFaultKind::kOperatorSilent && f.kind != SoakFaultKind::kPush) events->push_back(off);
    faults.push_back(f);
  }
  std::stable_sort(events->begin(), events->end(),
                   [](const HilFault& a, const HilFault& b) { return a.tick < b.tick; });
  return faults;
}

// Tilted beyond 60 degrees.
bool Fallen(const QuadrupedPlant& p) noexcept {
  const double* q = p.base().quat_wxyz;
  return 1 - 2 * (q[1] * q[1] + q[2] * q[2]) < 0.5;
}

class Judge {
 public:
  explicit Judge(SoakReport& r) : r_(r) {}
  __attribute__((format(printf, 3, 4))) void Violation(std::uint64_t tick, const char* fmt, ...) {
    ++r_.violation_count;
    if (r_.violations.size() >= kKeptViolations) return;
    char b[240];
    const int n = std::snprintf(b, sizeof b, "tick %llu: ", static_cast<unsigned long long>(tick));
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(b + n, sizeof b - static_cast<std::size_t>(n), fmt, args);
    va_end(args);
    r_.violations.emplace_back(b);
  }
  // A fault's outcome, once the next one begins (or the run ends at `now`).
  void Close(const SoakFault& f, std::uint64_t now, std::uint64_t healthy_ticks, bool fallen, bool run_ended) {
    if (!f.while_walking) return;
    const char* k = ToString(f.kind);
    const auto start = static_cast<unsigned long long>(f.start);
    if (f.bound > 0) {
      if (f.safe_tick < 0 || static_cast<std::uint64_t>(f.safe_tick) > f.start + f.bound)
        Violation(f.start, "%s from tick %llu: the safe state %s (bound: %llu ticks)", k, start,
                  f.safe_tick < 0 ? "never came" : "came too late", static_cast<unsigned long long>(f.bound));
    } else if (f.safe_tick >= 0) {
      Violation(static_cast<std::uint64_t>(f.safe_tick), "%s from tick %llu: stopped the robot (it must not)", k,
                start);
    }
    if (f.safe_tick < 0) return;
    if (f.rearm_tick < 0) {
      // Owed unless the robot fell, or the run ended before a recovery was possible.
      if (!fallen && !(run_ended && now < f.end + healthy_ticks + 3000))
        Violation(now, "%s from tick %llu: stopped at tick %lld and not re-armed", k, start,
                  static_cast<long long>(f.safe_tick));
    } else if (static_cast<std::uint64_t>(f.rearm_tick) < f.end + healthy_ticks) {
      Violation(static_cast<std::uint64_t>(f.rearm_tick),
                "%s from tick %llu to %llu: re-armed before the fault ended and %llu healthy ticks passed", k, start,
                static_cast<unsigned long long>(f.end), static_cast<unsigned long long>(healthy_ticks));
    }
  }

 private:
  SoakReport& r_;
};

}  // namespace

const char* ToString(SoakFaultKind kind) noexcept {
  switch (kind) {
    case SoakFaultKind::kSilentMotor: return "silent motor";
    case SoakFaultKind::kImuSilent: return "IMU silent";
    case SoakFaultKind::kBusOff: return "bus-off";
    case SoakFaultKind::kBadReplies: return "out-of-range replies";
    case SoakFaultKind::kOperatorSilent: return "operator silent";
    case SoakFaultKind::kDropFrames: return "frame drops";
    case SoakFaultKind::kPush: return "push";
  }
  return "?";
}

robot::RobotModel SoakModel(const robot::RobotModel& m, bool realtime) {
  robot::RobotModel r = m;
  robot::RecoverySpec& rec = r.supervisor.recovery;
  rec.automatic = true;
  rec.causes = 0;
  for (Cause c : {Cause::kStaleSample, Cause::kLostPeer, Cause::kTransportFault, Cause::kInvalidSample})
    rec.causes |= 1u << static_cast<unsigned>(c);
  if (realtime) rec.causes |= 1u << static_cast<unsigned>(Cause::kDeadlineOverrun);
  rec.max_automatic = 0xffffffffu;
  rec.healthy_s = 0.5;
  rec.healthy_ticks = static_cast<std::uint32_t>(std::llround(0.5 / m.tick_period_s));
  return r;
}

std::uint64_t ResidentKiB() noexcept {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char b[128] = {};
  const ssize_t n = ::read(fd, b, sizeof b - 1);
  ::close(fd);
  if (n <= 0) return 0;
  unsigned long long size = 0, resident = 0;
  if (std::sscanf(b, "%llu %llu", &size, &resident) != 2) return 0;
  return resident * static_cast<unsigned long long>(sysconf(_SC_PAGESIZE)) / 1024;
}

Result<SoakReport> RunQuadrupedSoak(const robot::RobotModel& shipped, const SoakOptions& o) {
  if (!shipped.can || shipped.StreamIndex("base_imu") < 0 || shipped.StreamIndex("velocity_command") < 0)
    return MakeError(ErrorCode::kMismatch, shipped.path +
                                               ": the soak needs a walking quadruped (CAN map, base_imu, "
                                               "velocity_command)");
  if (o.ticks == 0) return MakeError(ErrorCode::kInvalidValue, "soak: ticks must be > 0");
  const robot::RobotModel m = SoakModel(shipped, o.realtime);
  SoakReport r;
  Rng rng(o.seed);
  const double total_s = static_cast<double>(o.ticks) * m.tick_period_s;
  auto schedule = loop::ParseSchedule(CommandSchedule(o, total_s, rng, &r.command_phases), "soak schedule", m);
  if (!schedule) return std::move(schedule).error();
  auto scenario = LoadQuadrupedScenario(m.dir + "/scenarios/flat.yaml", m, m.tick_period_s);
  if (!scenario) return std::move(scenario).error();
  QuadrupedHilOptions hil = scenario->hil;
  r.faults = DrawFaults(m, o, rng, &hil.faults);
  hil.seed = o.seed;
  RigOptions ro;
  ro.policy = o.policy;
  ro.trace_every = o.trace_every;
  ro.realtime = o.realtime;
  auto made = QuadrupedRig::Make(m, std::move(hil), std::move(*schedule), ro);
  if (!made) return std::move(made).error();
  QuadrupedRig& rig = **made;
  loop::LoopData& l = rig.loop();
  const robot::RobotData& d = rig.data();
  std::unique_ptr<loop::Recorder> recorder;
  if (!o.record.empty()) {
    auto rec = loop::Recorder::Open(o.record, m, loop::MakeLogHeader(m, rig.source().kind, rig.source().hash),
                                    o.record_options);
    if (!rec) return std::move(rec).error();
    recorder = std::move(*rec);
    if (auto st = loop::AttachRecorder(m, d, l, recorder.get()); !st) return st.error();
  }
  const auto& limits = m.supervisor_model.commands;
  const std::uint64_t healthy = m.supervisor.recovery.healthy_ticks;
  std::array<rt::LatencyHistogram, 10> latency;
  Judge judge(r);
  r.mode_by_second.reserve(static_cast<std::size_t>(total_s) + 1);
  r.rss_kib.reserve(o.ticks / std::max<std::uint64_t>(1, o.rss_every) + 2);
  std::size_t next = 0;                  // the next fault to begin
  std::int64_t current = -1;             // the fault in force or last begun
  std::int64_t operator_off_until = -1;  // the operator is silent until this tick
  std::uint64_t rearms = 0;
  Mode mode = Mode::kNominal;
  bool fallen = false;
  std::uint8_t second_mode = 0;
  const std::uint64_t per_second = Ticks(1.0, m.tick_period_s);
  const auto t_start = std::chrono::steady_clock::now();
  l.Arm();
  rig.StartClock();
  for (std::uint64_t t = 0; t < o.ticks; ++t) {
    // A fault begins: the last one's outcome is known.
    if (next < r.faults.size() && r.faults[next].start == t) {
      if (current >= 0) judge.Close(r.faults[static_cast<std::size_t>(current)], t, healthy, fallen, false);
      SoakFault& f = r.faults[next];
      f.while_walking = l.phase() == loop::Phase::kRun && mode < Mode::kSafeStop;
      if (f.kind == SoakFaultKind::kOperatorSilent) {
        rig.operator_source().Kill();
        operator_off_until = static_cast<std::int64_t>(f.end);
      }
      current = static_cast<std::int64_t>(next++);
    }
    if (operator_off_until >= 0 && static_cast<std::int64_t>(t) == operator_off_until) {
      rig.operator_source().Revive();
      operator_off_until = -1;
    }
    // The controller's tick: timed (without the wait for its deadline), its allocations counted.
    {
      AllocationScope scope;
      rig.TickController();
      r.allocations += scope.count();
    }
    latency[static_cast<std::size_t>(t * 10 / o.ticks)].Record(rig.last_tick_ns());
    for (std::size_t k = 0; k < limits.size(); ++k) {
      const double c = d.command[k];
      if (!(std::isfinite(c) && c >= limits[k].min && c <= limits[k].max)) {
        ++r.commands_outside_limits;
        judge.Violation(t, "command '%s' = %g outside [%g, %g]", limits[k].name.c_str(), c, limits[k].min,
                        limits[k].max);
        break;
      }
    }
    // Stops and re-arms.
    const Mode now = l.supervisor().mode;
    if (now >= Mode::kSafeStop && mode < Mode::kSafeStop) ++r.stops;
    mode = now;
    if (current >= 0) {
      SoakFault& f = r.faults[static_cast<std::size_t>(current)];
      if (f.safe_tick < 0 && now >= Mode::kSafeStop) f.safe_tick = static_cast<std::int64_t>(t);
    }
    if (const loop::RecoveryStatus& rec = l.recovery(); rec.automatic != rearms) {
      rearms = rec.automatic;
      ++r.rearms;
      bool owed = false;
      for (std::int64_t k = current; k >= 0 && !owed; --k) {
        SoakFault& f = r.faults[static_cast<std::size_t>(k)];
        if (f.safe_tick >= 0 && f.rearm_tick < 0) {
          f.rearm_tick = static_cast<std::int64_t>(rec.last_tick);
          owed = true;
        }
      }
      if (!owed) judge.Violation(t, "re-armed with no fault that stopped the robot (%s)", rec.last);
    }
    // The plant's tick.
    if (!rig.TickPlant())
      return MakeError(ErrorCode::kInvalidValue, "soak: the plant failed at tick " + std::to_string(t));
    const bool f_now = Fallen(rig.hil().plant());
    if (f_now && !fallen) ++r.falls;
    fallen = f_now;
    second_mode = std::max(second_mode, static_cast<std::uint8_t>(now));
    if ((t + 1) % per_second == 0) {
      r.mode_by_second.push_back(second_mode);
      second_mode = 0;
    }
    if (o.rss_every != 0 && t % o.rss_every == 0) r.rss_kib.emplace_back(t, ResidentKiB());
    r.ticks = t + 1;
    if (o.progress_every != 0 && (t + 1) % o.progress_every == 0 && o.progress) o.progress(t + 1, r);
  }
  if (current >= 0) judge.Close(r.faults[static_cast<std::size_t>(current)], o.ticks, healthy, fallen, true);
  if (recorder) {
    if (auto st = recorder->Stop(); !st) r.record_error = st.error().message;
    r.records = recorder->records();
    r.records_dropped = recorder->dropped();
    r.record_files = recorder->files();
    r.record_files_deleted = recorder->files_deleted();
    (void)loop::AttachRecorder(m, d, l, nullptr);
  }
  r.rss_kib.emplace_back(o.ticks, ResidentKiB());
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  for (std::size_t k = 0; k < latency.size(); ++k) r.tick_latency[k] = latency[k].Snapshot().Stats();
  for (const loop::ModeChange& c : l.mode_changes())
    r.summary.push_back("mode change: tick " + std::to_string(c.tick) + ": " + c.reason);
  r.summary.push_back("mode changes: " + std::to_string(l.mode_change_count()) + ", phase changes " +
                      std::to_string(l.phase_change_count()));
  // Faults beyond the run's end are not part of it.
  while (!r.faults.empty() && r.faults.back().start >= o.ticks) r.faults.pop_back();
  return r;
}

}  // namespace pbppo::sim
