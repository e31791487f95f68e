// A supervisor model shaped like the AUV's, for the supervisor's tests and its fuzz target: v in
// [0, 1.5] (degraded: 0.75), 0.1 per tick, safe-stop ramps 0.3 per tick; omega in [-0.5, 0.5],
// 0.25 per tick, ramps 0.5 per tick; the sample stale after 1 tick, safe-stop after 3, lost after
// 20; 3 invalid samples in a row stop; one DDS link.
#pragma once

#include "runtime/safety/supervisor.hpp"

namespace pbppo::test {

inline safety::SupervisorModel AuvLikeSupervisorModel() {
  using safety::StopKind;
  safety::SupervisorModel m;
  m.commands = {{"v", 0.0, 1.5, 0.0, 0.75, 0.1, StopKind::kRamp, 0.3, 0, -1},
                {"omega", -0.5, 0.5, -0.5, 0.5, 0.25, StopKind::kRamp, 0.5, 0, -1}};
  m.streams = {{"sensor", 1, 3, 20, 3}};
  m.input_names = {"surge_mps", "sonar_5_m"};
  m.transport_names = {"dds"};
  return m;
}

}  // namespace pbppo::test
