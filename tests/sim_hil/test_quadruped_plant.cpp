// The quadruped stand plant: loads from the URDF, hangs under gravity, holds a pose under joint
// PD torques, is bit-for-bit deterministic, and reports its speed.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "runtime/robot/urdf.hpp"
#include "sim_hil/plants/quadruped_plant.hpp"
#include "tests/support/test_paths.hpp"

using pbppo::sim::QuadrupedPlant;

namespace {

pbppo::robot::RobotDescription Robot() {
  auto d = pbppo::robot::LoadRobotDescription(pbppo::test::SourcePath("models/quadruped/quadruped.yaml"));
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  return *d;
}

std::unique_ptr<QuadrupedPlant> Plant(const pbppo::robot::RobotDescription& d) {
  auto p = QuadrupedPlant::Make(d);
  REQUIRE_MESSAGE(p.ok(), p.error().message);
  return std::move(*p);
}

// Joint PD toward q_des, evaluated once per tick.
void Pd(QuadrupedPlant& p, const std::vector<double>& q_des, double kp, double kd, std::vector<double>& tau) {
  for (std::size_t i = 0; i < p.joint_count(); ++i) tau[i] = kp * (q_des[i] - p.q_rad(i)) - kd * p.dq_rad_s(i);
  p.SetJointTorques(tau.data(), tau.size());
}

}  // namespace

TEST_CASE("stand plant: one tick advances 1 ms - a bent knee falls under gravity with zero torque") {
  const auto d = Robot();
  auto p = Plant(d);
  REQUIRE(p->joint_count() == 12);
  REQUIRE(p->Reset(d.default_q_rad, std::vector<double>(12, 0.0)).ok());
  REQUIRE(p->Step());
  CHECK(p->tick() == 1);
  CHECK(p->time_s() == doctest::Approx(1e-3));
  for (int i = 0; i < 199; ++i) REQUIRE(p->Step());
  CHECK(p->time_s() == doctest::Approx(0.2));
  // Front knee at -0.8 rad (shank pointing forward) swings back toward hanging (q -> 0).
  CHECK(p->q_rad(2) > -0.8 + 0.05);
  // Hind knee at +0.8 swings toward 0 too.
  CHECK(p->q_rad(8) < 0.8 - 0.05);
  // The legs hang outboard of the HAA axes: left and right legs swing as mirror images.
  CHECK(std::abs(p->q_rad(0)) > 1e-3);
  CHECK(p->q_rad(0) == doctest::Approx(-p->q_rad(3)).epsilon(1e-9));
  CHECK(p->q_rad(6) == doctest::Approx(-p->q_rad(9)).epsilon(1e-9));
}

TEST_CASE("stand plant: joint PD holds the default pose within a few mrad of the gravity sag") {
  const auto d = Robot();
  auto p = Plant(d);
  std::vector<double> tau(12, 0.0);
  for (int i = 0; i < 2000; ++i) {
    Pd(*p, d.default_q_rad, 200.0, 3.0, tau);
    REQUIRE(p->Step());
  }
  for (std::size_t j = 0; j < 12; ++j) {
    INFO(d.joint_names[j]);
    CHECK(std::abs(p->q_rad(j) - d.default_q_rad[j]) < 0.05);  // sag <= (m g l) / kp
    CHECK(std::abs(p->dq_rad_s(j)) < 1e-3);
  }
}

TEST_CASE("stand plant: bit-for-bit deterministic - and its speed") {
  const auto d = Robot();
  auto a = Plant(d);
  auto b = Plant(d);
  std::vector<double> ta(12), tb(12), q_des(12);
  const int kTicks = 2000;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < kTicks; ++k) {
    for (std::size_t j = 0; j < 12; ++j) q_des[j] = d.default_q_rad[j] + 0.2 * std::sin(0.003 * k * (1.0 + 0.1 * j));
    Pd(*a, q_des, 60.0, 1.5, ta);
    REQUIRE(a->Step());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (int k = 0; k < kTicks; ++k) {
    for (std::size_t j = 0; j < 12; ++j) q_des[j] = d.default_q_rad[j] + 0.2 * std::sin(0.003 * k * (1.0 + 0.1 * j));
    Pd(*b, q_des, 60.0, 1.5, tb);
    REQUIRE(b->Step());
  }
  for (std::size_t j = 0; j < 12; ++j) {
    CHECK(a->q_rad(j) == b->q_rad(j));
    CHECK(a->dq_rad_s(j) == b->dq_rad_s(j));
  }
  std::printf("stand plant: %d ticks (%.1f s simulated) in %.3f s wall: %.1f simulated s per wall s, %.1f us/tick\n",
              kTicks, kTicks * 1e-3, wall, kTicks * 1e-3 / wall, wall / kTicks * 1e6);
}
