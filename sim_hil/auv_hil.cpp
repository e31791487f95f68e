#include "sim_hil/auv_hil.hpp"

#include <time.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "report/plots.hpp"
#include "runtime/core/clock.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"

namespace pbppo::sim {
namespace {

struct Row {
  double t_s, x_m, y_m, yaw_rad, v_cmd, w_cmd, u_mps, r_radps;
  int target;
  double clearance_m;
};

struct TargetEvent {
  int index;
  double t_s, x_m, y_m;
};

struct CollisionEvent {
  double t_s, x_m, y_m, clearance_m;
};

struct Recorder {
  std::vector<Row> rows;
  std::vector<TargetEvent> targets;
  std::vector<CollisionEvent> collisions;
  std::vector<double> fields;  // the sample as the robot model's fields

  void Record(const AuvNavTask& task, double v_cmd, double w_cmd) {
    const AuvState& s = task.vehicle();
    const AuvFieldIndex& i = task.config().fields;
    task.FillSensorFields(fields);
    rows.push_back(Row{s.time_s, s.x_m, s.y_m, fields[i.yaw], v_cmd, w_cmd, s.u_mps, s.r_radps, task.target_index(),
                       fields[i.clearance]});
  }
  void Events(const AuvNavTask& task, const AuvStepResult& r) {
    const AuvState& s = task.vehicle();
    if (r.events.target_reached >= 0) targets.push_back(TargetEvent{r.events.target_reached, s.time_s, s.x_m, s.y_m});
    if (r.events.collision) {
      task.FillSensorFields(fields);
      collisions.push_back(CollisionEvent{s.time_s, s.x_m, s.y_m, fields[task.config().fields.clearance]});
    }
  }
};

// What the vehicle counts of the commands it takes.
struct CommandCounters {
  std::uint64_t received = 0, invalid = 0, dropped_full = 0, written = 0;
};

Status WriteTrajectory(const std::string& path, const std::vector<Row>& rows) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return MakeError(ErrorCode::kIo, "--trajectory '" + path + "': cannot write");
  std::fprintf(f, "t_s,x_m,y_m,yaw_rad,v_cmd_mps,w_cmd_radps,u_mps,r_radps,target,clearance_m\n");
  for (const Row& r : rows)
    std::fprintf(f, "%.3f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%.9g\n", r.t_s, r.x_m, r.y_m, r.yaw_rad, r.v_cmd,
                 r.w_cmd, r.u_mps, r.r_radps, r.target, r.clearance_m);
  if (std::fclose(f) != 0) return MakeError(ErrorCode::kIo, "--trajectory '" + path + "': write failed");
  return {};
}

struct RunSummary {
  AuvHilOutcome outcome = AuvHilOutcome::kError;
  std::uint64_t ticks = 0, applied = 0, ignored = 0, overruns = 0, faulty_samples = 0;
  CommandCounters link;
  double wall_s = 0;
};

Status WriteEvents(const std::string& path, const AuvHilOptions& o, const AuvNavTask& task, const Recorder& rec,
                   const RunSummary& sum) {
  std::ofstream f(path);
  if (!f) return MakeError(ErrorCode::kIo, "--events '" + path + "': cannot write");
  const AuvEpisodeStats& st = task.stats();
  f << "{\n  \"layout\": \"" << o.layout << "\",\n  \"seed\": " << o.seed << ",\n  \"mode\": \""
    << (o.lockstep ? "lockstep" : "realtime") << "\",\n  \"outcome\": \"" << ToString(sum.outcome)
    << "\",\n  \"targets_reached\": [";
  for (std::size_t i = 0; i < rec.targets.size(); ++i) {
    const auto& e = rec.targets[i];
    f << (i ? ", " : "") << "{\"index\": " << e.index << ", \"t_s\": " << e.t_s << ", \"x_m\": " << e.x_m
      << ", \"y_m\": " << e.y_m << "}";
  }
  f << "],\n  \"collisions\": [";
  for (std::size_t i = 0; i < rec.collisions.size(); ++i) {
    const auto& e = rec.collisions[i];
    f << (i ? ", " : "") << "{\"t_s\": " << e.t_s << ", \"x_m\": " << e.x_m << ", \"y_m\": " << e.y_m
      << ", \"clearance_m\": " << e.clearance_m << "}";
  }
  f << "],\n  \"steps\": " << st.steps << ",\n  \"time_s\": " << st.time_s
    << ",\n  \"episode_return\": " << st.episode_return << ",\n  \"min_clearance_m\": " << st.min_clearance_m
    << ",\n  \"random_obstacles\": " << st.random_obstacles << ",\n  \"commands\": {\"applied\": " << sum.applied
    << ", \"ignored\": " << sum.ignored << ", \"received\": " << sum.link.received
    << ", \"invalid\": " << sum.link.invalid << ", \"dropped_full\": " << sum.link.dropped_full
    << "},\n  \"faulty_samples\": " << sum.faulty_samples << ",\n  \"samples_written\": " << sum.link.written
    << ",\n  \"overruns\": " << sum.overruns << "\n}\n";
  if (!f.good()) return MakeError(ErrorCode::kIo, "--events '" + path + "': write failed");
  return {};
}

// The trajectory over the layout: walls, boxes and circles (fixed and this episode's random ones),
// targets numbered with their acceptance circles, the start point.
Status WritePlot(const AuvHilOptions& o, const AuvTaskConfig& cfg, const AuvNavTask& task, AuvHilOutcome outcome,
                 const std::vector<Row>& rows) {
  const World2d& w = task.world();
  report::MapPlot m;
  m.title = "AUV HIL: layout " + o.layout + ", seed " + std::to_string(o.seed) + ", " + ToString(outcome);
  m.arena = {w.arena.x_min_m, w.arena.x_max_m, w.arena.y_min_m, w.arena.y_max_m};
  for (const Box& b : w.boxes) m.boxes.push_back({b.x_min_m, b.x_max_m, b.y_min_m, b.y_max_m});
  const std::size_t fixed = cfg.layout.world.circles.size();
  for (std::size_t i = 0; i < w.circles.size(); ++i)
    (i < fixed ? m.obstacles : m.random_obstacles)
        .push_back({w.circles[i].x_m, w.circles[i].y_m, w.circles[i].radius_m});
  for (const auto& t : cfg.layout.targets) m.targets.push_back({t[0], t[1]});
  m.target_radius_m = cfg.task.target_radius_m;
  m.paths.emplace_back();
  for (const Row& r : rows) m.paths.back().xy.push_back({r.x_m, r.y_m});
  if (auto s = report::PlotMap(m, o.plot_png); !s) return MakeError(s.error().code, "--plot: " + s.error().message);
  return {};
}

}  // namespace

