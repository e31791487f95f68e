// Replays a sequence of returns through a clip schedule, open loop: each line of RETURNS is the
// feedback for the arm chosen just before it. Prints, a line per iteration, the chosen arm and
// every arm's exploitation term (%.17g), for check_reference_schedule.py to compare with the
// released script's rule. usage: schedule_replay SCHEDULE ARMS RETURNS
#include <cstdio>
#include <fstream>
#include <string>

#include "policies/trainer/clip_schedule.hpp"

using namespace pbppo::trainer;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: schedule_replay SCHEDULE ARMS RETURNS\n");
    return 2;
  }
  auto arms = ParseArms(argv[2]);
  if (!arms) {
    std::fprintf(stderr, "schedule_replay: %s\n", arms.error().message.c_str());
    return 2;
  }
  auto config = ParseSchedule(argv[1], *arms);
  if (!config) {
    std::fprintf(stderr, "schedule_replay: %s\n", config.error().message.c_str());
    return 2;
  }
  std::ifstream in(argv[3]);
  if (!in) {
    std::fprintf(stderr, "schedule_replay: cannot read %s\n", argv[3]);
    return 2;
  }
  auto schedule = MakeClipSchedule(*config);
  std::string line;
  for (long n = 1; std::getline(in, line); ++n) {
    std::size_t used = 0;
    double r = 0;
    try {
      r = std::stod(line, &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0 || line.find_first_not_of(" \t\r", used) != std::string::npos) {
      std::fprintf(stderr, "schedule_replay: %s line %ld: '%s' is not a number\n", argv[3], n, line.c_str());
      return 2;
    }
    const int arm = schedule->Choose();
    std::printf("%d", arm);
    for (const ArmState& a : schedule->arms()) std::printf(" %.17g", a.value);
    std::printf("\n");
    schedule->Update(arm, r, 0.0);
  }
  return 0;
}
