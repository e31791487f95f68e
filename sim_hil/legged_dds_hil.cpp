#include "sim_hil/legged_dds_hil.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <optional>

#include <nlohmann/json.hpp>

#include "runtime/core/clock.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "sim_hil/plants/quadruped_plant.hpp"
#include "sim_hil/quadruped_rig.hpp"

namespace pbppo::sim {

bool ParseLeggedDdsFault(const std::string& text, LeggedDdsFault* out, std::string* error) {
  LeggedDdsFault f;
  const auto at = text.find('@');
  f.kind = text.substr(0, at);
  const char* p = at == std::string::npos ? nullptr : text.c_str() + at + 1;
  char* end = nullptr;
  bool ok = p != nullptr && (f.kind == "stop" || f.kind == "crc" || f.kind == "nan" || f.kind == "range" ||
                             f.kind == "lost" || f.kind == "silent");
  if (ok) {
    f.start_s = std::strtod(p, &end);
    ok = end != p && std::isfinite(f.start_s) && f.start_s >= 0;
  }
  if (ok && *end == '+') {
    const char* from = end + 1;
    f.duration_s = std::strtod(from, &end);
    ok = end != from && std::isfinite(f.duration_s) && f.duration_s > 0;
  }
  if (ok && *end == ':') {
    const char* from = end + 1;
    const long m = std::strtol(from, &end, 10);
    ok = end != from && m >= 0 && m < 64;
    f.motor = static_cast<int>(m);
  }
  if (!ok || *end != '\0') {
    *error = "'" + text + "' is not KIND@SECONDS[+DURATION][:MOTOR] with KIND stop, crc, nan, range, lost or silent";
    return false;
  }
  *out = f;
  return true;
}

namespace {

constexpr double kPosStop = 2.146e9, kVelStop = 16000.0;  // the SDK's "no position / velocity term"

int Fail(const std::string& why) {
  std::fflush(stdout);
  std::fprintf(stderr, "pbppo-hil go2: %s\n", why.c_str());
  return 1;
}

// One motor's command as the command message carries it, and where it sits.
struct MotorLeaves {
  int mode = -1, q = -1, dq = -1, kp = -1, kd = -1, tau = -1;
};
struct MotorCmd {
  double mode = 0, q = 0, dq = 0, kp = 0, kd = 0, tau = 0;
};

struct FaultOutcome {
  std::uint64_t start_period = 0;
  std::int64_t stopped_after = -1;  // periods from the fault's start to damping or passive; -1: never
  bool began = false;
};

}  // namespace

int RunLeggedDdsHil(const LeggedDdsHilOptions& o, const std::atomic<bool>& stop) {
  auto model_r = robot::LoadRobotModel(o.robot);
  if (!model_r) return Fail(model_r.error().message);
  const robot::RobotModel& m = *model_r;
  if (!m.body || m.motors.empty()) return Fail(m.path + ": the robot has no description or no motors");
  const std::string& transport = m.streams[m.motors.front().stream].transport;
  // The state message (the one that carries the motors' streams) and the command message.
  dds::DdsLinkOptions lo;
  lo.domain_id = o.domain_id;
  auto link_r = dds::DdsLink::Open(m, transport, dds::DdsSide::kPeer, lo);
  if (!link_r) return Fail(link_r.error().message);
  dds::DdsLink& link = **link_r;
  int state = -1, command = -1;
  for (std::size_t i = 0; i < link.message_count(); ++i) {
    const robot::DdsMessageSpec& msg = link.message(i);
    if (msg.direction == robot::MessageDirection::kIn &&
        std::count(msg.streams.begin(), msg.streams.end(), m.motors.front().stream) > 0)
      state = static_cast<int>(i);
    if (msg.direction == robot::MessageDirection::kOut) command = static_cast<int>(i);
  }
  if (state < 0 || command < 0)
    return Fail(m.path + ": transport '" + transport + "' has no in message with the motors or no out message");
  using K = robot::ValueTerm::Kind;
  const std::size_t n = m.motors.size();
  std::vector<MotorLeaves> leaves(n);
  for (std::size_t k = 0; k < n; ++k) {
    const robot::MotorSpec& mo = m.motors[k];
    MotorLeaves& l = leaves[k];
    const auto cmd = [&](std::uint32_t c) {
      return c == robot::kNoCommand ? -1 : link.LeafOf(static_cast<std::size_t>(command), K::kCommand, c);
    };
    l.mode = link.LeafOf(static_cast<std::size_t>(command), K::kMotorOn, static_cast<std::uint32_t>(k));
    l.q = cmd(mo.q), l.dq = cmd(mo.dq), l.kp = cmd(mo.kp), l.kd = cmd(mo.kd), l.tau = cmd(mo.tau);
    if (l.q < 0 || l.dq < 0 || l.kp < 0 || l.kd < 0 || l.tau < 0)
      return Fail(m.path + ": the command message does not carry every command of motor '" + mo.joint +
                  "' alone in a member (q_des_, dq_des_, kp_, kd_, tau_ff_)");
  }
  const robot::RobotDescription& body = *m.body;
  std::vector<std::size_t> joint(n);
  for (std::size_t k = 0; k < n; ++k)
    joint[k] = static_cast<std::size_t>(std::find(body.joint_names.begin(), body.joint_names.end(), m.motors[k].joint) -
                                        body.joint_names.begin());
  const auto imu = std::find_if(m.streams.begin(), m.streams.end(),
                                [](const robot::StreamSpec& s) { return s.kind == robot::StreamKind::kImu; });
  if (imu == m.streams.end()) return Fail(m.path + ": the robot has no IMU");
  const int tick_field = m.FieldIndex("tick");
  std::vector<int> foot_field;
  for (int i = 0; m.FieldIndex("foot_force_" + std::to_string(i)) >= 0; ++i)
    foot_field.push_back(m.FieldIndex("foot_force_" + std::to_string(i)));
  for (const LeggedDdsFault& f : o.faults) {
    if (f.motor >= static_cast<int>(n))
      return Fail("--fault " + f.kind + ": motor " + std::to_string(f.motor) + ", the robot has " + std::to_string(n));
    if (f.kind == "lost" && m.motors[static_cast<std::size_t>(f.motor)].lost_field < 0)
      return Fail("--fault lost: motor " + std::to_string(f.motor) + " (" +
                  m.motors[static_cast<std::size_t>(f.motor)].joint + ") reports no lost frames in " + m.path +
                  " (motors.lost_per_sample_max)");
  }

  // The schedule the controller plays: the commands per phase of the report.
  std::optional<loop::Schedule> schedule;
  std::vector<std::size_t> columns;
  if (!o.commands.empty()) {
    auto s = loop::LoadSchedule(o.commands, m);
    if (!s) return Fail(s.error().message);
    auto c = s->Columns(m, {"command_vx", "command_vy", "command_yaw_rate"});
    if (!c) return Fail(c.error().message);
    schedule = std::move(*s);
    columns = *c;
  }

  // The remote's schedule: a stream the state message fills.
  std::optional<loop::Schedule> remote;
  if (!o.remote.empty()) {
    auto s = loop::LoadSchedule(o.remote, m);
    if (!s) return Fail(s.error().message);
    const auto& carried = link.message(static_cast<std::size_t>(state)).streams;
    if (std::count(carried.begin(), carried.end(), s->stream_index) == 0)
      return Fail("--remote " + o.remote + ": stream '" + s->stream + "' is not carried by the state message");
    remote = std::move(*s);
  }

  // The plant on flat ground at the default pose, dropped from the training's start height.
  QuadrupedPlantOptions po;
  po.tick_s = 0.001;
  po.substeps = 4;
  po.mount = Mount::kGround;
  auto plant_r = QuadrupedPlant::Make(body, po);
  if (!plant_r) return Fail(plant_r.error().message);
  QuadrupedPlant& plant = **plant_r;
  double base_xyz[3] = {0, 0, 0.4};
  if (auto task = m.Document("walk_task"); task && (*task)->yaml["simulation"]["init_base_height_m"])
    base_xyz[2] = (*task)->yaml["simulation"]["init_base_height_m"].as<double>();
  if (auto st = plant.Reset(body.default_q_rad, std::vector<double>(body.joint_count(), 0.0), base_xyz); !st)
    return Fail(st.error().message);
  const double period_s = m.tick_period_s;
  const int plant_ticks = std::max(1, static_cast<int>(std::lround(period_s / po.tick_s)));
  const double end_s = o.duration_s > 0 ? o.duration_s : schedule ? schedule->duration_s() + 3.0 : 1e300;

  double mass_kg = 0;
  for (const robot::UrdfLink& l : body.urdf.links) mass_kg += l.has_inertial ? l.inertial.mass_kg : 0.0;
  const double weight_n = mass_kg * po.gravity_m_s2;
  std::printf("pbppo-hil go2: %s, %zu motors, %s, domain %d, state every %.1f ms; waiting for the controller\n",
              m.name.c_str(), n, o.lockstep ? "lock-step" : "real-time", o.domain_id, period_s * 1e3);
  std::fflush(stdout);
  bool peer = false;
  for (double waited = 0; !peer && waited < o.peer_timeout_s && !stop.load(); waited += 0.1)
    peer = link.WaitForPeer(kNsPerS / 10);
  if (!peer) return stop.load() ? 0 : Fail("no controller on domain " + std::to_string(o.domain_id));

  dds::DdsSample state_sample(link.message(static_cast<std::size_t>(state)).type);
  dds::DdsSample command_sample(link.message(static_cast<std::size_t>(command)).type);
  const std::uint32_t crc_leaf = link.message(static_cast<std::size_t>(state)).checksum.leaf;
  const bool has_crc = link.message(static_cast<std::size_t>(state)).checksum.present;
  std::vector<double> fields(m.fields.size(), 0.0);
  std::vector<MotorCmd> cmd(n);
  std::vector<double> tau(body.joint_count(), 0.0);
  std::vector<RigSample> trace;
  std::vector<FaultOutcome> outcome(o.faults.size());
  std::uint64_t period = 0, published = 0, answered = 0, bad_crc = 0, out_of_limits = 0, faulty_samples = 0;
  std::string first_violation;
  const auto t0 = std::chrono::steady_clock::now();
  bool plant_ok = true, controller_left = false, controller_lost = false, getting_up = true;

  const auto active = [&](const LeggedDdsFault& f, double t) { return t >= f.start_s && t < f.start_s + f.duration_s; };
  // A motor that stops answering: what it reported last (q, dq, tau), held while the fault lasts.
  std::vector<std::optional<std::array<double, 3>>> held(o.faults.size());
  const auto silent = [&](std::size_t motor, double t) {
    return std::any_of(o.faults.begin(), o.faults.end(), [&](const LeggedDdsFault& f) {
      return f.kind == "silent" && static_cast<std::size_t>(f.motor) == motor && active(f, t);
    });
  };
  const auto publish = [&](double t) {
    bool skip = false, corrupt = false;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t j = joint[k];
      fields[m.motors[k].q_field] = plant.q_rad(j);
      fields[m.motors[k].dq_field] = plant.dq_rad_s(j);
      fields[m.motors[k].tau_field] = plant.tau_nm(j);
      if (m.motors[k].lost_field >= 0) fields[static_cast<std::size_t>(m.motors[k].lost_field)] = 0.0;
    }
    double q[4], g[3], a[3];
    plant.BaseImu(q, g, a);
    for (int k = 0; k < 4; ++k) fields[imu->first_field + static_cast<std::uint32_t>(k)] = q[k];
    for (int k = 0; k < 3; ++k) fields[imu->first_field + 4 + static_cast<std::uint32_t>(k)] = g[k];
    for (int k = 0; k < 3; ++k) fields[imu->first_field + 7 + static_cast<std::uint32_t>(k)] = a[k];
    // Foot force sensors: the robot's weight shared by the feet on the ground (N).
    const std::uint32_t feet = plant.foot_contacts();
    const int down = std::popcount(feet);
    for (std::size_t i = 0; i < foot_field.size(); ++i)
      fields[static_cast<std::size_t>(foot_field[i])] =
          (feet >> i & 1u) != 0 ? std::round(weight_n / std::max(down, 1)) : 0.0;
    if (tick_field >= 0) fields[static_cast<std::size_t>(tick_field)] = static_cast<double>(published % 4294967296ull);
    if (remote) {
      const robot::StreamSpec& rs = m.streams[remote->stream_index];
      const int p = remote->PhaseAt(t);
      for (std::uint32_t k = 0; k < rs.field_count; ++k)
        fields[rs.first_field + k] = p < 0 ? 0.0 : remote->phases[static_cast<std::size_t>(p)].values[k];
    }
    for (std::size_t i = 0; i < o.faults.size(); ++i) {
      const LeggedDdsFault& f = o.faults[i];
      if (!active(f, t)) {
        held[i].reset();
        continue;
      }
      const robot::MotorSpec& mo = m.motors[static_cast<std::size_t>(f.motor)];
      if (f.kind == "stop") skip = true;
      if (f.kind == "crc") corrupt = true;
      if (f.kind == "nan") fields[mo.q_field] = std::nan("");
      if (f.kind == "range") fields[mo.q_field] = 10.0;
      if (f.kind == "lost") fields[static_cast<std::size_t>(mo.lost_field)] = 1.0;  // its counter grows by one
      if (f.kind == "silent") {
        if (!held[i]) held[i] = std::array<double, 3>{fields[mo.q_field], fields[mo.dq_field], fields[mo.tau_field]};
        fields[mo.q_field] = (*held[i])[0];
        fields[mo.dq_field] = (*held[i])[1];
        fields[mo.tau_field] = (*held[i])[2];
        if (mo.lost_field >= 0) fields[static_cast<std::size_t>(mo.lost_field)] = 1.0;
      }
    }
    if (skip) return true;
    link.FillFromFields(static_cast<std::size_t>(state), fields, &state_sample);
    if (corrupt && has_crc)
      state_sample.Set(crc_leaf, static_cast<double>(static_cast<std::uint32_t>(state_sample.Get(crc_leaf)) ^ 0x1u));
    if (std::any_of(o.faults.begin(), o.faults.end(), [&](const LeggedDdsFault& f) { return active(f, t); }))
      ++faulty_samples;
    ++published;
    return link.writer(static_cast<std::size_t>(state))->Write(state_sample.bytes()).ok();
  };
  // A command: its checksum, and every motor's values inside the robot's limits.
  const auto take = [&](const dds::DdsSample& c) {
    if (!link.ChecksumMatches(static_cast<std::size_t>(command), c)) {
      ++bad_crc;
      return;
    }
    bool ok = true;
    for (std::size_t k = 0; k < n; ++k) {
      const MotorLeaves& l = leaves[k];
      const robot::MotorSpec& mo = m.motors[k];
      MotorCmd x;
      x.mode = l.mode >= 0 ? c.Get(static_cast<std::uint32_t>(l.mode)) : 1.0;
      x.q = c.Get(static_cast<std::uint32_t>(l.q));
      x.dq = c.Get(static_cast<std::uint32_t>(l.dq));
      x.kp = c.Get(static_cast<std::uint32_t>(l.kp));
      x.kd = c.Get(static_cast<std::uint32_t>(l.kd));
      x.tau = c.Get(static_cast<std::uint32_t>(l.tau));
      const auto inside = [&](double v, std::uint32_t ci) {
        const robot::CommandSpec& s = m.commands[ci];
        // float32 on the wire: a limit rounds by up to one part in 2^24.
        const double slack = 1e-6 * std::max(1.0, std::fabs(v));
        return std::isfinite(v) && v >= s.min - slack && v <= s.max + slack;
      };
      const bool passive = x.mode == 0 && x.q == 0 && x.dq == 0 && x.kp == 0 && x.kd == 0 && x.tau == 0;
      // A position target matters only with stiffness (switched on, the loop sends kp 0 and q 0).
      const bool q_ok = x.kp == 0 ? std::isfinite(x.q) : inside(x.q, mo.q);
      if (!passive && !(q_ok && inside(x.dq, mo.dq) && inside(x.kp, mo.kp) && inside(x.kd, mo.kd) &&
                        inside(x.tau, mo.tau) && (x.mode == 0 || x.mode == 1))) {
        ok = false;
        if (first_violation.empty())
          first_violation = "motor '" + mo.joint + "' at period " + std::to_string(period) + ": mode " +
                            std::to_string(x.mode) + ", q " + std::to_string(x.q) + ", dq " + std::to_string(x.dq) +
                            ", kp " + std::to_string(x.kp) + ", kd " + std::to_string(x.kd) + ", tau " +
                            std::to_string(x.tau);
      }
      cmd[k] = x;
    }
    if (!ok) ++out_of_limits;
  };