const char* ToString(AuvHilOutcome o) noexcept {
  switch (o) {
    case AuvHilOutcome::kSuccess: return "success";
    case AuvHilOutcome::kCollision: return "collision";
    case AuvHilOutcome::kTimeLimit: return "time_limit";
    case AuvHilOutcome::kMaxTime: return "max_time";
    case AuvHilOutcome::kStopped: return "stopped";
    case AuvHilOutcome::kControllerLost: return "controller_lost";
    case AuvHilOutcome::kError: return "error";
  }
  return "?";
}

namespace {

// The vehicle's side of the robot's DDS transport (the robot file's messages, as the peer): the
// sensor sample out, the controller's commands in (every one, in order) and its status.
class VehicleLink {
 public:
  static Result<VehicleLink> Open(const robot::RobotModel& model, const AuvHilOptions& o) {
    VehicleLink v;
    const int stream = model.StreamIndex("sensor");
    if (stream < 0) return MakeError(ErrorCode::kMismatch, model.path + ": no stream 'sensor' for the vehicle");
    const std::string& transport = model.streams[static_cast<std::size_t>(stream)].transport;
    dds::DdsLinkOptions lo;
    lo.domain_id = o.domain_id;
    auto naming = dds::ParseDdsNaming(o.dds_naming);
    if (!naming) return std::move(naming).error();
    lo.naming = *naming;
    lo.security = {o.dds_security, o.dds_identity};
    auto link = dds::DdsLink::Open(model, transport, dds::DdsSide::kPeer, lo);
    if (!link) return std::move(link).error();
    v.link_ = std::move(*link);
    for (std::size_t i = 0; i < v.link_->message_count(); ++i) {
      const robot::DdsMessageSpec& m = v.link_->message(i);
      if (m.direction == robot::MessageDirection::kIn && m.stream == static_cast<std::uint32_t>(stream)) v.sensor_ = i;
      if (m.direction == robot::MessageDirection::kOut) v.command_ = i;
    }
    const robot::DdsMessageSpec& cmd = v.link_->message(v.command_);
    using K = robot::ValueTerm::Kind;
    const int tick = model.FieldIndex("tick"), surge = model.CommandIndex("surge_speed"),
              yaw = model.CommandIndex("yaw_rate");
    v.answers_ = tick < 0 ? -1 : v.link_->LeafOf(v.command_, K::kField, static_cast<std::uint32_t>(tick));
    v.surge_ = surge < 0 ? -1 : v.link_->LeafOf(v.command_, K::kCommand, static_cast<std::uint32_t>(surge));
    v.yaw_rate_ = yaw < 0 ? -1 : v.link_->LeafOf(v.command_, K::kCommand, static_cast<std::uint32_t>(yaw));
    v.mode_ = v.link_->LeafOf(v.command_, K::kMode);
    if (v.link_->message(v.command_).direction != robot::MessageDirection::kOut || v.answers_ < 0 || v.surge_ < 0 ||
        v.yaw_rate_ < 0)
      return MakeError(ErrorCode::kMismatch, model.path + ": transport '" + transport +
                                                 "' has no command message carrying field.tick, command.surge_speed "
                                                 "and command.yaw_rate");
    v.stamp_ = v.link_->message(v.sensor_).type.LeafIndex("stamp_ns");
    v.sample_.emplace(v.link_->message(v.sensor_).type);
    v.command_sample_.emplace(cmd.type);
    return v;
  }

