// The walking quadruped's soak (sim_hil/quadruped_soak.hpp) at full length, for bench/soak.sh (with
// --realtime on its own 1 kHz clock, set up as pbppo-controller sets itself up: memory locked,
// SCHED_FIFO 80; the plant shares the thread):
//
//   pbppo_bench_soak --ticks 1000000 --seed 1 --out DIR [--realtime] [--policy BLOB] [--robot quadruped]
//                    [--record LOG [--record-max-mb MB [--record-rotate N]]]
//
// A progress line every 10,000 ticks; then the report (stdout and DIR/report.txt) and, for the
// plots, DIR/rss.csv (tick, resident KiB), DIR/latency.csv (tenth of the run, p50, p99, p99.9,
// max of the controller's tick, us), DIR/faults.csv (one row per fault), DIR/modes.csv (the
// highest mode in each simulated second). Exit 0 when every promise held and the latency tail
// did not drift (the last tenth's p99 within 1.25 x the first's + 10 us), 1 otherwise, 2 on bad
// arguments. With --record the controller's ticks are recorded as pbppo-controller records them
// (rotated by size with --record-max-mb); the newest file is then replayed on its own, against the
// soak's robot (its recovery rule is the soak's), and must match bit for bit.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/loop/record_cli.hpp"
#include "runtime/loop/replay.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/robot/find_robot.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/rt/rt_setup.hpp"
#include "sim_hil/quadruped_soak.hpp"

using namespace pbppo;

