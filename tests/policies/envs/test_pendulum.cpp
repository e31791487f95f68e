// Pendulum against Gymnasium 0.29.1's Pendulum-v1: every row of the golden trace.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "policies/envs/pendulum.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::envs {
namespace {

struct Row {
  int traj = 0;
  int t = 0;
  float action = 0;
  double reward = 0;
  float obs[3] = {};
  double th = 0, thdot = 0;
  int terminated = 0, truncated = 0;
};

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, sep)) out.push_back(item);
  return out;
}

bool FloatClose(float got, float want) {
  const float tol = std::max(std::fabs(want) * std::numeric_limits<float>::epsilon(), 1e-12f);
  return std::fabs(got - want) <= tol;
}

std::unique_ptr<Pendulum> MakePendulum() {
  auto env = MakeEnv(EnvOptions{});
  REQUIRE_MESSAGE(env.ok(), (env.ok() ? "" : env.error().message));
  return std::unique_ptr<Pendulum>(static_cast<Pendulum*>(env.value().release()));
}

TEST_CASE("pendulum reproduces every row of the Gymnasium golden trace") {
  std::ifstream in(test::SourcePath("tests/data/pendulum_golden.csv"));
  REQUIRE(in.good());
  std::vector<std::pair<double, double>> initial;
  std::vector<Row> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("# initial states", 0) == 0) {
      // "# initial states (th0, thdot0) per traj: 0:(a,b); 1:(c,d); ..."
      const auto colon = line.find("traj:");
      for (const auto& part : Split(line.substr(colon + 5), ';')) {
        const auto open = part.find('('), comma = part.find(','), close = part.find(')');
        initial.emplace_back(std::stod(part.substr(open + 1, comma - open - 1)),
                             std::stod(part.substr(comma + 1, close - comma - 1)));
      }
      continue;
    }
    if (line.empty() || line[0] == '#' || line.rfind("traj", 0) == 0) continue;
    const auto f = Split(line, ',');
    REQUIRE(f.size() == 11);
    Row r;
    r.traj = std::stoi(f[0]);
    r.t = std::stoi(f[1]);
    r.action = std::stof(f[2]);
    r.reward = std::stod(f[3]);
    for (int i = 0; i < 3; ++i) r.obs[i] = std::stof(f[4 + i]);
    r.th = std::stod(f[7]);
    r.thdot = std::stod(f[8]);
    r.terminated = std::stoi(f[9]);
    r.truncated = std::stoi(f[10]);
    rows.push_back(r);
  }
  REQUIRE(initial.size() == 7);
  REQUIRE(rows.size() == 1400);

  // One step from each recorded state: every row within 1e-12 (observation to float32
  // rounding). NumPy's float64 sin (SIMD) and the C library's differ by up to 1 ulp, so each
  // step is compared from the golden state before it.
  auto env = MakePendulum();
  int checked = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    if (r.t == 0) {
      const auto& s0 = initial[static_cast<std::size_t>(r.traj)];
      env->SetState(s0.first, s0.second, 0);
    } else {
      env->SetState(rows[i - 1].th, rows[i - 1].thdot, static_cast<std::uint32_t>(r.t));
    }
    float obs[3];
    const StepResult s = env->Step({&r.action, 1}, obs);
    INFO("traj " << r.traj << " t " << r.t);
    CHECK(std::fabs(s.reward - r.reward) <= 1e-12);
    CHECK(std::fabs(env->theta() - r.th) <= 1e-12);
    CHECK(std::fabs(env->theta_dot() - r.thdot) <= 1e-12);
    for (int k = 0; k < 3; ++k) CHECK(FloatClose(obs[k], r.obs[k]));
    CHECK(s.terminated == (r.terminated != 0));
    CHECK(s.truncated == (r.truncated != 0));
    ++checked;
  }
  CHECK(checked == 1400);

  // Free-running over whole episodes: the 1-ulp sin differences grow only through the unstable
  // upright equilibrium (trajectory 2 starts there) and stay below 1e-9 over 200 steps.
  double worst = 0.0;
  for (const Row& r : rows) {
    if (r.t == 0) {
      const auto& s0 = initial[static_cast<std::size_t>(r.traj)];
      env->SetState(s0.first, s0.second, 0);
    }
    float obs[3];
    const StepResult s = env->Step({&r.action, 1}, obs);
    worst = std::max(
        {worst, std::fabs(s.reward - r.reward), std::fabs(env->theta() - r.th), std::fabs(env->theta_dot() - r.thdot)});
    CHECK(s.truncated == (r.truncated != 0));
  }
  CHECK(worst <= 1e-9);
}

TEST_CASE("pendulum reset draws from the documented ranges and is deterministic") {
  auto env = MakePendulum();
  Rng a(5), b(5);
  auto other = env->Clone();
  float oa[3], ob[3];
  for (int i = 0; i < 100; ++i) {
    env->Reset(a, oa);
    other->Reset(b, ob);
    CHECK(std::fabs(env->theta()) <= M_PI);
    CHECK(std::fabs(env->theta_dot()) <= 1.0);
    for (int k = 0; k < 3; ++k) CHECK(oa[k] == ob[k]);
  }
  CHECK(env->layout().Hash() != 0);
  CHECK(env->max_episode_steps() == 200);
}

TEST_CASE("angle normalisation follows Python's floored modulo") {
  CHECK(Pendulum::AngleNormalize(0.0) == doctest::Approx(0.0));
  CHECK(Pendulum::AngleNormalize(M_PI) == doctest::Approx(-M_PI));
  CHECK(Pendulum::AngleNormalize(-M_PI) == doctest::Approx(-M_PI));
  CHECK(Pendulum::AngleNormalize(3 * M_PI + 0.5) == doctest::Approx(-M_PI + 0.5));
  CHECK(Pendulum::AngleNormalize(-0.5) == doctest::Approx(-0.5));
}

TEST_CASE("unknown environments and mismatched layouts are refused with the name") {
  EnvOptions cartpole;
  cartpole.name = "cartpole";
  auto bad = MakeEnv(cartpole);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("'cartpole' unknown") != std::string::npos);
  auto layout = robot::ParseIoLayout(
      "robot: pendulum\nobservations:\n  - {name: a, signal: a}\nactions:\n  - {name: t, command: t, low: -1, high: "
      "1}\n",
      "inline");
  REQUIRE(layout.ok());
  auto env = Pendulum::Make(layout.value());
  REQUIRE_FALSE(env.ok());
  CHECK(env.error().message.find("observation size 1") != std::string::npos);
}

}  // namespace
}  // namespace pbppo::envs
