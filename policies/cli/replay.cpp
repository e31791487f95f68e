#include "policies/cli/replay.hpp"

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

#include "runtime/loop/policy_source.hpp"
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
  c->add_option("log", o.logs,
                "Log written by pbppo-controller --record; several: files of one rotated recording, in order")
      ->required();
  c->add_option("--robot", o.robot, "The robot of the recording: a name or its robot.yaml")->required();
  c->add_option("--policy", o.policy, "The recording's policy blob");
  c->add_option_function<std::string>(
       "--switch-policy", [&o](const std::string& blob) { o.switch_policies.push_back(blob); },
       "The recording's other policies (pbppo-controller --switch-policy), in the same order")
      ->trigger_on_parse();
  c->add_option("--trajectory", o.trajectory, "The recording's joint trajectory file");
  c->add_option("--out", o.out, "Write the replayed commands (one line per tick, hexadecimal floats)");
  auto* trace = c->add_option("--trace", o.trace,
                              "Write a CSV row per tick: tick, phase, mode and the robot's fields as it held them");
  c->add_option("--trace-fields", o.trace_fields, "The fields of --trace (default: every field)")
      ->delimiter(',')
      ->needs(trace);
  c->add_option("--policy-io", o.policy_io,
                "Write each policy run's observation and action as float32 rows to PREFIX.obs.f32 and "
                "PREFIX.act.f32 (to run the same inputs through another implementation)");
  policy::AddKernelOption(*c, o.kernel)
      ->description("The recording's forward kernel (pbppo-controller --kernel; auto: this CPU's fastest)");
  return c;
}