namespace {

double Us(std::int64_t ns) {
  return static_cast<double>(ns) / 1000.0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("The walking quadruped's soak: faults from a seeded schedule, recovery, memory and latency");
  std::uint64_t ticks = 1'000'000, seed = 1;
  std::string out = "soak", robot_arg = "quadruped", policy;
  app.add_option("--ticks", ticks, "Lock-step ticks (1 ms each)")->check(CLI::Range(1000ull, 1'000'000'000ull));
  app.add_option("--seed", seed, "Seed of the command and fault schedules");
  app.add_option("--out", out, "Folder for the report and the plots' data");
  app.add_option("--robot", robot_arg, "The quadruped: a name or its robot.yaml");
  app.add_option("--policy", policy, "The walking policy (default: the robot's shipped flat-ground policy)");
  bool realtime = false;
  app.add_flag("--realtime", realtime, "The controller on its own clock at the robot's period (else lock-step)");
  loop::RecordCli record;
  loop::AddRecordOptions(app, record);
  CLI11_PARSE(app, argc, argv);
  auto robot_path = robot::FindRobot(robot_arg);
  if (!robot_path) {
    std::fprintf(stderr, "pbppo_bench_soak: %s\n", robot_path.error().message.c_str());
    return 2;
  }
  auto model = robot::LoadRobotModel(*robot_path);
  if (!model) {
    std::fprintf(stderr, "pbppo_bench_soak: %s\n", model.error().message.c_str());
    return 2;
  }
  if (policy.empty())
    policy = (std::filesystem::path(model->dir) / "../../policies/frozen/quadruped_walk/flat.blob").lexically_normal();
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::fprintf(stderr, "pbppo_bench_soak: --out %s: %s\n", out.c_str(), ec.message().c_str());
    return 2;
  }
  if (realtime) {  // as pbppo-controller sets itself up: memory locked, SCHED_FIFO 80
    const rt::RtSetupResult rs = rt::SetUpRealTime(rt::RtOptions{});
    for (const auto& w : rs.warnings) std::fprintf(stderr, "pbppo_bench_soak: warning: %s\n", w.c_str());
  }
  sim::SoakOptions o;
  o.ticks = ticks;
  o.seed = seed;
  o.policy = policy;
  o.progress_every = 10'000;
  o.realtime = realtime;
  o.record = record.path;
  o.record_options = record.options();
  o.progress = [&](std::uint64_t t, const sim::SoakReport& r) {
    std::fprintf(stderr, "\rsoak: tick %llu of %llu (%.0f %%), %llu stops, %llu re-arms, %llu violations   ",
                 static_cast<unsigned long long>(t), static_cast<unsigned long long>(ticks),
                 100.0 * static_cast<double>(t) / static_cast<double>(ticks), static_cast<unsigned long long>(r.stops),
                 static_cast<unsigned long long>(r.rearms), static_cast<unsigned long long>(r.violation_count));
  };
  auto r = sim::RunQuadrupedSoak(*model, o);
  std::fprintf(stderr, "\n");
  if (!r) {
    std::fprintf(stderr, "pbppo_bench_soak: %s\n", r.error().message.c_str());
    return 1;
  }
  std::ofstream(out + "/rss.csv") << [&] {
    std::string s = "tick,rss_kib\n";
    for (const auto& [t, kib] : r->rss_kib) s += std::to_string(t) + "," + std::to_string(kib) + "\n";
    return s;
  }();
  std::string lat = "tenth,p50_us,p99_us,p999_us,max_us\n";
  char line[256];
  for (std::size_t k = 0; k < r->tick_latency.size(); ++k) {
    const rt::LatencyStats& s = r->tick_latency[k];
    std::snprintf(line, sizeof line, "%zu,%.2f,%.2f,%.2f,%.2f\n", k + 1, Us(s.p50_ns), Us(s.p99_ns), Us(s.p999_ns),
                  Us(s.max_ns));
    lat += line;
  }
  std::ofstream(out + "/latency.csv") << lat;
  std::string faults =
      "kind,start_tick,end_tick,subject,while_walking,safe_tick,detection_ticks,bound_ticks,rearm_tick\n";
  std::uint64_t stopping = 0, worst = 0, stopped_before = 0;
  for (const sim::SoakFault& f : r->faults) {
    if (!f.while_walking) ++stopped_before;  // the robot was not walking when it began
    const long long det = f.safe_tick >= 0 ? f.safe_tick - static_cast<long long>(f.start) : -1;
    if (f.bound > 0 && f.while_walking && det >= 0) {
      ++stopping;
      worst = std::max<std::uint64_t>(worst, static_cast<std::uint64_t>(det));
    }
    std::snprintf(line, sizeof line, "%s,%llu,%llu,%d,%d,%lld,%lld,%llu,%lld\n", sim::ToString(f.kind),
                  static_cast<unsigned long long>(f.start), static_cast<unsigned long long>(f.end), f.subject,
                  f.while_walking ? 1 : 0, static_cast<long long>(f.safe_tick), det,
                  static_cast<unsigned long long>(f.bound), static_cast<long long>(f.rearm_tick));
    faults += line;
  }
  std::ofstream(out + "/faults.csv") << faults;
  std::string modes = "second,mode\n";
  for (std::size_t s = 0; s < r->mode_by_second.size(); ++s)
    modes += std::to_string(s + 1) + "," + std::to_string(r->mode_by_second[s]) + "\n";
  std::ofstream(out + "/modes.csv") << modes;

  const rt::LatencyStats &first = r->tick_latency.front(), &last = r->tick_latency.back();
  const bool drift = Us(last.p99_ns) > 1.25 * Us(first.p99_ns) + 10.0;
  const std::uint64_t rss_first = r->rss_kib[r->rss_kib.size() / 10].second, rss_last = r->rss_kib.back().second;
  std::string rep;
  auto add = [&](const std::string& s) { rep += s + "\n"; };
  std::snprintf(line, sizeof line, "soak: %llu ticks (%.0f s of walking, %s) in %.0f s of wall time, seed %llu",
                static_cast<unsigned long long>(r->ticks), static_cast<double>(r->ticks) * model->tick_period_s,
                realtime ? "real time" : "lock-step", r->wall_s, static_cast<unsigned long long>(seed));
  add(line);
  std::snprintf(
      line, sizeof line,
      "faults: %zu (%llu stopping faults while walking, detected within %llu ticks at worst; %llu began while "
      "the robot was not walking); stops %llu, "
      "re-arms %llu, falls %llu; %llu command phases",
      r->faults.size(), static_cast<unsigned long long>(stopping), static_cast<unsigned long long>(worst),
      static_cast<unsigned long long>(stopped_before), static_cast<unsigned long long>(r->stops),
      static_cast<unsigned long long>(r->rearms), static_cast<unsigned long long>(r->falls),
      static_cast<unsigned long long>(r->command_phases));
  add(line);
  std::snprintf(
      line, sizeof line, "controller: %llu allocations in its ticks, %llu ticks with a command outside its limits",
      static_cast<unsigned long long>(r->allocations), static_cast<unsigned long long>(r->commands_outside_limits));
  add(line);
  std::snprintf(line, sizeof line, "resident memory: %llu KiB after the first tenth, %llu KiB at the end (%+lld KiB)",
                static_cast<unsigned long long>(rss_first), static_cast<unsigned long long>(rss_last),
                static_cast<long long>(rss_last) - static_cast<long long>(rss_first));
  add(line);
  std::snprintf(line, sizeof line,
                "controller tick: first tenth p50 %.1f us p99 %.1f us max %.1f us; last tenth p50 %.1f us p99 %.1f us "
                "max %.1f us: %s",
                Us(first.p50_ns), Us(first.p99_ns), Us(first.max_ns), Us(last.p50_ns), Us(last.p99_ns), Us(last.max_ns),
                drift ? "DRIFT (p99 beyond 1.25 x + 10 us)" : "no drift");
  add(line);
  std::snprintf(line, sizeof line, "violations: %llu", static_cast<unsigned long long>(r->violation_count));
  add(line);
  bool replayed = true;
  if (!record.path.empty()) {
    // The newest file, replayed on its own from its snapshot.
    const std::string newest = loop::RotatedPath(record.path, r->record_files - 1);
    std::string how;
    auto log = loop::ReadLog(newest);
    loop::SourceFiles source_files;
    source_files.policy = policy;
    source_files.self_test = false;
    auto source = loop::LoadSource(sim::SoakModel(*model, realtime), source_files);
    if (!log || !source) {
      how = !log ? log.error().message : source.error().message;
    } else if (auto rp = loop::Replay(sim::SoakModel(*model, realtime), *log, source->source.get(), source->hash);
               !rp) {
      how = rp.error().message;
    } else {
      how = std::to_string(rp->ticks) + " ticks from tick " + std::to_string(log->records.front().inputs.tick) + ", " +
            std::to_string(rp->mismatches) + " different" + (rp->mismatches != 0 ? ": " + rp->first_mismatch : "");
      replayed = rp->mismatches == 0 && rp->compared > 0;
    }
    replayed = replayed && r->record_error.empty() && r->records_dropped == 0;
    std::string files = std::to_string(r->record_files) + (r->record_files == 1 ? " file" : " files");
    if (record.max_mb > 0) {
      char mib[48];
      std::snprintf(mib, sizeof mib, " of at most %g MiB (%u deleted)", record.max_mb, r->record_files_deleted);
      files += mib;
    }
    std::snprintf(line, sizeof line, "log: %llu records in %s, %llu dropped%s%s",
                  static_cast<unsigned long long>(r->records), files.c_str(),
                  static_cast<unsigned long long>(r->records_dropped), r->record_error.empty() ? "" : "; ",
                  r->record_error.c_str());
    add(line);
    add("log: the newest file, " + newest + ", replayed alone: " + how);
  }
  for (const std::string& v : r->violations) add("  " + v);
  for (const std::string& s : r->summary) add("  " + s);
  std::printf("%s", rep.c_str());
  std::ofstream(out + "/report.txt") << rep;
  const bool ok = r->violation_count == 0 && r->allocations == 0 && r->commands_outside_limits == 0 && !drift &&
                  rss_last <= rss_first + 1024 && replayed;
  return ok ? 0 : 1;
}
