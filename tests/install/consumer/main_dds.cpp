// A user's controller project using the installed runtime: a robot loaded from its robot file, its
// DDS transport opened through the transport table (pbppo::transports) as a controller does, and
// the robot's peer (a vehicle) in the same process on the installed profile and a domain of its own:
// a sensor sample in, a command out.
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/bindings.hpp"

int main(int argc, char** argv) {
  if (argc != 4) return 2;
  using namespace pbppo;
  auto robot = robot::LoadRobotModel(argv[1]);
  if (!robot) {
    std::fprintf(stderr, "consumer_dds: %s\n", robot.error().message.c_str());
    return 1;
  }
  const robot::RobotModel& m = *robot;
  transport::Settings settings;
  settings.dds.profile_file = argv[2];
  settings.dds.domain_id = std::atoi(argv[3]);
  auto controller = transport::Open(m, m.transports[0], settings);
  auto vehicle = dds::DdsLink::Open(m, m.transports[0].name, dds::DdsSide::kPeer, settings.dds);
  if (!controller || !vehicle) {
    std::fprintf(stderr, "consumer_dds: %s\n", (!controller ? controller.error() : vehicle.error()).message.c_str());
    return 1;
  }
  constexpr std::int64_t kTimeout = 10'000'000'000;
  if (!(*controller)->Connect(kTimeout) || !(*vehicle)->WaitForPeer(kTimeout)) {
    std::fprintf(stderr, "consumer_dds: the two sides did not discover each other\n");
    return 1;
  }
  // The vehicle sends its sensor stream's fields (tick 7, 16 sonar beams at 15 m).
  robot::RobotData data = robot::MakeRobotData(m);
  std::vector<double> fields(m.fields.size(), 15.0);
  fields[static_cast<std::size_t>(m.FieldIndex("tick"))] = 7;
  fields[static_cast<std::size_t>(m.FieldIndex("sonar_beams"))] = 16;
  dds::DdsSample sample((*vehicle)->message(0).type);
  (*vehicle)->FillFromFields(0, fields, &sample);
  if (!(*vehicle)->writer(0)->Write(sample.bytes())) return 1;
  std::uint64_t version = 0;
  if (!(*controller)->WaitForSample(0, &version, kTimeout)) return 1;
  (*controller)->Read(m, data);
  data.command[static_cast<std::size_t>(m.CommandIndex("surge_speed"))] = 0.5;
  (*controller)->Write(m, data);
  dds::DdsSample got((*vehicle)->message(1).type);
  if (!(*vehicle)->reader(1)->WaitPop(got.bytes(), nullptr, kTimeout)) return 1;
  const double answers = got.Get("answers").value(), v = got.Get("surge_speed_mps").value();
  std::printf("consumer_dds: sample tick %g -> command v = %g answering tick %g\n",
              data.fields[static_cast<std::size_t>(m.FieldIndex("tick"))], v, answers);
  return answers == 7 && v == 0.5 ? 0 : 1;
}
