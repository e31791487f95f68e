#include "policies/cli/train.hpp"

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "policies/cli/process_group.hpp"
#include "policies/envs/registry.hpp"
#include "policies/trainer/checkpoint.hpp"
#include "policies/trainer/exporter.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/core/clock.hpp"

namespace pbppo::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<std::int64_t> g_first_sigint_ns{0};
static_assert(std::atomic<std::int64_t>::is_always_lock_free, "used from a signal handler");

// The first SIGINT or SIGTERM asks for a clean stop (log, summary, checkpoint, resume.bin). A second
// one ends the process at once, but only when it comes more than a second later: `timeout -s INT`
// and a terminal's job control can deliver the same interrupt twice (to the process and to its
// group), which must not kill the run.
extern "C" void OnSigint(int) {
  const std::int64_t now = MonotonicNs();  // clock_gettime only: async-signal-safe
  const std::int64_t first = g_first_sigint_ns.load();
  if (first == 0) {
    g_first_sigint_ns.store(now);
    g_stop.store(true);
    return;
  }
  if (now - first < 1'000'000'000) return;
  std::signal(SIGINT, SIG_DFL);
  std::raise(SIGINT);
}

int Fail(const std::string& msg, int rc = 2) {
  std::fprintf(stderr, "pbppo train: %s\n", msg.c_str());
  return rc;
}

// "64-64" -> {64, 64}, each width in [1, 2048]; an error names the flag and the bad part.
std::vector<int> ParseWidths(const std::string& flag, const std::string& s) {
  std::vector<int> out;
  std::size_t pos = 0;
  while (pos <= s.size()) {
    const auto dash = s.find('-', pos);
    const std::string part = s.substr(pos, dash == std::string::npos ? std::string::npos : dash - pos);
    char* end = nullptr;
    const long v = std::strtol(part.c_str(), &end, 10);
    if (part.empty() || *end != '\0' || v < 1 || v > 2048)
      throw CLI::ValidationError(flag, "'" + part + "' is not a width in [1, 2048]");
    out.push_back(static_cast<int>(v));
    if (dash == std::string::npos) break;
    pos = dash + 1;
  }
  return out;
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string Human(double v) {
  char buf[32];
  if (v >= 1e6) {
    std::snprintf(buf, sizeof buf, "%.2fM", v / 1e6);
  } else if (v >= 1e3) {
    std::snprintf(buf, sizeof buf, "%.1fk", v / 1e3);
  } else {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  }
  return buf;
}

}  // namespace

void AddEnvOptions(CLI::App& s, envs::EnvOptions& env, envs::EnvFlag::Use use) {
  std::string names;
  for (const envs::EnvSpec& e : envs::Environments())
    names += (names.empty() ? "" : ", ") + e.name + " (" + e.description + ")";
  s.add_option("--env", env.name, "Environment: " + names)->default_str(env.name);
  s.add_option("--models", env.models_dir, "Models folder (default: the source tree's models/)");
  // Every environment's own flags, each once; the environment checks them (envs::MakeEnv).
  for (const envs::SharedFlag& f : envs::FlagsFor(use)) {
    const std::string name = f.flag->name;
    std::string help;
    bool same_help = true, same_default = true;
    for (const envs::EnvFlag* d : f.declarations) {
      same_help = same_help && d->help == f.flag->help;
      same_default = same_default && d->default_value == f.flag->default_value;
    }
    for (std::size_t k = 0; k < f.environments.size(); ++k) {
      if (same_help) {
        help += (k == 0 ? "" : ", ") + f.environments[k];
      } else {
        help += (k == 0 ? "" : "; ") + f.environments[k] + ": " + f.declarations[k]->help;
      }
    }
    if (same_help) help += ": " + f.flag->help;
    CLI::Option* opt = nullptr;
    if (f.flag->kind == envs::EnvFlag::Kind::kSwitch) {
      opt = s.add_flag_callback("--" + name, [&env, name] { env.flags[name] = "true"; }, help);
    } else {
      opt = s.add_option_function<std::string>(
          "--" + name, [&env, name](const std::string& v) { env.flags[name] = v; }, help);
      if (same_default && !f.flag->default_value.empty()) opt->default_str(f.flag->default_value);
      if (f.flag->kind == envs::EnvFlag::Kind::kReal) opt->type_name("FLOAT");
      if (f.flag->kind == envs::EnvFlag::Kind::kInteger) opt->type_name("INT");
    }
  }
}

void AddTrainOptions(CLI::App& s, trainer::TrainOptions& o, bool& quiet, std::string* resume) {
  AddEnvOptions(s, o.env, envs::EnvFlag::kTrain);

  // The clip schedule: --schedule and --arms make it (ParseSchedule, with the mode's default
  // bandit weights), the bandit flags adjust it; resolved once every flag is read.
  struct ScheduleFlags {
    std::string schedule = "pbppo", arms = "0.02:0.5:6";
    double lambda = -1, gamma = -1;  // < 0: the schedule's default
  };
  auto flags = std::make_shared<ScheduleFlags>();
  s.add_option("--schedule", flags->schedule,
               "Clip schedule: fixed:EPS, pbppo-paper[:wi-ad|:wo-ad], pbppo-reference[:wi-ad|:wo-ad], pbppo")
      ->default_str(flags->schedule);
  s.add_option("--arms", flags->arms, "Candidate clip bounds: MIN:MAX:N (linspace) or a,b,c; each in [0, 1]")
      ->default_str(flags->arms);
  s.add_option_function<std::string>(
      "--feedback",
      [&o](const std::string& v) {
        if (v == "eval") {
          o.schedule.feedback = trainer::FeedbackSource::kEval;
        } else if (v == "rollout") {
          o.schedule.feedback = trainer::FeedbackSource::kRollout;
        } else {
          throw CLI::ValidationError("--feedback", "'" + v + "' unknown (eval or rollout)");
        }
      },
      "Bandit feedback: eval (k deterministic episodes, the default) or rollout");
  o.schedule.feedback = trainer::FeedbackSource::kEval;
  s.add_option("--eval-episodes", o.schedule.eval_episodes, "k, evaluation episodes per iteration (eval feedback)");
  s.add_option("--bandit-lambda", flags->lambda, "Exploration weight (default: 5 paper/reference, 1 pbppo)");
  s.add_option("--bandit-gamma", flags->gamma, "Bandit discount (default: 0.99 paper/reference, 0.95 pbppo)");
  s.final_callback([&o, flags] {
    std::vector<double> arms;
    if (flags->schedule.rfind("fixed", 0) != 0) {
      auto a = trainer::ParseArms(flags->arms);
      if (!a) throw CLI::ValidationError(a.error().message);
      arms = a.value();
    }
    auto sc = trainer::ParseSchedule(flags->schedule, arms);
    if (!sc) throw CLI::ValidationError(sc.error().message);
    sc->feedback = o.schedule.feedback;
    sc->eval_episodes = o.schedule.eval_episodes;
    if (flags->lambda >= 0) sc->lambda = flags->lambda;
    if (flags->gamma >= 0) {
      if (flags->gamma > 1) throw CLI::ValidationError("--bandit-gamma", Number(flags->gamma) + " is not in [0, 1]");
      sc->gamma = flags->gamma;
    }
    o.schedule = sc.value();
  });

  s.add_option_function<double>(
       "--steps",
       [&o](double v) {
         if (!(v >= 1 && v <= 1e12)) throw CLI::ValidationError("--steps", Number(v) + " is not in [1, 1e12]");
         o.total_steps = static_cast<std::uint64_t>(std::llround(v));
       },
       "Training environment steps (e.g. 2e5)")
      ->default_str("2e5");
  o.total_steps = 200000;
  s.add_option("--seed", o.seed, "Seed")->check(cli_checks::NonNegativeInteger());
  s.add_option("--out", o.out_dir,
               "Output folder (log.csv, summary.json, policy.blob, plots); required unless --resume");
  // Sizes and PPO's coefficients: (flag, variable, help) each.
  using IntOption = std::tuple<const char*, int*, const char*>;
  for (auto [flag, value, help] : {IntOption{"--threads", &o.threads,
                                             "Worker threads: the environments' steps and the update (whose "
                                             "result does not depend on the count)"},
                                   IntOption{"--envs", &o.num_envs, "Parallel environments"},
                                   IntOption{"--rollout", &o.rollout_steps, "Steps per environment and iteration"},
                                   IntOption{"--minibatch", &o.minibatch, "Minibatch size"},
                                   IntOption{"--epochs", &o.epochs, "Epochs per iteration"}})
    s.add_option(flag, *value, help);
  using RealOption = std::tuple<const char*, double*, const char*>;
  for (auto [flag, value, help] :
       {RealOption{"--lr", &o.learning_rate,
                   "Adam learning rate (the first one with --lr-schedule anneal or adaptive)"},
        RealOption{"--gamma", &o.gamma, "Discount"}, RealOption{"--gae-lambda", &o.gae_lambda, "GAE lambda"},
        RealOption{"--ent-coef", &o.ent_coef, "Entropy coefficient"},
        RealOption{"--vf-coef", &o.vf_coef, "Value loss coefficient"},
        RealOption{"--max-grad-norm", &o.max_grad_norm, "Global gradient-norm clip (<= 0: off)"},
        RealOption{"--clip-vf", &o.clip_vf, "Value clipping range (<= 0: off)"},
        RealOption{"--log-std-init", &o.log_std_init, "Initial log standard deviation"}})
    s.add_option(flag, *value, help);
  s.add_option_function<std::string>(
       "--lr-schedule",
       [&o](const std::string& v) {
         auto sched = trainer::ParseLrSchedule(v);
         if (!sched) throw CLI::ValidationError(sched.error().message);
         o.lr_schedule = sched.value();
       },
       "Learning rate over the run: constant; anneal (linear to 0 over the budget); adaptive[:KL] (rsl_rl's: "
       "/1.5 when the policy's KL divergence exceeds 2 KL, x1.5 below KL/2, within [1e-5, 1e-2]; KL 0.01)")
      ->default_str("constant");
  s.add_flag("--keep-best", o.keep_best, "Also write best.blob: the policy of the best last-100-episode return");
  s.add_option("--snapshots", o.snapshots,
               "Also write N blobs evenly spaced over the run into OUT/snapshots/ (named by training steps), "
               "to choose among on held-out episodes (tools/select_*.sh)");
  s.add_option_function<std::string>(
       "--hidden", [&o](const std::string& v) { o.policy_hidden = ParseWidths("--hidden", v); },
       "Policy hidden widths, e.g. 64-64")
      ->default_str("64-64");
  s.add_option_function<std::string>(
      "--value-hidden", [&o](const std::string& v) { o.value_hidden = ParseWidths("--value-hidden", v); },
      "Value network hidden widths (default: --hidden)");
  s.add_option_function<std::string>(
       "--activation",
       [&o](const std::string& v) {
         if (!policy::ParseActivation(v, &o.activation))
           throw CLI::ValidationError("--activation", "'" + v + "' unknown (tanh, elu, relu, identity)");
         if (o.activation == policy::Activation::kLeakyRelu)
           throw CLI::ValidationError("--activation", "'" + v + "' is not trainable here (tanh, elu, relu, identity)");
       },
       "Hidden activation: tanh, elu, relu, identity")
      ->default_str("tanh");
  s.add_flag("--normalize-obs", o.normalize_observations,
             "Running observation normalisation (the actor's is frozen into the blob; a privileged critic "
             "observation gets its own)");
  s.add_flag("--scale-rewards", o.scale_rewards, "Scale rewards by the running std of the discounted return");
  s.add_flag_callback(
      "--no-adv-norm", [&o] { o.normalize_advantages = false; }, "No per-minibatch advantage normalisation");
  s.add_flag_callback("--no-plots", [&o] { o.plots = false; }, "Do not draw the curves");
  s.add_option("--checkpoint-seconds", o.checkpoint_seconds, "Seconds between checkpoint blobs");
  s.add_option("--critic-warmup", o.critic_warmup,
               "With --init: the first N iterations train only the (fresh) value network, the policy is held");
  s.add_option("--init", o.init_blob,
               "Start from this blob's policy and observation normaliser (same IO layout, --hidden and "
               "--activation; value network and log-std start fresh), e.g. to continue on a harder layout");
  s.add_flag("--quiet", quiet, "No progress line");
  s.add_option("--resume-every", o.resume_every,
               "Iterations between the resumable states written to OUT/resume.bin (also written at a stop; 0: never)")
      ->check(CLI::NonNegativeNumber);
  if (resume != nullptr) {
    s.add_option("--resume", *resume,
                 "Continue the stopped run in this folder from its resume.bin, with its own options (--threads and "
                 "--quiet may be given; any ranks and threads give the same weights as the run uninterrupted)");
  }
}

namespace {

// `pbppo train --resume DIR`: the run's options from DIR/resume.bin's arguments, read as the command
// line reads them; --threads from this command line if given. Errors name the flag or the file.
// `say`: this process prints the warning of another build (rank 0 alone does).
Result<trainer::TrainOptions> ResumeOptions(const std::string& dir, const std::vector<std::string>& args,
                                            const trainer::TrainOptions& given, bool* quiet, bool say) {
  auto refuse = [](const std::string& what) { return MakeError(ErrorCode::kInvalidValue, "--resume: " + what); };
  bool threads_given = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const std::string name = a.substr(0, a.find('='));
    if (name == "--resume" || name == "--threads") {
      threads_given |= name == "--threads";
      if (a.find('=') == std::string::npos) ++i;  // its value
    } else if (name != "--quiet") {
      return refuse(
          "the run's options are those its resume.bin recorded; only --threads and --quiet may be given "
          "with it, not '" +
          a + "'");
    }
  }
  const std::string path = dir + "/" + trainer::kResumeFile;
  if (!std::filesystem::exists(path)) {
    if (std::filesystem::exists(dir + "/summary.json"))
      return refuse("the run in '" + dir + "' finished (summary.json, no " + trainer::kResumeFile +
                    "): nothing to resume");
    return refuse("'" + path + "' does not exist (a run writes it every --resume-every iterations and at a stop)");
  }
  auto file = trainer::ReadResumeFile(path);
  if (!file) return refuse(file.error().message);
  if (say && file->git_revision != trainer::BuildGitRevision()) {
    std::fprintf(stderr,
                 "pbppo train: --resume: '%s' was written by build %s, this is %s: the run continues, but its weights "
                 "may differ from the first build's run uninterrupted\n",
                 path.c_str(), file->git_revision.c_str(), trainer::BuildGitRevision());
  }
  trainer::TrainOptions o;
  bool recorded_quiet = false;
  CLI::App app{"pbppo train"};
  AddTrainOptions(app, o, recorded_quiet, nullptr);
  try {
    app.parse(std::vector<std::string>(file->args.rbegin(), file->args.rend()));
  } catch (const CLI::ParseError& e) {
    return refuse("'" + path + "' holds arguments this build refuses: " + e.what());
  }
  o.out_dir = dir;  // the folder it is in, wherever the run was started from
  if (threads_given) o.threads = given.threads;
  o.command_args = std::move(file->args);
  o.resume_state = std::move(file->state);
  *quiet = *quiet || recorded_quiet;
  return o;
}

}  // namespace