  bool WaitForPeer(std::int64_t timeout_ns) { return link_->WaitForPeer(timeout_ns); }
  Status Publish(std::span<const double> fields, double time_s) {
    link_->FillFromFields(sensor_, fields, &*sample_);
    if (stamp_ >= 0) sample_->Set(static_cast<std::uint32_t>(stamp_), std::round(time_s * 1e9));
    return link_->writer(sensor_)->Write(sample_->bytes());
  }
  // The next command (false: none within timeout_ns); checked: non-finite set-points, a mode
  // above e-stop or set-points no vehicle takes are counted as invalid.
  bool NextCommand(std::int64_t timeout_ns, std::uint64_t* answers, double* v, double* w) {
    dds::DdsReader& r = *link_->reader(command_);
    const bool got = timeout_ns > 0 ? r.WaitPop(command_sample_->bytes(), nullptr, timeout_ns)
                                    : r.Pop(command_sample_->bytes(), nullptr);
    if (!got) return false;
    const dds::DdsSample& c = *command_sample_;
    *answers = static_cast<std::uint64_t>(c.Get(static_cast<std::uint32_t>(answers_)));
    *v = c.Get(static_cast<std::uint32_t>(surge_));
    *w = c.Get(static_cast<std::uint32_t>(yaw_rate_));
    const double mode = mode_ >= 0 ? c.Get(static_cast<std::uint32_t>(mode_)) : 0.0;
    if (!std::isfinite(*v) || !std::isfinite(*w) || mode > 3 || std::abs(*v) > 20 || std::abs(*w) > 20) ++invalid_;
    return true;
  }
  void Flush(std::int64_t timeout_ns) { (void)link_->Flush(timeout_ns); }
  CommandCounters counters() const {
    CommandCounters c;
    const dds::DdsReaderCounters in = link_->reader(command_)->counters();
    c.received = in.received;
    c.invalid = invalid_;
    c.dropped_full = in.dropped;
    c.written = link_->writer(sensor_)->counters().written;
    return c;
  }

 private:
  std::unique_ptr<dds::DdsLink> link_;
  std::size_t sensor_ = 0, command_ = 0;
  int answers_ = -1, surge_ = -1, yaw_rate_ = -1, mode_ = -1, stamp_ = -1;
  std::optional<dds::DdsSample> sample_, command_sample_;
  std::uint64_t invalid_ = 0;
};

}  // namespace

