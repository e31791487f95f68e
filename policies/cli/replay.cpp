#include "policies/cli/replay.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>

#include "runtime/loop/replay.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/policy/kernel_option.hpp"

namespace pbppo::cli {
namespace {

int Fail(const std::string& msg) {
  std::fprintf(stderr, "pbppo replay: %s\n", msg.c_str());
  return 1;
}

}  // namespace

CLI::App* AddReplay(CLI::App& app, ReplayOptions& o) {
  auto* c = app.add_subcommand("replay", "Replay a recorded controller log and compare the commands bit for bit");
  c->add_option("log", o.log, "Log written by pbppo-controller --record")->required();
  c->add_option("--robot", o.robot, "The robot of the recording: a name or its robot.yaml")->required();
  c->add_option("--policy", o.policy, "The recording's policy blob");
  c->add_option("--trajectory", o.trajectory, "The recording's joint trajectory file");
  c->add_option("--out", o.out, "Write the replayed commands (one line per tick, hexadecimal floats)");
  policy::AddKernelOption(*c, o.kernel)
      ->description("The recording's forward kernel (pbppo-controller --kernel; auto: this CPU's fastest)");
  return c;
}

int Replay(const ReplayOptions& o) {
  // A recording cut short (a full disk, a crash) replays up to its last whole record.
  auto log = loop::ReadLog(o.log, loop::LogTail::kAcceptCut);
  if (!log) return Fail(log.error().message);
  auto robot = robot::LoadRobotModel(o.robot);
  if (!robot) return Fail(robot.error().message);
  const loop::SourceKind kind = log->header.source;
  if (kind == loop::SourceKind::kPolicy && o.policy.empty())
    return Fail(o.log + ": recorded with a policy: give it with --policy");
  if (kind == loop::SourceKind::kTrajectory && o.trajectory.empty())
    return Fail(o.log + ": recorded with a trajectory: give it with --trajectory");
  if (kind == loop::SourceKind::kNone && !(o.policy.empty() && o.trajectory.empty()))
    return Fail(o.log + ": recorded without a command source: no --policy or --trajectory");
  // The self-test ran when the recording armed; a replay compares the commands instead.
  auto source = loop::LoadSource(*robot, {o.policy, o.trajectory, false, policy::KernelOption(o.kernel)});
  if (!source) return Fail(source.error().message);
  auto r = loop::Replay(*robot, *log, source->source.get(), source->hash);
  if (!r) return Fail(r.error().message);
  if (!o.out.empty()) {
    std::ofstream f(o.out);
    f << loop::FormatOutputs(*robot, r->outputs);
    if (!f) return Fail("--out: cannot write '" + o.out + "'");
  }
  std::printf("replay: %s: %llu ticks, %llu commands compared, %llu different%s%s\n", o.log.c_str(),
              static_cast<unsigned long long>(r->ticks), static_cast<unsigned long long>(r->compared),
              static_cast<unsigned long long>(r->mismatches), r->mismatches != 0 ? "; first: " : "",
              r->first_mismatch.c_str());
  if (!log->complete)
    std::printf("replay: %s ends early, at offset %zu: %s; the %zu whole records before it were replayed\n",
                o.log.c_str(), log->cut_at, log->cut_reason.c_str(), log->records.size());
  else if (log->end != loop::LogEnd::kStopped)
    std::printf("replay: %s ends where its recording stopped: %s; the %zu whole records before it were replayed\n",
                o.log.c_str(), loop::DescribeEnd(*log).c_str(), log->records.size());
  if (r->compared == 0) return Fail(o.log + ": no command to compare (no whole tick recorded)");
  return r->mismatches == 0 ? 0 : 1;
}

}  // namespace pbppo::cli
