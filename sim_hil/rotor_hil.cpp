#include "sim_hil/rotor_hil.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "runtime/transport/can/can_transport.hpp"

namespace pbppo::sim {

Result<std::unique_ptr<RotorHil>> RotorHil::Make(const robot::RobotModel& model, const RotorHilOptions& options) {
  auto devices = CanDevices::Make(model, options, "rotor HIL");
  if (!devices.ok()) return std::move(devices).error();
  auto plant = RotorPlant::Make(*model.body, model.tick_period_s, options.substeps);
  if (!plant.ok()) return std::move(plant).error();
  std::unique_ptr<RotorHil> h(new RotorHil(std::move(*plant)));
  h->devices_ = std::move(*devices);
  const std::size_t n = model.body->joint_count();
  if (!options.initial_q_rad.empty()) {
    if (options.initial_q_rad.size() != n)
      return MakeError(ErrorCode::kMismatch, "rotor HIL: " + std::to_string(options.initial_q_rad.size()) +
                                                 " initial positions for " + std::to_string(n) + " joints");
    h->plant_.Reset(options.initial_q_rad, std::vector<double>(n, 0.0));
  }
  h->tau_.assign(n, 0.0);
  return h;
}

void RotorHil::Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept {
  const double* q = plant_.q_rad();
  const double* dq = plant_.dq_rad_s();
  devices_->Receive(expect_per_bus, wait_ns, q, dq, tick_);
  devices_->Torques(q, dq, tick_, tau_.data());
  plant_.Step(tau_.data());
  can::ImuSample level;  // the base on its stand: level, still, gravity up the z axis
  level.quat_wxyz[0] = 1.0;
  level.accel_m_s2[2] = 9.81;
  devices_->Send(level);
  ++tick_;
}

int RunRotorHil(int argc, char** argv, const std::atomic<bool>& stop) {
  CLI::App app{"pbppo-hil rotors: any robot of a CAN map on a stand, every actuated joint a free rotor"};
  std::string robot, can_list;
  bool lockstep = false;
  double duration_s = 0;
  app.add_option("--robot", robot, "The robot (its robot.yaml: a description and a CAN map)")->required();
  app.add_option("--can", can_list, "CAN interfaces, one per bus of the CAN map (IF0[,IF1...])");
  app.add_flag("--lockstep", lockstep, "Each tick waits for the controller's frames (up to 100 ms)");
  app.add_option("--duration", duration_s, "Stop after this much simulated time (s)")->check(CLI::Range(0.0, 1e7));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  auto fail = [](const std::string& msg, int rc) {
    std::fprintf(stderr, "pbppo-hil rotors: %s\n", msg.c_str());
    return rc;
  };
  auto model = robot::LoadRobotModel(robot);
  if (!model) return fail(model.error().message, 2);
  auto interfaces = can::ParseInterfaceList(can_list);
  if (!interfaces) return fail("--can: " + interfaces.error().message, 2);
  RotorHilOptions o;
  o.interfaces = std::move(*interfaces);
  auto h = RotorHil::Make(*model, o);
  if (!h) return fail(h.error().message, 2);
  RotorHil& sim = **h;
  std::printf("pbppo-hil: %s on a stand, %zu joints as free rotors, on %s, %s\n", model->name.c_str(),
              sim.plant().joint_count(), sim.devices().interface(0).c_str(),
              lockstep ? "lock-step" : "free-running at the tick period");
  std::fflush(stdout);
  const auto limit = duration_s > 0 ? static_cast<std::uint64_t>(duration_s / model->tick_period_s) : 0;
  const HilLoopResult r = RunHilLoop(
      [&] {
        sim.Tick(lockstep ? sim.devices().frames_per_tick().data() : nullptr, lockstep ? 100'000'000 : 0);
        return true;
      },
      lockstep, static_cast<std::int64_t>(model->tick_period_s * 1e9), limit, stop);
  const double sim_s = static_cast<double>(sim.tick()) * model->tick_period_s;
  std::printf("pbppo-hil: %.3f s simulated in %.3f s wall (%.3f simulated s per wall s), %llu overruns\n", sim_s,
              r.wall_s, sim_s / r.wall_s, static_cast<unsigned long long>(r.overruns));
  PrintDeviceSummary(sim.devices(), *model->can, sim.plant().q_rad());
  return 0;
}

}  // namespace pbppo::sim
