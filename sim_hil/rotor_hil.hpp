// Any robot of a CAN map on a stand, behind its emulated devices: the rotor plant
// (sim_hil/plants/rotor_plant.hpp: every actuated joint a free rotor) and one emulated MIT driver
// per motor and the first IMU (level and still: the base is on the stand) on the map's buses
// (sim_hil/can_devices.hpp). Nothing in it names a robot: a robot that is only data (robot.yaml,
// URDF, description, CAN map) runs against it through pbppo-controller (pbppo-hil rotors) or in
// one process over the in-process network.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_model.hpp"
#include "sim_hil/can_devices.hpp"
#include "sim_hil/plants/rotor_plant.hpp"

namespace pbppo::sim {

struct RotorHilOptions : CanDevicesOptions {
  std::vector<double> initial_q_rad;  // per actuated joint; empty: 0 (inside a revolute joint's limits)
  std::uint32_t substeps = 4;         // plant steps per tick
};

class RotorHil {
 public:
  static Result<std::unique_ptr<RotorHil>> Make(const robot::RobotModel& model, const RotorHilOptions& options);

  // One simulation tick: expect_per_bus (may be null) frames waited for on each bus, for at most
  // wait_ns (lock-step); the drivers answer, their torques drive the plant one tick, the replies
  // and the IMU's sample go out.
  void Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept;

  std::uint64_t tick() const noexcept { return tick_; }
  const RotorPlant& plant() const noexcept { return plant_; }
  const CanDevices& devices() const noexcept { return *devices_; }
  // The torque each joint got in the last tick (Nm).
  double tau_nm(std::size_t joint) const noexcept { return tau_[joint]; }

 private:
  explicit RotorHil(RotorPlant plant) : plant_(std::move(plant)) {}
  RotorPlant plant_;
  std::unique_ptr<CanDevices> devices_;
  std::vector<double> tau_;
  std::uint64_t tick_ = 0;
};

// pbppo-hil rotors: the program (usage in hil_main.cpp). argv[0] is "rotors". Exit status: 0
// done, 1 a failure at run time, 2 bad arguments or files.
int RunRotorHil(int argc, char** argv, const std::atomic<bool>& stop);

}  // namespace pbppo::sim