int RunAuvHil(const AuvHilOptions& o, const std::atomic<bool>& stop) {
  auto fail = [](const std::string& why) {
    std::fflush(stdout);
    std::fprintf(stderr, "pbppo-hil auv: %s\n", why.c_str());
    return 1;
  };
  auto model = robot::LoadRobotModel(o.robot);
  if (!model) return fail(model.error().message);
  auto cfg = MakeAuvTaskConfig(*model, o.layout);
  if (!cfg) return fail(cfg.error().message);
  auto task_r = AuvNavTask::Create(*cfg);
  if (!task_r) return fail(task_r.error().message);
  AuvNavTask& task = *task_r;
  // The plot needs the trajectory file; write it beside the picture when none was asked for.
  AuvHilOptions opt = o;
  if (!opt.plot_png.empty() && opt.trajectory_csv.empty()) opt.trajectory_csv = opt.plot_png + ".csv";
  auto link_r = VehicleLink::Open(*model, o);
  if (!link_r) return fail(link_r.error().message);
  VehicleLink& link = *link_r;

  std::vector<float> obs(static_cast<std::size_t>(task.observation_size()));
  task.Reset(o.seed, obs.data());
  const double period_s = task.control_period_s();
  const auto period_ns = static_cast<std::int64_t>(std::llround(period_s * 1e9));
  const long max_ticks =
      o.max_time_s > 0 ? static_cast<long>(std::ceil(o.max_time_s / period_s - 1e-9)) : task.max_episode_steps();

  std::printf("pbppo-hil auv: layout %s, seed %llu, %s, domain %d, %d random obstacles; waiting for the controller\n",
              o.layout.c_str(), static_cast<unsigned long long>(o.seed), o.lockstep ? "lock-step" : "real-time",
              o.domain_id, task.stats().random_obstacles);
  std::fflush(stdout);

  RunSummary sum;
  Recorder rec;
  rec.fields.assign(model->fields.size(), 0.0);
  rec.rows.reserve(static_cast<std::size_t>(std::min<long>(max_ticks, task.max_episode_steps())) + 1);
  const auto t0 = std::chrono::steady_clock::now();
  // Wait for the controller: its sensor reader matched to our writer and its command writer to our reader.
  bool peer = false;
  for (double waited = 0; !peer && waited < o.peer_timeout_s && !stop.load(); waited += 0.1)
    peer = link.WaitForPeer(kNsPerS / 10);
  if (!peer) {
    sum.outcome = stop.load() ? AuvHilOutcome::kStopped : AuvHilOutcome::kControllerLost;
    if (!stop.load())
      return fail("no controller matched on domain " + std::to_string(o.domain_id) + " within " +
                  std::to_string(o.peer_timeout_s) + " s");
  }

  const AuvFieldIndex& fi = cfg->fields;
  std::vector<double> fields(model->fields.size(), 0.0);
  double v_cmd = 0, w_cmd = 0;
  std::uint64_t tick = 0;
  auto publish = [&](bool last) -> bool {
    task.FillSensorFields(fields);
    fields[fi.tick] = static_cast<double>(tick);
    if (last) fields[fi.episode_end] = 1.0;
    const double t_s = task.vehicle().time_s;
    if (!o.fault.empty() && t_s >= o.fault_time_s && t_s < o.fault_time_s + o.fault_duration_s) {
      ++sum.faulty_samples;
      if (o.fault == "nan") {
        fields[fi.yaw] = std::nan("");
        fields[fi.surge] = std::nan("");
      } else {
        fields[fi.surge] = 99.0;
      }
    }
    auto st = link.Publish(fields, task.vehicle().time_s);
    if (!st)
      std::fprintf(stderr, "pbppo-hil auv: sensor sample write failed (tick %llu): %s\n",
                   static_cast<unsigned long long>(tick), st.error().message.c_str());
    return st.ok();
  };
  bool io_ok = true;
  if (peer) {
    rec.Record(task, 0.0, 0.0);
    io_ok = publish(false);
    timespec next{};
    clock_gettime(CLOCK_MONOTONIC, &next);
    while (io_ok) {
      if (stop.load()) {
        sum.outcome = AuvHilOutcome::kStopped;
        break;
      }
      bool have = false;
      std::uint64_t answers = 0;
      double v = 0, w = 0;
      if (o.lockstep) {
        // The command answering the sample of `tick`; others are counted and ignored.
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.command_timeout_s);
        while (!have && !stop.load() && std::chrono::steady_clock::now() < deadline) {
          if (!link.NextCommand(kNsPerS / 10, &answers, &v, &w)) continue;
          if (answers == tick)
            have = true;
          else
            ++sum.ignored;
        }
        if (stop.load()) continue;
        if (!have) {
          sum.outcome = AuvHilOutcome::kControllerLost;
          break;
        }
        v_cmd = v;
        w_cmd = w;
      } else {
        AddNs(&next, period_ns);
        timespec now{};
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (now.tv_sec > next.tv_sec || (now.tv_sec == next.tv_sec && now.tv_nsec > next.tv_nsec)) ++sum.overruns;
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
        while (link.NextCommand(0, &answers, &v, &w)) {
          have = true;
          v_cmd = v;
          w_cmd = w;
        }
      }
      if (have) ++sum.applied;
      const AuvStepResult r = task.StepCommand(v_cmd, w_cmd, obs.data());
      ++tick;
      rec.Record(task, task.commanded_speed_mps(), task.commanded_yaw_rate_radps());
      rec.Events(task, r);
      const bool max_time = static_cast<long>(tick) >= max_ticks && !r.terminated && !r.truncated;
      const bool end = r.terminated || r.truncated || max_time;
      io_ok = publish(end);
      if (end) {
        sum.outcome = task.stats().success    ? AuvHilOutcome::kSuccess
                      : task.stats().collided ? AuvHilOutcome::kCollision
                      : r.truncated           ? AuvHilOutcome::kTimeLimit
                                              : AuvHilOutcome::kMaxTime;
        break;
      }
    }
    link.Flush(kNsPerS);  // the last sample reaches the controller before we leave
  }
  sum.ticks = tick;
  sum.link = link.counters();
  sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!io_ok) sum.outcome = AuvHilOutcome::kError;

  const AuvEpisodeStats& st = task.stats();
  std::printf(
      "pbppo-hil auv: %s after %.1f s simulated (%llu ticks, %.2f s wall): %d/%zu targets, return %.1f, min clearance "
      "%.2f m\n  commands: applied %llu, ignored %llu, received %llu, invalid %llu; samples written %llu; overruns "
      "%llu\n",
      ToString(sum.outcome), st.time_s, static_cast<unsigned long long>(sum.ticks), sum.wall_s, st.targets_reached,
      cfg->layout.targets.size(), st.episode_return, st.min_clearance_m, static_cast<unsigned long long>(sum.applied),
      static_cast<unsigned long long>(sum.ignored), static_cast<unsigned long long>(sum.link.received),
      static_cast<unsigned long long>(sum.link.invalid), static_cast<unsigned long long>(sum.link.written),
      static_cast<unsigned long long>(sum.overruns));
  for (const auto& e : rec.targets) std::printf("  target %d reached at %.1f s\n", e.index + 1, e.t_s);
  for (const auto& e : rec.collisions)
    std::printf("  collision at %.1f s at (%.2f, %.2f), clearance %.2f m\n", e.t_s, e.x_m, e.y_m, e.clearance_m);

  int rc = (sum.outcome == AuvHilOutcome::kError || sum.outcome == AuvHilOutcome::kControllerLost) ? 1 : 0;
  std::fflush(stdout);
  if (sum.outcome == AuvHilOutcome::kControllerLost)
    std::fprintf(stderr, "pbppo-hil auv: no command answering tick %llu within %.1f s\n",
                 static_cast<unsigned long long>(tick), o.command_timeout_s);
  if (!opt.trajectory_csv.empty())
    if (auto s = WriteTrajectory(opt.trajectory_csv, rec.rows); !s) rc = fail(s.error().message);
  if (!opt.events_json.empty())
    if (auto s = WriteEvents(opt.events_json, opt, task, rec, sum); !s) rc = fail(s.error().message);
  if (!opt.plot_png.empty()) {
    if (auto s = WritePlot(opt, *cfg, task, sum.outcome, rec.rows); !s)
      rc = fail(s.error().message);
    else
      std::printf("  plot: %s\n", opt.plot_png.c_str());
  }
  std::fflush(stdout);
  return rc;
}

}  // namespace pbppo::sim
