#include "policies/cli/sweep_plan.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <string>

#include "policies/cli/train.hpp"
#include "policies/envs/registry.hpp"
#include "policies/trainer/options.hpp"

namespace pbppo::cli {
namespace {

Error Bad(const std::string& msg) {
  return MakeError(ErrorCode::kInvalidValue, msg);
}

// "KEY=V1,V2,...": the values split at ',' ('\,' is a comma inside a value); none empty, none twice.
Result<Axis> ParseAxis(const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos || eq == 0) return Bad("--grid '" + spec + "': expected KEY=VALUE[,VALUE...]");
  Axis a{spec.substr(0, eq), {""}};
  for (std::size_t i = eq + 1; i < spec.size(); ++i) {
    if (spec[i] == '\\' && i + 1 < spec.size() && spec[i + 1] == ',') {
      a.values.back() += ',';
      ++i;
    } else if (spec[i] == ',') {
      a.values.emplace_back();
    } else {
      a.values.back() += spec[i];
    }
  }
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    if (a.values[i].empty()) return Bad("--grid " + a.key + ": empty value in '" + spec + "'");
    if (std::find(a.values.begin(), a.values.begin() + static_cast<long>(i), a.values[i]) !=
        a.values.begin() + static_cast<long>(i))
      return Bad("--grid " + a.key + ": value '" + a.values[i] + "' given twice");
  }
  return a;
}

// "1-5", "1,3,7", "1-3,8": every seed once.
Result<std::vector<std::uint64_t>> ParseSeeds(const std::string& s) {
  std::vector<std::uint64_t> out;
  auto number = [&](const std::string& part, std::uint64_t* v) {
    if (part.empty() || part.find_first_not_of("0123456789") != std::string::npos || part.size() > 19) return false;
    *v = std::stoull(part);
    return true;
  };
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, ',')) {
    const auto dash = part.find('-');
    std::uint64_t a = 0, b = 0;
    if (!number(part.substr(0, dash), &a) || (dash != std::string::npos && !number(part.substr(dash + 1), &b)))
      return Bad("--seeds: '" + part + "' is not a seed or a range A-B");
    if (dash == std::string::npos) b = a;
    if (b < a || b - a >= 100000 || out.size() + (b - a) >= 100000)
      return Bad("--seeds: '" + part + "' is not a range A-B with A <= B (at most 100000 seeds)");
    for (std::uint64_t v = a; v <= b; ++v) {
      if (std::find(out.begin(), out.end(), v) != out.end())
        return Bad("--seeds: seed " + std::to_string(v) + " given twice");
      out.push_back(v);
    }
  }
  if (out.empty() || s.back() == ',') return Bad("--seeds: '" + s + "' names no seed");
  return out;
}

// A grid value as part of a folder name (after "KEY="): '%' and '/' percent-encoded.
std::string FileNamePart(const std::string& v) {
  std::string r;
  for (char c : v) r += c == '%' ? "%25" : c == '/' ? "%2F" : std::string(1, c);
  return r;
}

// ARGS through pbppo train's own parser (AddTrainOptions on a fresh CLI::App) into `o`: "" or the
// parser's message. `given`: the flags ARGS set, by name ("--out"). Without `out_required` --out may
// be missing (the shared flags alone).
std::string ParseTrain(const std::vector<std::string>& args, trainer::TrainOptions& o,
                       std::vector<std::string>* given = nullptr, bool out_required = true) {
  CLI::App app{"pbppo train"};
  bool quiet = false;
  AddTrainOptions(app, o, quiet);
  if (!out_required) app.get_option("--out")->required(false);
  for (const auto& a : args)
    if (a == "-h" || a == "--help") return a + ": not a run's flag (see pbppo train --help)";
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes the arguments last first
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  if (given != nullptr)
    for (const CLI::Option* opt : app.get_options())
      if (opt->count() > 0) given->push_back(opt->get_name());
  return "";
}

// `pbppo eval`'s flags for the environment a run trained on: its name, the models folder, and the
// flags the environment carries to its evaluation (its shape: a layout, a terrain), given or default.
std::vector<std::string> EvalEnvFlags(const envs::EnvOptions& e) {
  std::vector<std::string> f = {"--env=" + e.name};
  if (!e.models_dir.empty()) f.push_back("--models=" + e.models_dir);
  if (const envs::EnvSpec* spec = envs::FindEnv(e.name)) {
    for (const envs::EnvFlag& flag : spec->flags) {
      if (!flag.carried_to_eval) continue;
      const auto given = e.flags.find(flag.name);
      const std::string& v = given != e.flags.end() ? given->second : flag.default_value;
      if (!v.empty()) f.push_back("--" + flag.name + "=" + v);
    }
  }
  return f;
}

}  // namespace

std::string CellName(const Plan& p, std::size_t cell) {
  std::string s;
  for (std::size_t k = 0; k < p.axes.size(); ++k) s += (k ? " " : "") + p.axes[k].key + "=" + p.cells[cell][k];
  return s.empty() ? "(no grid)" : s;
}

