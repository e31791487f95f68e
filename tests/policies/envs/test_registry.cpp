// The environments' registrations: every flag is declared whole (help, refusal, a default its own
// check accepts), MakeEnv checks the flags it is given against them (naming the flag, the value and
// the environments that have it) and completes the rest with the defaults; summary.json's keys.
#include <doctest/doctest.h>

#include <set>
#include <string>

#include "policies/envs/registry.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using namespace pbppo::envs;

TEST_CASE("registry: every environment and flag is declared whole") {
  std::set<std::string> names;
  for (const EnvSpec& s : Environments()) {
    CAPTURE(s.name);
    CHECK(names.insert(s.name).second);
    CHECK_FALSE(s.description.empty());
    CHECK(static_cast<bool>(s.make));
    CHECK(FindEnv(s.name) == &s);
    std::set<std::string> flags;
    for (const EnvFlag& f : s.flags) {
      CAPTURE(f.name);
      CHECK(flags.insert(f.name).second);
      CHECK(f.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz-") == std::string::npos);
      CHECK_FALSE(f.help.empty());
      CHECK_FALSE(f.only.empty());
      CHECK(f.use != 0);
      if (f.carried_to_eval) CHECK(f.use == EnvFlag::kBoth);  // pbppo eval must take what sweep passes it
      if (!f.default_value.empty() && f.check) CHECK(f.check(f.default_value).ok());
      CHECK(FindFlag(s, f.name) == &f);
    }
  }
  CHECK(FindEnv("cartpole") == nullptr);
  // A flag several environments have is offered once, naming them all.
  bool through = false;
  for (const SharedFlag& f : FlagsFor(EnvFlag::kEval)) {
    CHECK(f.environments.size() == f.declarations.size());
    if (f.flag->name != "through-ends") continue;
    through = true;
    CHECK(f.environments == std::vector<std::string>{"hopper", "walker2d", "half-cheetah", "ant"});
  }
  CHECK(through);
  for (const SharedFlag& f : FlagsFor(EnvFlag::kTrain)) CHECK(f.flag->name != "through-ends");
}

TEST_CASE("registry: flags checked against the environment, defaults filled, typed in summary.json") {
  EnvOptions o;
  o.name = "auv-nav";
  o.models_dir = test::SourcePath("models");
  o.flags["extra-obstacles"] = "3";
  auto r = ResolveEnvOptions(o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  CHECK(FlagText(*r, "layout") == "hard");  // the default
  CHECK(FlagInteger(*r, "extra-obstacles") == 3);
  CHECK(FlagReal(*r, "exploring-starts") == 0.0);
  CHECK_FALSE(r->flags.contains("plot"));  // pbppo eval's, not taken in training
  const nlohmann::json j = FlagsJson(*r, EnvFlag::kTrain);
  CHECK(j["layout"] == "hard");
  CHECK(j["extra_obstacles"] == 3);
  CHECK(j["exploring_starts"] == 0.0);
  CHECK(j["progress"] == "");
  CHECK_FALSE(j.contains("plot"));

  auto error = [](EnvOptions e) {
    auto res = ResolveEnvOptions(e);
    REQUIRE_FALSE(res.ok());
    return res.error().message;
  };
  o.flags["extra-obstacles"] = "three";
  CHECK(error(o) == "--extra-obstacles: 'three' is not a whole number");
  o.flags["extra-obstacles"] = "1";
  o.flags["exploring-starts"] = "1.5";
  CHECK(error(o) == "--exploring-starts: 1.5 is not in [0, 1]");
  EnvOptions p;
  p.flags["layout"] = "easy";
  CHECK(error(p) == "--layout: only auv-nav has obstacle layouts, not 'pendulum'");
  p.flags = {{"wind", "3"}};
  CHECK(error(p) == "--wind: no environment has this flag");
  // pbppo eval's flags: refused in training, and for environments without them.
  EnvOptions w;
  w.name = "quadruped-walk";
  w.flags["randomize"] = "true";
  CHECK(error(w) == "--randomize: 'quadruped-walk' does not take it in pbppo train");
  w.purpose = EnvPurpose::kEval;
  auto eval = ResolveEnvOptions(w);
  REQUIRE_MESSAGE(eval.ok(), eval.error().message);
  CHECK(FlagSet(*eval, "randomize"));
  CHECK(FlagReal(*eval, "settle-s") == 1.0);
  EnvOptions pendulum;
  pendulum.purpose = EnvPurpose::kEval;
  pendulum.flags["through-ends"] = "true";
  CHECK(error(pendulum) ==
        "--through-ends: only hopper, walker2d, half-cheetah and ant step on after an episode ends, not 'pendulum'");
  pendulum.flags = {{"plot", "x.png"}};
  CHECK(error(pendulum) == "--plot: only auv-nav and quadruped-walk draw plots, not 'pendulum'");
  pendulum.name = "quadruped-walk";
  pendulum.flags = {{"settle-s", "-1"}};
  CHECK(error(pendulum) == "--settle-s: -1 is not in [0, 100]");
}
