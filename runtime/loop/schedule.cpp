#include "runtime/loop/schedule.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::loop {

using robot::YamlFields;

int Schedule::PhaseAt(double t_s) const noexcept {
  for (std::size_t i = 0; i < phases.size(); ++i)
    if (t_s < phases[i].start_s + phases[i].duration_s) return static_cast<int>(i);
  return -1;
}

Result<Schedule> ParseSchedule(const std::string& text, const std::string& origin, const robot::RobotModel& m) {
  auto parsed = robot::ParseYaml(text, origin);
  if (!parsed) return std::move(parsed).error();
  const YAML::Node& root = *parsed;
  const YamlFields y(origin);
  if (!root.IsMap()) return y.Fail("", "a schedule is a mapping");
  PBPPO_TRY(y.Keys(root, "", {"stream", "phases"}));
  Schedule s;
  s.path = origin;
  PBPPO_TRY(y.Text(root, "stream", "", &s.stream, YamlFields::TextRule::kToken));
  const int stream = m.StreamIndex(s.stream);
  if (stream < 0 || m.streams[static_cast<std::size_t>(stream)].kind != robot::StreamKind::kDeclared)
    return y.Fail("stream", "'" + s.stream + "' is not a declared stream of " + m.path);
  s.stream_index = static_cast<std::uint32_t>(stream);
  const robot::StreamSpec& spec = m.streams[s.stream_index];
  YAML::Node phases;
  PBPPO_TRY(y.List(root, "phases", "", true, &phases));
  if (phases.size() == 0) return y.Fail("phases", "the schedule has no phase");
  double t = 0;
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const YAML::Node& n = phases[i];
    const std::string w = "phases[" + std::to_string(i) + "]";
    if (!n.IsMap()) return y.Fail(w, "a phase is a mapping");
    SchedulePhase p;
    PBPPO_TRY(y.Text(n, "name", w, &p.name, YamlFields::TextRule::kToken));
    PBPPO_TRY(y.Number(n, "duration_s", w, 1e-3, 1e6, &p.duration_s));
    p.start_s = t;
    t += p.duration_s;
    p.values.assign(spec.field_count, 0.0);
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (key == "name" || key == "duration_s") continue;
      const int f = m.FieldIndex(key);
      if (f < 0 || m.fields[static_cast<std::size_t>(f)].stream != s.stream_index)
        return y.Fail(w + " '" + p.name + "'." + key, "is not a field of stream '" + s.stream + "'");
      const robot::FieldSpec& fs = m.fields[static_cast<std::size_t>(f)];
      double v = 0;
      PBPPO_TRY(y.Number(n, key.c_str(), w + " '" + p.name + "'", fs.min, fs.max, &v));
      p.values[static_cast<std::size_t>(f) - spec.first_field] = v;
    }
    s.phases.push_back(std::move(p));
  }
  return s;
}

Result<Schedule> LoadSchedule(const std::string& path, const robot::RobotModel& model) {
  auto text = robot::ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseSchedule(*text, path, model);
}

Result<std::unique_ptr<ScheduleTransport>> ScheduleTransport::Create(const robot::RobotModel& m, Schedule schedule) {
  if (schedule.stream_index >= m.streams.size() || m.streams[schedule.stream_index].name != schedule.stream)
    return MakeError(ErrorCode::kMismatch, schedule.path + ": stream '" + schedule.stream + "' is not in " + m.path);
  const robot::StreamSpec& spec = m.streams[schedule.stream_index];
  std::unique_ptr<ScheduleTransport> t(new ScheduleTransport(std::move(schedule)));
  t->first_field_ = spec.first_field;
  t->tick_s_ = m.tick_period_s;
  t->period_ticks_ =
      std::max<std::uint32_t>(1, static_cast<std::uint32_t>(std::lround(spec.period_s / m.tick_period_s)));
  return t;
}

Result<std::vector<std::size_t>> Schedule::Columns(const robot::RobotModel& m,
                                                   std::initializer_list<std::string_view> fields) const {
  const robot::StreamSpec& spec = m.streams[stream_index];
  std::vector<std::size_t> out;
  for (std::string_view name : fields) {
    std::size_t f = 0;
    while (f < spec.field_count && m.fields[spec.first_field + f].name != name) ++f;
    if (f == spec.field_count)
      return MakeError(ErrorCode::kMismatch,
                       path + ": stream '" + stream + "' has no field '" + std::string(name) + "'");
    out.push_back(f);
  }
  return out;
}

void ScheduleTransport::Read(const robot::RobotModel&, robot::RobotData& d) noexcept {
  if (!started_) {
    started_ = true;
    start_tick_ = d.tick;
  }
  const std::uint64_t k = d.tick - start_tick_;
  const int phase = schedule_.PhaseAt(static_cast<double>(k) * tick_s_);
  if (phase < 0) finished_ = true;
  if (finished_ || killed_ || k % period_ticks_ != 0) return;
  const SchedulePhase& p = schedule_.phases[static_cast<std::size_t>(phase)];
  std::copy(p.values.begin(), p.values.end(), d.fields.begin() + first_field_);
  d.fresh[schedule_.stream_index] = 1;
  ++samples_;
}

}  // namespace pbppo::loop
