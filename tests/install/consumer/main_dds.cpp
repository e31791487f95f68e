// A user's controller project using the installed DDS transport: a controller link and a vehicle
// link in one process (the installed profile, a domain of its own) exchange a sample and a command.
#include <cstdio>
#include <cstdlib>

#include "runtime/transport/dds/auv_dds_link.hpp"

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  using namespace pbppo::dds;
  AuvDdsOptions o;
  o.profile_file = argv[1];
  o.domain_id = std::atoi(argv[2]);
  auto controller = AuvDdsLink::Create(AuvDdsRole::kController, o);
  auto vehicle = AuvDdsLink::Create(AuvDdsRole::kVehicle, o);
  if (!controller || !vehicle) {
    std::fprintf(stderr, "consumer_dds: %s\n", (!controller ? controller : vehicle).error().message.c_str());
    return 1;
  }
  constexpr std::int64_t kTimeout = 10'000'000'000;
  if (!(*controller)->WaitForPeer(kTimeout) || !(*vehicle)->WaitForPeer(kTimeout)) {
    std::fprintf(stderr, "consumer_dds: the links did not discover each other\n");
    return 1;
  }
  pbppo::robot::AuvSensorSample s;
  s.tick = 7;
  s.sonar_beams = 16;
  for (float& r : s.sonar_m) r = 15.0f;
  if (auto st = (*vehicle)->PublishSample(s); !st) return 1;
  if (!(*controller)->WaitForSample(0, kTimeout)) return 1;
  AuvSensorInput in;
  (*controller)->ReadSample(&in);
  pbppo::robot::AuvCommand c;
  c.answers = in.value.tick;
  c.surge_speed_mps = 0.5;
  if (!(*controller)->PushCommand(c)) return 1;
  AuvCommandInput got;
  if (!(*vehicle)->WaitForCommand(&got, kTimeout)) return 1;
  std::printf("consumer_dds: sample tick %llu (flags %u) -> command v = %g answering tick %llu\n",
              static_cast<unsigned long long>(in.value.tick), in.flags, got.value.surge_speed_mps,
              static_cast<unsigned long long>(got.value.answers));
  return got.value.answers == 7 && got.value.surge_speed_mps == 0.5 ? 0 : 1;
}
