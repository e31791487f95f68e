// Signals: what an IO layout observes, computed from the robot's fields by name. The names a
// robot offers, generic and data-defined, are:
//
//   <field>                every field of the robot model (q_LF_HAA, dq_LF_HAA, surge_mps,
//                          command_vx, base_imu_gyro_x, ...)
//   <declared>             every signal of robot.yaml's signals section: a field, a field minus a
//                          parameter, a wrapped angle, cos / sin of a field, the least of several
//                          fields, or the unit gravity vector in an IMU's frame from its orientation
//                          (projected_gravity_x|y|z)
//   last_action_<action>   the previous policy output of that action (policy units; 0 at first)
//
// A SignalProgram is compiled once at set-up for the signals a layout (or the supervisor) names;
// Compute is noexcept and allocation-free. The trainer's environments and the controller compute
// an observation through the same program.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::robot {

class SignalProgram {
 public:
  // One output per name, in order. Unknown names are refused, naming the signal and the known ones.
  static Result<SignalProgram> Create(const RobotModel& model, const std::vector<std::string>& names);
  // The signals the IO layout's observations read, each once (the names ObservationBuilder maps).
  static Result<SignalProgram> ForLayout(const RobotModel& model, const IoLayout& layout);

  // out[i] = signal i from the fields and the previous action (policy units, one per layout action).
  void Compute(std::span<const double> fields, std::span<const float> last_action, double* out) const noexcept;

  const std::vector<std::string>& names() const noexcept { return names_; }
  std::size_t size() const noexcept { return names_.size(); }
  // The stream each signal depends on (its first field's; last actions: -1).
  const std::vector<std::int32_t>& streams() const noexcept { return stream_; }

 private:
  enum class Op : std::uint8_t { kField, kWrap, kCos, kSin, kMinus, kMin, kGravityX, kGravityY, kGravityZ, kAction };
  struct Step {
    Op op = Op::kField;
    std::uint32_t a = 0, n = 1;  // fields [a, a + n) of `fields_` (kMin, kGravity*), a field, or an action
    double value = 0;
  };
  std::vector<Step> steps_;
  std::vector<std::uint32_t> fields_;  // kMin and kGravity* operands
  std::vector<std::string> names_;
  std::vector<std::int32_t> stream_;
};

// An angle wrapped to (-pi, pi]; exact (and the identity) for angles already in that range.
double WrapAngleRad(double a) noexcept;

// The names of every signal the robot offers (fields, declared signals, last actions of its layout).
std::vector<std::string> SignalNames(const RobotModel& model);

}  // namespace pbppo::robot
