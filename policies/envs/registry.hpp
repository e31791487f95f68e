// The environments pbppo knows, each as one registration (EnvSpec): its name and description, its
// own flags (name, help, default, check), how it is built from them, and what `pbppo eval` adds
// for it. `pbppo train`, `pbppo eval` and `pbppo sweep` take every flag from here and never name an
// environment; adding one is its files and one line in Environments() (registry.cpp).
//
//   flags       EnvFlag: the flag's name (--layout), help, default, kind (text, number, switch),
//               where it is taken (pbppo train, pbppo eval, both), the check of a given value, and
//               what the refusal of an environment without it says ("--extra-obstacles: only
//               auv-nav has obstacles, not 'pendulum'"). Several environments may declare the same
//               flag (the MuJoCo tasks' --through-ends): the command line shows it once.
//   make        builds the environment from EnvOptions whose flags MakeEnv() checked and completed
//               with the defaults (FlagText / FlagReal / FlagInteger / FlagSet read them).
//   evaluation  pbppo eval runs the blob over episodes through the runtime's Forward; an
//               environment may hook into those episodes (auv-nav: trajectories, outcomes, a map;
//               the MuJoCo tasks: on through episode ends) or replace them by its own test
//               (quadruped-walk: the paper's test, a velocity schedule).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "policies/envs/env.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_model.hpp"

namespace pbppo::envs {

struct EnvFlag {
  enum class Kind : std::uint8_t {
    kText,     // any text the check accepts
    kReal,     // a number (summary.json: a number)
    kInteger,  // a whole number
    kSwitch,   // no value: given or not (summary.json: true or false)
  };
  enum Use : std::uint8_t { kTrain = 1, kEval = 2, kBoth = 3 };