int Train(trainer::TrainOptions o, bool quiet, const std::string& resume, const std::vector<std::string>& args) {
  // Under mpirun: one run over the job's ranks (data-parallel); rank 0 prints and writes. Every rank
  // reads the same arguments, so a refusal is every rank's, printed once.
  const ProcessGroup group;
  if (group.size() > 1) o.group = &group;
  const bool writer = group.rank() == 0;
  auto refuse = [&](const std::string& msg) { return writer ? Fail(msg) : 2; };
  if (!resume.empty()) {
    auto resumed = ResumeOptions(resume, args, o, &quiet, writer);
    if (!resumed) return refuse(resumed.error().message);
    o = std::move(*resumed);
    o.group = group.size() > 1 ? &group : nullptr;
  } else {
    if (o.out_dir.empty()) return refuse("--out is required (or --resume DIR)");
    o.command_args = args;
  }
  // Every option checked before the run starts (bad input: exit 2).
  if (auto st = o.Validate(); !st) return refuse(st.error().message);
  auto env = envs::MakeEnv(o.env);
  if (!env) return refuse(env.error().message);

  g_stop.store(false);
  g_first_sigint_ns.store(0);
  o.stop = &g_stop;
  auto previous = std::signal(SIGINT, OnSigint);
  auto previous_term = std::signal(SIGTERM, OnSigint);  // mpirun's Ctrl-C, a scheduler's notice
  auto last_print = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  bool printed = false;
  auto progress = [&](const trainer::Progress& p) {
    if (quiet || !writer) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_print < std::chrono::milliseconds(250) && p.env_steps < p.total_steps) return;
    last_print = now;
    printed = true;
    char success[32] = "";
    if (std::isfinite(p.task_success)) std::snprintf(success, sizeof success, "  success %.0f%%", 100 * p.task_success);
    char tracking[64] = "";
    if (std::isfinite(p.tracking_error[0]))
      std::snprintf(tracking, sizeof tracking, "  |error| vx %.2f vy %.2f yaw %.2f", p.tracking_error[0],
                    p.tracking_error[1], p.tracking_error[2]);
    std::fprintf(stderr, "\r%s/%s steps  %s steps/s  ETA %.0fs  return %.1f%s%s  eps %.3f   ",
                 Human(static_cast<double>(p.env_steps)).c_str(), Human(static_cast<double>(p.total_steps)).c_str(),
                 Human(p.steps_per_second).c_str(), p.eta_seconds, p.mean_return, success, tracking, p.epsilon);
    std::fflush(stderr);
  };
  if (writer) {
    std::fprintf(stderr, "pbppo train: %s, %s, seed %llu, %d rank%s x %d thread%s -> %s\n", o.env.name.c_str(),
                 o.schedule.Describe().c_str(), static_cast<unsigned long long>(o.seed), group.size(),
                 group.size() == 1 ? "" : "s", o.threads, o.threads == 1 ? "" : "s", o.out_dir.c_str());
  }
  // A rank that fails ends the job: the others would wait for it in the next exchange.
  auto failed = [&](const std::string& msg) {
    if (printed) std::fprintf(stderr, "\n");
    const std::string where = group.size() > 1 ? " (rank " + std::to_string(group.rank()) + ")" : "";
    Fail(msg + where, 1);
    if (group.size() > 1) group.Abort(1);
    return 1;
  };
  Result<trainer::TrainResult> r = MakeError(ErrorCode::kInvalidValue, "not run");
  try {
    r = trainer::Train(o, std::move(env).value(), progress);
  } catch (const std::exception& e) {
    return failed(e.what());
  }
  std::signal(SIGINT, previous);
  std::signal(SIGTERM, previous_term);
  if (printed) std::fprintf(stderr, "\n");
  if (!r) return failed(r.error().message);
  if (!writer) return r->interrupted ? 130 : 0;
  std::printf("env steps %llu (+ %llu evaluation steps = %llu)  wall %.1f s  %.0f steps/s\n",
              static_cast<unsigned long long>(r->env_steps), static_cast<unsigned long long>(r->eval_steps),
              static_cast<unsigned long long>(r->env_steps + r->eval_steps), r->wall_seconds, r->steps_per_second);
  std::printf("final return (last 100 training episodes) %.2f\n", r->final_return);
  const trainer::TimeShares& t = r->time;
  std::printf(
      "time: rollout %.1f s (actor %.1f, environments %.1f, first thread), returns %.1f, update %.1f, evaluation "
      "%.1f, ranks exchanging %.1f, other %.1f\n",
      t.rollout, t.rollout_policy, t.rollout_env, t.returns, t.update, t.evaluation, t.exchange, t.other);
  std::printf("blob %s/policy.blob\n%s\n", o.out_dir.c_str(), r->plots_note.c_str());
  if (r->interrupted) {
    std::fprintf(stderr,
                 "pbppo train: interrupted; log and last checkpoint are in %s (continue: pbppo train --resume %s)\n",
                 o.out_dir.c_str(), o.out_dir.c_str());
    return 130;
  }
  return 0;
}

}  // namespace pbppo::cli