// Every run's argument list, each checked with pbppo train's parser, its options with
// TrainOptions::Validate and the environment's with envs::MakeEnv; nothing is written.
Result<Plan> MakePlan(const SweepOptions& o) {
  Plan p;
  for (const auto& spec : o.grid) {
    auto a = ParseAxis(spec);
    if (!a) return std::move(a).error();
    for (const auto& b : p.axes)
      if (b.key == a->key) return Bad("--grid " + a->key + ": the key is given twice");
    p.axes.push_back(std::move(a).value());
  }
  auto seeds = ParseSeeds(o.seeds);
  if (!seeds) return std::move(seeds).error();
  p.seeds = std::move(seeds).value();

  // Grid keys are pbppo train's options; --out, --seed and --quiet are the sweep's to set.
  CLI::App probe;
  trainer::TrainOptions probe_options;
  bool probe_quiet = false;
  AddTrainOptions(probe, probe_options, probe_quiet);
  for (const auto& a : p.axes) {
    if (a.key == "out" || a.key == "seed" || a.key == "quiet")
      return Bad("--grid " + a.key + ": the sweep sets --" + a.key + " itself (seeds: --seeds)");
    if (a.key == "help" || a.key.rfind('-', 0) == 0 || probe.get_option_no_throw("--" + a.key) == nullptr)
      return Bad("--grid " + a.key + ": pbppo train has no option --" + a.key + " (write the key without dashes)");
  }
  {
    trainer::TrainOptions shared;
    std::vector<std::string> given;
    if (auto err = ParseTrain(o.train_flags, shared, &given, false); !err.empty())
      return Bad("train flags after --: " + err);
    for (const auto& g : given) {
      if (g == "--out" || g == "--seed" || g == "--quiet")
        return Bad("train flags after --: " + g + ": the sweep sets it for each run (" +
                   (g == "--out"    ? "DIR/KEY=VALUE/.../seed=N"
                    : g == "--seed" ? "--seeds"
                                    : "no progress line") +
                   ")");
      for (const auto& a : p.axes)
        if (g == "--" + a.key) return Bad("train flags after --: " + g + " is also a --grid key");
    }
  }
  // Each grid value on its own, so that a refusal names its key and value.
  for (const auto& a : p.axes) {
    for (const auto& v : a.values) {
      std::vector<std::string> args = o.train_flags;
      args.insert(args.end(), {"--" + a.key + "=" + v, "--seed=1", "--out=" + o.out});
      trainer::TrainOptions t;
      if (auto err = ParseTrain(args, t); !err.empty()) return Bad("--grid " + a.key + "=" + v + ": " + err);
      if ((a.key + "=" + FileNamePart(v)).size() > 255)
        return Bad("--grid " + a.key + "=" + v + ": too long for a folder name (255 bytes)");
    }
  }

  // The cells: every combination of the axes' values, the first axis outermost.
  p.cells.emplace_back();
  for (const auto& a : p.axes) {
    std::vector<std::vector<std::string>> next;
    for (const auto& c : p.cells)
      for (const auto& v : a.values) {
        next.push_back(c);
        next.back().push_back(v);
      }
    p.cells = std::move(next);
  }
  for (std::size_t c = 0; c < p.cells.size(); ++c) {
    std::string prefix;
    std::vector<std::string> grid_args;
    for (std::size_t k = 0; k < p.axes.size(); ++k) {
      prefix += p.axes[k].key + "=" + FileNamePart(p.cells[c][k]) + "/";
      grid_args.push_back("--" + p.axes[k].key + "=" + p.cells[c][k]);
    }
    for (std::uint64_t seed : p.seeds) {
      Run r;
      r.cell = c;
      r.seed = seed;
      r.rel = prefix + "seed=" + std::to_string(seed);
      const std::string dir = o.out + "/" + r.rel;
      r.train_args = {"train"};
      r.train_args.insert(r.train_args.end(), o.train_flags.begin(), o.train_flags.end());
      r.train_args.insert(r.train_args.end(), grid_args.begin(), grid_args.end());
      r.train_args.insert(r.train_args.end(), {"--seed=" + std::to_string(seed), "--out=" + dir, "--quiet"});
      trainer::TrainOptions t;
      std::string err = ParseTrain({r.train_args.begin() + 1, r.train_args.end()}, t);
      if (err.empty() && seed == p.seeds.front()) {  // the seed changes neither the options nor the environment
        if (auto st = t.Validate(); !st) err = st.error().message;
        if (auto env = envs::MakeEnv(t.env); err.empty() && !env) err = env.error().message;
      }
      if (!err.empty()) return Bad("grid cell " + CellName(p, c) + ": " + err);
      r.eval_args = {"eval", dir + "/policy.blob"};
      for (auto& f : EvalEnvFlags(t.env)) r.eval_args.push_back(std::move(f));
      r.eval_args.insert(r.eval_args.end(), {"--episodes=" + std::to_string(o.final_episodes),
                                             "--seed=" + std::to_string(o.eval_seed), "--json"});
      p.runs.push_back(std::move(r));
    }
  }

  Json grid = Json::array();
  for (const auto& a : p.axes) grid.push_back({{"key", a.key}, {"values", a.values}});
  p.record = {{"grid", grid},
              {"seeds", p.seeds},
              {"train_flags", o.train_flags},
              {"final_episodes", o.final_episodes},
              {"eval_seed", o.eval_seed}};
  return p;
}

}  // namespace pbppo::cli