int Replay(const ReplayOptions& o) {
  auto robot = robot::LoadRobotModel(o.robot);
  if (!robot) return Fail(robot.error().message);
  // The trace: its fields, then one row per tick as it is replayed.
  std::vector<std::uint32_t> traced;
  for (const std::string& name : o.trace_fields) {
    const int f = robot->FieldIndex(name);
    if (f < 0) return Fail("--trace-fields: '" + name + "' is not a field of robot '" + robot->name + "'");
    traced.push_back(static_cast<std::uint32_t>(f));
  }
  if (o.trace_fields.empty())
    for (std::uint32_t f = 0; f < robot->fields.size(); ++f) traced.push_back(f);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> trace(nullptr, &std::fclose);
  if (!o.trace.empty()) {
    trace.reset(std::fopen(o.trace.c_str(), "w"));
    if (!trace) return Fail("--trace: cannot write '" + o.trace + "': " + std::strerror(errno));
    std::fprintf(trace.get(), "tick,phase,mode");
    for (std::uint32_t f : traced) std::fprintf(trace.get(), ",%s", robot->fields[f].name.c_str());
    std::fprintf(trace.get(), "\n");
  }
  // --policy-io: the policy's observation and action at each of its runs.
  using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;
  File obs_file(nullptr, &std::fclose), act_file(nullptr, &std::fclose);
  if (!o.policy_io.empty()) {
    if (o.policy.empty()) return Fail("--policy-io needs --policy (a recording with a policy)");
    for (auto [file, ext] : {std::pair{&obs_file, ".obs.f32"}, std::pair{&act_file, ".act.f32"}}) {
      const std::string path = o.policy_io + ext;
      file->reset(std::fopen(path.c_str(), "wb"));
      if (!*file) return Fail("--policy-io: cannot write '" + path + "': " + std::strerror(errno));
    }
  }
  const loop::PolicySource* policy_source = nullptr;
  std::uint64_t policy_runs = 0;
  const loop::ReplayTick each_tick = [&](const robot::RobotData& d, const loop::LoopData& l) {
    if (policy_source != nullptr && policy_source->runs() != policy_runs) {
      policy_runs = policy_source->runs();
      const auto obs = policy_source->observation();
      const auto act = policy_source->action();
      std::fwrite(obs.data(), sizeof(float), obs.size(), obs_file.get());
      std::fwrite(act.data(), sizeof(float), act.size(), act_file.get());
    }
    std::FILE* t = trace.get();
    if (t == nullptr) return;
    std::fprintf(t, "%llu,%s,%s", static_cast<unsigned long long>(d.tick), loop::ToString(l.phase()),
                 safety::ToString(d.mode));
    for (std::uint32_t f : traced) {
      const double v = d.fields[f];
      if (std::isnan(v)) {
        std::fputs(",nan", t);
      } else {
        std::fprintf(t, ",%.17g", v);
      }
    }
    std::fputc('\n', t);
  };
  std::string outputs;
  bool differs = false;
  std::uint64_t run = 0, next_tick = 0;
  std::uint32_t sequence = 0;
  for (std::size_t k = 0; k < o.logs.size(); ++k) {
    const std::string& path = o.logs[k];
    // A recording cut short (a full disk, a crash) replays up to its last whole record.
    auto log = loop::ReadLog(path, loop::LogTail::kAcceptCut);
    if (!log) return Fail(log.error().message);
    const loop::SourceKind kind = log->header.source;
    if (kind == loop::SourceKind::kPolicy && o.policy.empty())
      return Fail(path + ": recorded with a policy: give it with --policy");
    if (kind == loop::SourceKind::kTrajectory && o.trajectory.empty())
      return Fail(path + ": recorded with a trajectory: give it with --trajectory");
    if (kind == loop::SourceKind::kNone && !(o.policy.empty() && o.trajectory.empty()))
      return Fail(path + ": recorded without a command source: no --policy or --trajectory");
    // Several files: one recording, one after another.
    const loop::LogHeader& h = log->header;
    const std::uint64_t first_tick = log->records.empty()        ? next_tick
                                     : log->records[0].type == 1 ? log->records[0].inputs.tick
                                                                 : log->records[0].outputs.tick;
    if (k > 0 && h.run != run)
      return Fail(path + ": another recording than " + o.logs[0] + "'s (run " + std::to_string(h.run) + ", not " +
                  std::to_string(run) + ")");
    if (k > 0 && h.sequence != sequence + 1)
      return Fail(path + ": file " + std::to_string(h.sequence) + " of the recording does not follow file " +
                  std::to_string(sequence) + " (" + o.logs[k - 1] + ")");
    if (k > 0 && first_tick != next_tick)
      return Fail(path + ": begins at tick " + std::to_string(first_tick) + ", " + o.logs[k - 1] +
                  " ended before tick " + std::to_string(next_tick));
    run = h.run;
    sequence = h.sequence;
    // The self-test ran when the recording armed; a replay compares the commands instead.
    auto source =
        loop::LoadSource(*robot, {o.policy, o.trajectory, false, policy::KernelOption(o.kernel), o.switch_policies});
    if (!source) return Fail(source.error().message);
    if (obs_file) {
      policy_source = dynamic_cast<const loop::PolicySource*>(source->source.get());
      if (policy_source == nullptr) return Fail("--policy-io: the recording's source is not one policy");
      // policy_runs goes on from the file before: a rotated file's snapshot restores the count.
    }
    auto r = loop::Replay(*robot, *log, source->source.get(), source->hash,
                          trace || obs_file ? each_tick : loop::ReplayTick{});
    if (!r) return Fail(path + ": " + r.error().message);
    if (!r->outputs.empty()) next_tick = r->outputs.back().tick + 1;
    if (!o.out.empty()) {
      std::string text = loop::FormatOutputs(*robot, r->outputs);
      if (k > 0) text.erase(0, text.find('\n') + 1);  // one header line
      outputs += text;
    }
    std::printf("replay: %s: %llu ticks, %llu commands compared, %llu different%s%s\n", path.c_str(),
                static_cast<unsigned long long>(r->ticks), static_cast<unsigned long long>(r->compared),
                static_cast<unsigned long long>(r->mismatches), r->mismatches != 0 ? "; first: " : "",
                r->first_mismatch.c_str());
    if (!log->snapshot.empty())
      std::printf("replay: %s is file %u of a rotated recording: replayed from its snapshot at tick %llu\n",
                  path.c_str(), h.sequence, static_cast<unsigned long long>(first_tick));
    if (!log->complete)
      std::printf("replay: %s ends early, at offset %zu: %s; the %zu whole records before it were replayed\n",
                  path.c_str(), log->cut_at, log->cut_reason.c_str(), log->records.size());
    else if (log->end == loop::LogEnd::kRotated)
      std::printf("replay: %s ends where the recording went on in the next file (%s)\n", path.c_str(),
                  log->next.c_str());
    else if (log->end != loop::LogEnd::kStopped)
      std::printf("replay: %s ends where its recording stopped: %s; the %zu whole records before it were replayed\n",
                  path.c_str(), loop::DescribeEnd(*log).c_str(), log->records.size());
    if (r->compared == 0) return Fail(path + ": no command to compare (no whole tick recorded)");
    differs = differs || r->mismatches != 0;
  }
  if (!o.out.empty()) {
    std::ofstream f(o.out);
    f << outputs;
    if (!f) return Fail("--out: cannot write '" + o.out + "'");
  }
  if (trace && (std::ferror(trace.get()) != 0 || std::fclose(trace.release()) != 0))
    return Fail("--trace: writing '" + o.trace + "' failed");
  for (File* f : {&obs_file, &act_file})
    if (*f && (std::ferror(f->get()) != 0 || std::fclose(f->release()) != 0))
      return Fail("--policy-io: writing '" + o.policy_io + ".*.f32' failed");
  if (!o.policy_io.empty())
    std::printf("replay: %llu policy runs: observations in %s.obs.f32, actions in %s.act.f32 (float32 rows)\n",
                static_cast<unsigned long long>(policy_runs), o.policy_io.c_str(), o.policy_io.c_str());
  return differs ? 1 : 0;
}

}  // namespace pbppo::cli
