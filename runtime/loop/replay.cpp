#include "runtime/loop/replay.hpp"

#include <cstdio>
#include <cstring>

namespace pbppo::loop {
namespace {

// The recorded inputs of one tick, as a transport.
class ReplayTransport final : public robot::Transport {
 public:
  const LogInputs* inputs = nullptr;
  void Read(const robot::RobotModel& m, robot::RobotData& d) noexcept override {
    for (auto& h : d.transports) h = {};
    if (inputs == nullptr) return;
    std::size_t v = 0;
    for (std::uint32_t s : inputs->streams) {
      const robot::StreamSpec& spec = m.streams[s];
      for (std::uint32_t f = 0; f < spec.field_count && v < inputs->values.size(); ++f)
        d.fields[spec.first_field + f] = inputs->values[v++];
      d.fresh[s] = 1;
    }
    for (const auto& [link, bits] : inputs->links) {
      if (link >= d.transports.size()) continue;
      d.transports[link].degraded = (bits & 1) != 0;
      d.transports[link].fault = (bits & 2) != 0;
      d.transports[link].lost = (bits & 4) != 0;
    }
  }
  void Write(const robot::RobotModel&, robot::RobotData&) noexcept override {}
};

std::string Hex(std::uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%016llx", static_cast<unsigned long long>(v));
  return b;
}

std::string HexFloat(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%a", v);
  return b;
}

LogOutputs OutputsOf(const robot::RobotData& d, Phase phase) {
  LogOutputs o;
  o.tick = d.tick;
  o.phase = static_cast<std::uint8_t>(phase);
  o.mode = static_cast<std::uint8_t>(d.mode);
  o.commands = d.command;
  for (robot::MotorCommand c : d.motors) o.motors.push_back(static_cast<std::uint8_t>(c));
  return o;
}

// "" when equal, else what differs first.
std::string Difference(const robot::RobotModel& m, const LogOutputs& got, const LogOutputs& want) {
  std::string what;
  if (got.tick != want.tick) {
    what.append("the replay is at tick ").append(std::to_string(got.tick));
  } else if (got.phase != want.phase) {
    what.append("phase ").append(ToString(static_cast<Phase>(got.phase)));
    what.append(" (recorded ").append(ToString(static_cast<Phase>(want.phase))).append(")");
  } else if (got.mode != want.mode) {
    what.append("mode ").append(safety::ToString(static_cast<safety::Mode>(got.mode)));
    what.append(" (recorded ").append(safety::ToString(static_cast<safety::Mode>(want.mode))).append(")");
  } else {
    for (std::size_t k = 0; what.empty() && k < got.commands.size() && k < want.commands.size(); ++k)
      if (std::memcmp(&got.commands[k], &want.commands[k], sizeof(double)) != 0)
        what.append("command '")
            .append(m.commands[k].name)
            .append("' ")
            .append(HexFloat(got.commands[k]))
            .append(" (recorded ")
            .append(HexFloat(want.commands[k]))
            .append(")");
    for (std::size_t k = 0; what.empty() && k < got.motors.size() && k < want.motors.size(); ++k)
      if (got.motors[k] != want.motors[k])
        what.append("motor '")
            .append(m.motors[k].joint)
            .append("' ")
            .append(std::to_string(got.motors[k]))
            .append(" (recorded ")
            .append(std::to_string(want.motors[k]))
            .append(")");
  }
  if (what.empty()) return what;
  std::string at = "tick ";
  at.append(std::to_string(want.tick)).append(": ").append(what);
  return at;
}

}  // namespace

Result<ReplayResult> Replay(const robot::RobotModel& robot, const Log& log, CommandSource* source,
                            std::uint64_t source_hash, const ReplayTick& each_tick) {
  const LogHeader& h = log.header;
  auto refuse = [&](const std::string& what) { return MakeError(ErrorCode::kMismatch, "replay: " + what); };
  if (h.robot != robot.name) return refuse("the log is of robot '" + h.robot + "', not '" + robot.name + "'");
  if (h.robot_hash != robot.hash)
    return refuse("robot_hash " + Hex(h.robot_hash) + " in the log, " + Hex(robot.hash) + " for " + robot.path +
                  " (the robot's files changed since the recording)");
  if (h.source_hash != source_hash)
    return refuse("source_hash " + Hex(h.source_hash) + " in the log, " + Hex(source_hash) +
                  " here (another policy or trajectory)");
  if (log.dropped != 0) return refuse(std::to_string(log.dropped) + " records were dropped while recording");
  auto model = robot::WithTickPeriod(robot, h.tick_period_s);
  if (!model) return std::move(model).error();
  const robot::RobotModel& m = *model;
  if (h.fields != m.fields.size() || h.streams != m.streams.size() ||
      h.links != m.supervisor_model.transport_names.size() || h.commands != m.commands.size() ||
      h.motors != m.motors.size())
    return refuse("the log's fields, streams, links, commands or motors do not count like " + robot.path + "'s");
  robot::RobotData data = robot::MakeRobotData(m);
  LoopOptions options;
  options.shutdown_after_source = (h.options & 1u) != 0;
  options.stop_at_end_field = (h.options & 2u) != 0;
  auto loop = MakeLoopData(m, source, options);
  // A later file of a rotated recording starts from the loop's state where the one before ended.
  if (!log.snapshot.empty()) {
    if (auto st = LoadState(m, data, *loop, log.snapshot); !st) return refuse(st.error().message);
  } else if (h.sequence != 0) {
    return refuse("file " + std::to_string(h.sequence) + " of a rotated recording has no snapshot to start from");
  }
  ReplayTransport replay;
  robot::Transport* transports[] = {&replay};
  ReplayResult r;
  auto compare = [&](const LogOutputs& want) {
    r.outputs.push_back(OutputsOf(data, loop->phase()));
    ++r.compared;
    const std::string d = Difference(m, r.outputs.back(), want);
    if (d.empty()) return;
    if (r.mismatches++ == 0) r.first_mismatch = d;
  };
  for (std::size_t i = 0; i < log.records.size(); ++i) {
    const LogRecord& rec = log.records[i];
    if (rec.type == 1) {
      const LogInputs& in = rec.inputs;
      if ((in.flags & 1) != 0) loop->Arm();
      if ((in.flags & 2) != 0) loop->Disarm();
      if ((in.flags & 4) != 0) loop->RequestStop();
      if ((in.flags & 8) != 0) loop->RequestEStop();
      if ((in.flags & 32) != 0) loop->RequestRearm();
      rt::TickTiming t;
      t.tick = in.tick;
      t.consecutive_misses = in.consecutive_misses;
      t.missed = (in.flags & 16) != 0;
      t.wake_ns = t.deadline_ns = 0;
      replay.inputs = &in;
      (void)Tick(m, data, *loop, transports, t);
      ++r.ticks;
      if (each_tick) each_tick(data, *loop);
      if (i + 1 < log.records.size() && log.records[i + 1].type == 2) compare(log.records[++i].outputs);
    } else {  // outputs with no inputs before them: the stop command of a robot whose clock stopped
      Shutdown(m, data, *loop, transports, rec.outputs.tick);
      if (each_tick) each_tick(data, *loop);
      compare(rec.outputs);
    }
  }
  return r;
}

std::string FormatOutputs(const robot::RobotModel& m, const std::vector<LogOutputs>& outputs) {
  std::string s = "tick,phase,mode";
  for (const auto& c : m.commands) s.append(",").append(c.name);
  for (const auto& mo : m.motors) s.append(",motor_").append(mo.joint);
  s.append("\n");
  for (const LogOutputs& o : outputs) {
    s.append(std::to_string(o.tick)).append(",").append(ToString(static_cast<Phase>(o.phase)));
    s.append(",").append(safety::ToString(static_cast<safety::Mode>(o.mode)));
    for (double c : o.commands) s.append(",").append(HexFloat(c));
    for (std::uint8_t c : o.motors) s.append(",").append(std::to_string(c));
    s.append("\n");
  }
  return s;
}

}  // namespace pbppo::loop
