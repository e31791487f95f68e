// The plant of the slider (tests/data/slider): a 1 kg cart on a spring (4 N/m) and a
// damper (1 N s/m) pushed by the controller's force, integrated (semi-implicit Euler) over the
// robot's tick. It speaks the robot's own DDS messages as the robot file declares them (the
// peer's side of its transport), in lock-step: the state of tick k, then the force answering k,
// then one tick of physics; after `ticks` ticks the last state is marked done. The only C++ the
// slider has.
//
//   slider_plant ROBOT_YAML DOMAIN TICKS TRAJECTORY_CSV
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/dds/dds_link.hpp"

using namespace pbppo;

namespace {

int Fail(const std::string& why) {
  std::fprintf(stderr, "slider_plant: %s\n", why.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) return Fail("usage: slider_plant ROBOT_YAML DOMAIN TICKS TRAJECTORY_CSV");
  auto model = robot::LoadRobotModel(argv[1]);
  if (!model) return Fail(model.error().message);
  const robot::RobotModel& m = *model;
  dds::DdsLinkOptions o;
  o.domain_id = std::atoi(argv[2]);
  const long ticks = std::atol(argv[3]);
  auto link = dds::DdsLink::Open(m, "link", dds::DdsSide::kPeer, o);
  if (!link) return Fail(link.error().message);
  dds::DdsLink& l = **link;
  const std::size_t state = l.MessageIndex("state").value(), force = l.MessageIndex("force").value();
  const auto field = [&](const char* name) { return static_cast<std::size_t>(m.FieldIndex(name)); };
  const std::size_t tick_f = field("tick"), x_f = field("position_m"), v_f = field("velocity_mps"),
                    done_f = field("done");
  const int answers = l.LeafOf(force, robot::ValueTerm::Kind::kField, static_cast<std::uint32_t>(tick_f));
  const int force_leaf =
      l.LeafOf(force, robot::ValueTerm::Kind::kCommand, static_cast<std::uint32_t>(m.CommandIndex("force")));
  if (answers < 0 || force_leaf < 0) return Fail("the force message carries no field.tick or command.force");
  if (!l.WaitForPeer(30'000'000'000)) return Fail("no controller within 30 s");

  std::FILE* csv = std::fopen(argv[4], "w");
  if (csv == nullptr) return Fail(std::string("cannot write ") + argv[4]);
  std::fprintf(csv, "tick,x_m,v_mps,force_n\n");
  const double dt = m.tick_period_s, k = 4.0, c = 1.0, mass = 1.0;
  double x = 0.3, v = 0.0;
  std::vector<double> fields(m.fields.size(), 0.0);
  dds::DdsSample out(l.message(state).type), in(l.message(force).type);
  for (long t = 0;; ++t) {
    fields[tick_f] = static_cast<double>(t);
    fields[x_f] = x;
    fields[v_f] = v;
    fields[done_f] = t >= ticks ? 1.0 : 0.0;
    l.FillFromFields(state, fields, &out);
    if (auto st = l.writer(state)->Write(out.bytes()); !st) return Fail(st.error().message);
    if (t >= ticks) break;
    // The force answering this state (others, late ones, are skipped).
    double f = 0;
    for (;;) {
      if (!l.reader(force)->WaitPop(in.bytes(), nullptr, 10'000'000'000))
        return Fail("no force for tick " + std::to_string(t));
      if (in.Get(static_cast<std::uint32_t>(answers)) != static_cast<double>(t)) continue;
      f = in.Get(static_cast<std::uint32_t>(force_leaf));
      break;
    }
    std::fprintf(csv, "%ld,%.17g,%.17g,%.9g\n", t, x, v, f);
    v += (f - k * x - c * v) / mass * dt;
    x += v * dt;
  }
  (void)l.Flush(1'000'000'000);
  if (std::fclose(csv) != 0) return Fail(std::string("cannot write ") + argv[4]);
  std::printf("slider_plant: %ld ticks, final x %.6f m, v %.6f m/s\n", ticks, x, v);
  return 0;
}