  std::string name;  // "extra-obstacles": --extra-obstacles; summary.json's key "extra_obstacles"
  std::string help;  // shown after the environments that have it
  // Taken when the flag is not given; "" for none (switches: off).
  std::string default_value;
  Kind kind = Kind::kText;
  Use use = kBoth;
  // The refusal of an environment without this flag, after "only <environments>": "has obstacles".
  std::string only;
  // Checks a given value (after the kind's own check); the message follows "--<name>: ", e.g.
  // "'maze' unknown (easy, medium, hard, mixed)". Empty: any value of the kind.
  std::function<Status(const std::string&)> check;
  // pbppo sweep evaluates a run with the value it trained with (the environment's shape: a layout, a
  // terrain), given or default.
  bool carried_to_eval = false;
};

// A flag in one call, for the registrations' tables.
EnvFlag Flag(std::string name, EnvFlag::Use use, EnvFlag::Kind kind, std::string default_value, std::string only,
             std::string help, std::function<Status(const std::string&)> check = {}, bool carried_to_eval = false);

// Common checks.
std::function<Status(const std::string&)> OneOf(std::vector<std::string> values);
std::function<Status(const std::string&)> InRange(double low, double high);
// The value passes when `parse(value)` succeeds (a Result or a Status); its error is the message.
template <typename Parse>
std::function<Status(const std::string&)> ParsedBy(Parse parse) {
  return [parse](const std::string& v) -> Status {
    if (auto r = parse(v); !r) return r.error();
    return {};
  };
}

// --- pbppo eval ----------------------------------------------------------------------------------

// What pbppo eval hands an environment's evaluation.
struct EvalRequest {
  std::string blob;                            // the blob's path, for messages
  const policy::PolicyModel* model = nullptr;  // loaded and checked against the environment's layout
  const EnvOptions* env = nullptr;             // its flags, pbppo eval's included (checked, defaults filled)
  int episodes = 0;                            // --episodes; 0: the environment's default
  std::uint64_t seed = 7;
  bool json = false;
};

// pbppo eval's episodes as counted, for what hooks add at the end.
struct EvalTotals {
  int episodes = 0;
  std::uint64_t seed = 0;
  int successes = 0, failures = 0, timeouts = 0;
};

// What an environment adds to pbppo eval's episodes. Called with the environment after each
// Reset (step 0) and Step, and at each episode's end with its return.
class EpisodeHooks {
 public:
  virtual ~EpisodeHooks() = default;
  // true: every episode runs max_episode_steps(), stepping on through terminations.
  virtual bool through_ends() const noexcept { return false; }
  virtual void Started(int episode, const Env& env) {
    (void)episode;
    (void)env;
  }
  virtual void Stepped(int episode, long step, const Env& env) {
    (void)episode;
    (void)step;
    (void)env;
  }
  virtual void Ended(int episode, const Env& env, double episode_return) {
    (void)episode;
    (void)env;
    (void)episode_return;
  }
  // After the last episode: keys for --json (`json`), lines for the text report (`text`). A
  // problem that does not spoil the evaluation (a plot that could not be drawn) is returned.
  virtual std::string Finish(const Env& env, const EvalTotals& totals, nlohmann::json& json, std::string& text) {
    (void)env;
    (void)totals;
    (void)json;
    (void)text;
    return {};
  }
};

struct EnvEvaluation {
  int default_episodes = 100;
  std::string episodes_are = "episodes";  // what --episodes counts ("robots")
  // Replaces pbppo eval's episodes (quadruped-walk: the paper's test): prints the report and returns
  // the exit status. Empty: the episodes, with `hooks`.
  std::function<int(const EvalRequest&, Env&)> run;
  // What the environment adds to the episodes; an error (a flag's bad value, a file that cannot be
  // written) refuses the evaluation (exit 2) and names the flag. Empty: nothing.
  std::function<Result<std::unique_ptr<EpisodeHooks>>(const EvalRequest&, Env&)> hooks;
};

// --- the registry --------------------------------------------------------------------------------

struct EnvSpec {
  std::string name;         // --env
  std::string description;  // pbppo's help
  std::vector<EnvFlag> flags;
  std::function<Result<std::unique_ptr<Env>>(const EnvOptions&)> make;
  EnvEvaluation evaluation;
};

// A concrete environment's Make() result as an Env's (the registrations' factories).
template <typename T>
Result<std::unique_ptr<Env>> AsEnv(Result<std::unique_ptr<T>> made) {
  if (!made) return std::move(made).error();
  return std::unique_ptr<Env>(std::move(made).value());
}

// Every environment, in the order of pbppo's help.
const std::vector<EnvSpec>& Environments();
// The environment `name`, nullptr if none.
const EnvSpec* FindEnv(const std::string& name) noexcept;
// The flag `name` of `spec`, nullptr if it has none.
const EnvFlag* FindFlag(const EnvSpec& spec, const std::string& name) noexcept;

// Every flag of some environment taken by `use` (kTrain: pbppo train; kEval: pbppo eval), once
// each (the first declaration), and the environments that have it.
struct SharedFlag {
  const EnvFlag* flag = nullptr;
  std::vector<std::string> environments;     // that have it
  std::vector<const EnvFlag*> declarations;  // each one's declaration
};
std::vector<SharedFlag> FlagsFor(EnvFlag::Use use);

// `options` checked (the environment, each given flag: its environment has it for this purpose,
// its value) and completed with the defaults of the flags not given. Errors name the flag and the
// value.
Result<EnvOptions> ResolveEnvOptions(const EnvOptions& options);

// Reading the flags of resolved options (the checks passed): "" / 0 / false where not given and
// without default.
std::string FlagText(const EnvOptions& options, const std::string& name);
double FlagReal(const EnvOptions& options, const std::string& name);
long FlagInteger(const EnvOptions& options, const std::string& name);
bool FlagSet(const EnvOptions& options, const std::string& name);

// The environment's flags of resolved options as summary.json records them: every flag of the
// environment taken by `use`, by its key (dashes as underscores), typed by its kind.
nlohmann::json FlagsJson(const EnvOptions& options, EnvFlag::Use use);

// The models folder of `options` (--models, else DefaultModelsDir()).
std::string ModelsDir(const EnvOptions& options);

}  // namespace pbppo::envs