  bool io_ok = publish(0.0);
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  const auto period_ns = static_cast<std::int64_t>(std::llround(period_s * 1e9));
  dds::DdsReader& reader = *link.reader(static_cast<std::size_t>(command));
  while (io_ok && plant_ok && !stop.load()) {
    const double t = static_cast<double>(period) * period_s;
    if (t >= end_s) break;
    if (o.lockstep) {
      bool got = false;
      for (double waited = 0; !got && waited < o.command_timeout_s && !stop.load(); waited += 0.1) {
        got = reader.WaitPop(command_sample.bytes(), nullptr, kNsPerS / 10);
        if (!got && answered > 0 && reader.matched_writers() == 0) break;  // the controller left
      }
      if (!got) {
        (answered > 0 && reader.matched_writers() == 0 ? controller_left : controller_lost) = true;
        break;
      }
      take(command_sample);
      ++answered;
      // Commands the controller sent on its lock-step timeout (before the first sample, or while
      // the state is stopped) answer no sample: the newest one queued is the answer.
      while (reader.Pop(command_sample.bytes(), nullptr)) {
        take(command_sample);
        ++answered;
      }
    } else {
      AddNs(&next, period_ns);
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
      while (reader.Pop(command_sample.bytes(), nullptr)) {
        take(command_sample);
        ++answered;
      }
      if (answered > 0 && reader.matched_writers() == 0) {
        controller_left = true;
        break;
      }
    }
    // The motors at the plant's rate.
    for (int s = 0; s < plant_ticks && plant_ok; ++s) {
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t j = joint[k];
        const MotorCmd& x = cmd[k];
        double v = 0;
        if (x.mode != 0 && !silent(k, t)) {
          v = x.tau;
          if (std::fabs(x.q) < kPosStop) v += x.kp * (x.q - plant.q_rad(j));
          if (std::fabs(x.dq) < kVelStop) v += x.kd * (x.dq - plant.dq_rad_s(j));
          const double limit = body.joint_at(j).effort_nm;
          v = std::isfinite(v) ? std::clamp(v, -limit, limit) : 0.0;
        }
        tau[j] = v;
      }
      plant.SetJointTorques(tau.data(), tau.size());
      plant_ok = plant.Step();
    }
    ++period;
    const double now = static_cast<double>(period) * period_s;
    // The trace: the base, the schedule's command, and what the commands say of the controller.
    RigSample r;
    r.t_s = now;
    FillBaseSample(plant, &r);
    const bool passive = std::all_of(cmd.begin(), cmd.end(), [](const MotorCmd& x) { return x.mode == 0; });
    const bool damping =
        !passive && std::all_of(cmd.begin(), cmd.end(), [](const MotorCmd& x) { return x.kp == 0 && x.kd > 0; });
    r.mode = static_cast<std::uint8_t>(damping || passive ? safety::Mode::kSafeStop : safety::Mode::kNominal);
    // Commanded again after passive or damping (the robot on the ground, or sitting), it is getting
    // up until its body leaves the ground: the body's contact then is no fall.
    if (damping || passive) {
      getting_up = true;
    } else if (!r.body_contact) {
      getting_up = false;
    }
    r.loop_phase = static_cast<std::uint8_t>(passive      ? loop::Phase::kArming
                                             : getting_up ? loop::Phase::kStandUp
                                                          : loop::Phase::kRun);
    if (schedule) {
      r.schedule_phase = schedule->PhaseAt(now - period_s);
      if (r.schedule_phase >= 0) {
        const auto& v = schedule->phases[static_cast<std::size_t>(r.schedule_phase)].values;
        r.cmd_vx = static_cast<float>(v[columns[0]]);
        r.cmd_vy = static_cast<float>(v[columns[1]]);
        r.cmd_yaw_rate = static_cast<float>(v[columns[2]]);
      }
    }
    trace.push_back(r);
    for (std::size_t i = 0; i < o.faults.size(); ++i) {
      FaultOutcome& fo = outcome[i];
      if (!fo.began && active(o.faults[i], now - period_s)) {
        fo.began = true;
        fo.start_period = period - 1;
      }
      if (fo.began && fo.stopped_after < 0 && (damping || passive))
        fo.stopped_after = static_cast<std::int64_t>(period - 1 - fo.start_period);
    }
    io_ok = publish(now);
  }
  (void)link.Flush(kNsPerS);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double sim_s = static_cast<double>(period) * period_s;

  const loop::Schedule none;
  const RigReport rep = ReportOfTrace(trace, schedule ? *schedule : none, o.settle_s, false);
  std::printf(
      "pbppo-hil go2: %.2f s simulated in %.2f s (%.2fx real time), %llu periods; state samples %llu "
      "(faulty %llu), commands %llu (checksum mismatches %llu, outside the limits %llu)\n",
      sim_s, wall_s, wall_s > 0 ? sim_s / wall_s : 0.0, static_cast<unsigned long long>(period),
      static_cast<unsigned long long>(published), static_cast<unsigned long long>(faulty_samples),
      static_cast<unsigned long long>(answered), static_cast<unsigned long long>(bad_crc),
      static_cast<unsigned long long>(out_of_limits));
  if (!first_violation.empty()) std::printf("  first command outside the limits: %s\n", first_violation.c_str());
  PrintRigReport(rep);  // without a schedule: no phases, the distance and falls
  for (std::size_t i = 0; i < o.faults.size(); ++i) {
    const LeggedDdsFault& f = o.faults[i];
    if (!outcome[i].began)
      std::printf("fault %s at %.2f s: not reached\n", f.kind.c_str(), f.start_s);
    else if (outcome[i].stopped_after < 0)
      std::printf("fault %s at %.2f s (motor %d): the commands never reached damping\n", f.kind.c_str(), f.start_s,
                  f.motor);
    else
      std::printf("fault %s at %.2f s (motor %d): damping %lld periods after it began\n", f.kind.c_str(), f.start_s,
                  f.motor, static_cast<long long>(outcome[i].stopped_after));
  }
  if (controller_lost)
    std::fprintf(stderr, "pbppo-hil go2: no command within %.1f s at period %llu\n", o.command_timeout_s,
                 static_cast<unsigned long long>(period));
  int rc = (!io_ok || !plant_ok || controller_lost || bad_crc > 0 || out_of_limits > 0) ? 1 : 0;
  if (!o.trace.empty())
    if (auto st = WriteRigTrace(trace, o.trace, 10); !st) rc = Fail(st.error().message);
  if (!o.plot.empty())
    if (auto st = PlotRigTrace(trace, m.name + " HIL", m.op.any(), o.plot); !st)
      std::fprintf(stderr, "pbppo-hil go2: --plot: %s\n", st.error().message.c_str());
  if (!o.report.empty()) {
    nlohmann::json j;
    j["robot"] = m.name;
    j["simulated_s"] = sim_s;
    j["wall_s"] = wall_s;
    j["periods"] = period;
    j["state_samples"] = published;
    j["faulty_samples"] = faulty_samples;
    j["commands"] = answered;
    j["checksum_mismatches"] = bad_crc;
    j["commands_outside_limits"] = out_of_limits;
    j["fell"] = rep.fell;
    j["distance_m"] = rep.distance_m;
    j["controller_left"] = controller_left;
    for (const PhaseTracking& p : rep.phases)
      j["phases"].push_back({{"name", p.name},
                             {"command", {p.command[0], p.command[1], p.command[2]}},
                             {"mean_abs_error", {p.mean_abs_error[0], p.mean_abs_error[1], p.mean_abs_error[2]}}});
    for (std::size_t i = 0; i < o.faults.size(); ++i)
      j["faults"].push_back({{"kind", o.faults[i].kind},
                             {"start_s", o.faults[i].start_s},
                             {"motor", o.faults[i].motor},
                             {"began", outcome[i].began},
                             {"stopped_after_periods", outcome[i].stopped_after}});
    const std::string text = j.dump(2) + "\n";
    if (auto st = policy::WriteFileAtomic(o.report, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
        !st)
      rc = Fail(st.error().message);
  }
  std::fflush(stdout);
  return rc;
}

}  // namespace pbppo::sim
