#include "policies/cli/sweep.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <sstream>
#include <thread>

#include "policies/cli/child_jobs.hpp"
#include "policies/cli/process_group.hpp"
#include "policies/cli/sweep_plan.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/policy/blob.hpp"

namespace pbppo::cli {
namespace {

namespace fs = std::filesystem;

constexpr int kFailed = 1, kUsage = 2, kInterrupted = 130;

void Say(const std::string& msg) {
  std::fprintf(stderr, "pbppo sweep: %s\n", msg.c_str());
}

// ---------------------------------------------------------------------------------------------
// Files.

// The project's one file reader (policy::ReadFileBytes), as text: sweep.json, result.json,
// eval.json and the runs' logs stay far below the limit.
Result<std::string> ReadText(const std::string& path) {
  auto bytes = policy::ReadFileBytes(path, std::uint64_t{64} << 20);
  if (!bytes) return std::move(bytes).error();
  return std::string(bytes->begin(), bytes->end());
}

Status WriteText(const std::string& path, const std::string& text) {
  return policy::WriteFileAtomic(path, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

Result<Json> ReadJson(const std::string& path) {
  auto text = ReadText(path);
  if (!text) return std::move(text).error();
  Json j = Json::parse(*text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return MakeError(ErrorCode::kFormat, path + ": not a JSON object");
  return j;
}

// The last `n` lines of a log, indented, one per line.
std::string Tail(const std::string& path, int n) {
  auto text = ReadText(path);
  if (!text) return "    (" + text.error().message + ")";
  std::vector<std::string> lines;
  std::stringstream ss(*text);
  for (std::string line; std::getline(ss, line);) lines.push_back(std::move(line));
  std::string out;
  for (std::size_t i = lines.size() > static_cast<std::size_t>(n) ? lines.size() - n : 0; i < lines.size(); ++i)
    out += (out.empty() ? "    " : "\n    ") + lines[i];
  return out;
}

// ---------------------------------------------------------------------------------------------
// result.json: written by a run's last step, read back by one reader for the table.

double Num(const Json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : std::nan("");
}

struct RunResult {
  double env_steps = 0, eval_steps = 0, wall_s = 0, train_return = 0, eval_mean = 0, eval_std = 0;
};

// `text` is result.json of run `r` (`where` names it in errors).
Result<RunResult> ReadResult(const std::string& text, const Plan& p, const Run& r, const std::string& where) {
  const Json j = Json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("train") || !j.contains("final_eval"))
    return MakeError(ErrorCode::kFormat, where + ": not a sweep run's result");
  Json grid = Json::object();
  for (std::size_t k = 0; k < p.axes.size(); ++k) grid[p.axes[k].key] = p.cells[r.cell][k];
  if (j.value("grid", Json()) != grid || j.value("seed", Json()) != Json(r.seed))
    return MakeError(ErrorCode::kMismatch, where + ": written for another run (grid " + j.value("grid", Json()).dump() +
                                               ", seed " + j.value("seed", Json()).dump() + ")");
  const Json& t = j["train"];
  const Json& e = j["final_eval"];
  return RunResult{Num(t, "env_steps"),   Num(t, "eval_steps"), Num(t, "wall_seconds"), Num(t, "final_return_last100"),
                   Num(e, "mean_return"), Num(e, "std_return")};
}

// ---------------------------------------------------------------------------------------------
// One run: train, evaluate the final policy, write result.json last.

struct Outcome {
  std::size_t run = 0;
  int rc = 0;          // 0: finished, `result` holds result.json; 130: interrupted; else failed
  std::string result;  // result.json's text, or what went wrong
};

Outcome RunOne(const SweepOptions& o, const Plan& p, std::size_t index, int slot) {
  const Run& r = p.runs[index];
  const std::string dir = o.out + "/" + r.rel;
  auto failed = [&](int rc, const std::string& what) { return Outcome{index, rc, what}; };
  std::error_code ec;
  fs::remove_all(dir, ec);  // a leftover of an interrupted run
  if (!ec) fs::create_directories(dir, ec);
  if (ec) return failed(kFailed, dir + ": " + ec.message());
  std::string error;
  const std::string train_log = dir + "/train.log";
  int rc = RunChild(r.train_args, train_log, train_log, slot, &error);
  if (rc < 0) return failed(kFailed, error);
  if (rc == kInterrupted || Stopped()) return failed(kInterrupted, "interrupted");
  if (rc != 0)
    return failed(rc, "pbppo train exited " + std::to_string(rc) + "; " + train_log + " ends:\n" + Tail(train_log, 6));
  auto summary = ReadJson(dir + "/summary.json");
  if (!summary) return failed(kFailed, summary.error().message);
  const std::string eval_log = dir + "/eval.log", eval_json = dir + "/eval.json";
  rc = RunChild(r.eval_args, eval_json, eval_log, slot, &error);
  if (rc < 0) return failed(kFailed, error);
  if (Stopped()) return failed(kInterrupted, "interrupted");
  if (rc != 0)
    return failed(rc, "pbppo eval exited " + std::to_string(rc) + "; " + eval_log + " ends:\n" + Tail(eval_log, 6));
  auto eval = ReadJson(eval_json);
  if (!eval) return failed(kFailed, eval.error().message);

  Json grid = Json::object();
  for (std::size_t k = 0; k < p.axes.size(); ++k) grid[p.axes[k].key] = p.cells[r.cell][k];
  const Json& s = *summary;
  Json j = {{"run", r.rel}, {"grid", grid}, {"seed", r.seed}};
  j["train"] = {{"env", s.value("env", Json())},
                {"env_steps", s.value("env_steps", Json())},
                {"eval_steps", s.value("eval_steps", Json())},
                {"wall_seconds", s.value("wall_seconds", Json())},
                {"final_return_last100", s.value("final_return_last100", Json())},
                {"args", Json(std::vector<std::string>(r.train_args.begin() + 1, r.train_args.end()))}};
  j["final_eval"] = {{"episodes", o.final_episodes},
                     {"seed", o.eval_seed},
                     {"mean_return", eval->value("mean_return", Json())},
                     {"std_return", eval->value("std_return", Json())},
                     {"min_return", eval->value("min_return", Json())},
                     {"max_return", eval->value("max_return", Json())}};
  std::string text = j.dump(2) + "\n";
  if (auto st = WriteText(dir + "/result.json", text); !st) return failed(kFailed, st.error().message);
  return {index, 0, std::move(text)};
}

std::string Fmt(const char* fmt, double v) {
  if (!std::isfinite(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::string Duration(double s) {
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof buf, "%.0fh%02.0fm", std::floor(s / 3600), std::floor(std::fmod(s, 3600) / 60));
  } else if (s >= 60) {
    std::snprintf(buf, sizeof buf, "%.0fm%02.0fs", std::floor(s / 60), std::floor(std::fmod(s, 60)));
  } else {
    std::snprintf(buf, sizeof buf, "%.0fs", s);
  }
  return buf;
}

// Runs the `assigned` runs (indices into the plan) `o.jobs` at a time; a line on stderr per finished run.
// `tag` starts each line ("" or "rank R: ").
std::vector<Outcome> Execute(const SweepOptions& o, const Plan& p, const std::vector<std::size_t>& assigned,
                             const std::string& tag) {
  std::mutex mu;
  std::size_t next = 0, done = 0;
  std::vector<Outcome> outcomes;
  const auto start = std::chrono::steady_clock::now();
  auto report = [&](const Outcome& out) {
    std::lock_guard lock(mu);
    outcomes.push_back(out);
    ++done;
    const Run& r = p.runs[out.run];
    const std::string name = (p.axes.empty() ? "" : CellName(p, r.cell) + " ") + "seed=" + std::to_string(r.seed);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string eta =
        done < assigned.size() && !Stopped()
            ? ", ETA " + Duration(elapsed / static_cast<double>(done) * static_cast<double>(assigned.size() - done))
            : "";
    char head[64];
    std::snprintf(head, sizeof head, "[%zu/%zu] ", done, assigned.size());
    if (out.rc == 0) {
      auto res = ReadResult(out.result, p, r, r.rel + "/result.json");
      std::string line = name + ": ";
      if (res) {
        line += "final eval return " + Fmt("%.2f", res->eval_mean) + " (sd " + Fmt("%.2f", res->eval_std) + ", " +
                std::to_string(o.final_episodes) + " episodes), training return " + Fmt("%.2f", res->train_return) +
                ", " + Fmt("%.0f", res->env_steps) + " + " + Fmt("%.0f", res->eval_steps) + " steps, " +
                Fmt("%.1f", res->wall_s) + " s";
      } else {
        line += res.error().message;
      }
      Say(tag + head + line + eta);
    } else if (out.rc == kInterrupted) {
      Say(tag + head + name + ": interrupted (its folder is redone next time)");
    } else {
      Say(tag + head + "FAILED " + name + " (" + o.out + "/" + r.rel + "): " + out.result);
    }
  };
  const int jobs = std::min<int>(o.jobs, static_cast<int>(std::max<std::size_t>(assigned.size(), 1)));
  auto worker = [&](int slot) {
    for (;;) {
      std::size_t i = 0;
      {
        std::lock_guard lock(mu);
        if (next >= assigned.size() || Stopped()) return;
        i = assigned[next++];
      }
      report(RunOne(o, p, i, slot));
    }
  };
  if (jobs == 1) {
    worker(0);
  } else {
    std::vector<std::thread> threads;
    for (int s = 0; s < jobs; ++s) threads.emplace_back(worker, s);
    for (auto& t : threads) t.join();
  }
  return outcomes;
}

// ---------------------------------------------------------------------------------------------
// The table: one row per grid cell over its finished seeds.

// P(|T| <= t) for Student's t with nu degrees of freedom (Abramowitz & Stegun 26.7.3, 26.7.4).
double StudentTwoSided(double t, int nu) {
  const double th = std::atan(t / std::sqrt(static_cast<double>(nu))), c2 = std::cos(th) * std::cos(th);
  double term = 1, sum = 1;
  for (int k = nu % 2 == 1 ? 3 : 2; k <= nu - 2; k += 2) {
    term *= c2 * (k - 1) / k;
    sum += term;
  }
  if (nu % 2 == 0) return std::sin(th) * sum;
  return 2 / M_PI * (th + (nu > 1 ? std::sin(th) * std::cos(th) * sum : 0.0));
}

// The half-width of the two-sided 95 % Student t interval of the mean of `xs` (NaN below 2 values).
double HalfWidth95(const std::vector<double>& xs, double mean) {
  const int n = static_cast<int>(xs.size());
  if (n < 2) return std::nan("");
  double var = 0;
  for (double x : xs) var += (x - mean) * (x - mean);
  double lo = 0, hi = 1000;  // the 0.975 quantile, by bisection (12.706 at one degree of freedom)
  for (int i = 0; i < 100; ++i) (StudentTwoSided(0.5 * (lo + hi), n - 1) < 0.95 ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi) * std::sqrt(var / (n - 1) / n);
}

double Mean(const std::vector<double>& xs) {
  double s = 0;
  for (double x : xs) s += x;
  return xs.empty() ? std::nan("") : s / static_cast<double>(xs.size());
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// Writes DIR/table.csv and DIR/table.md from every finished run's result (by run index); returns
// the Markdown table.
Result<std::string> WriteTables(const SweepOptions& o, const Plan& p, const std::vector<const RunResult*>& results) {
  std::string csv, md, rule = "|";
  for (const auto& a : p.axes) {
    csv += CsvField(a.key) + ",";
    md += "| " + a.key + " ";
    rule += " --- |";
  }
  csv +=
      "seeds,eval_return_mean,eval_return_ci95,eval_return_min,eval_return_max,train_return_mean,env_steps_mean,"
      "eval_steps_mean,wall_s_mean\n";
  md +=
      "| seeds | final eval return (mean ± 95 % CI) | min | max | training return | training steps | evaluation "
      "steps | wall s |\n";
  for (int i = 0; i < 8; ++i) rule += " ---: |";
  md += rule + "\n";
  for (std::size_t c = 0; c < p.cells.size(); ++c) {
    std::vector<double> ret, train, env_steps, eval_steps, wall;
    for (std::size_t i = 0; i < p.runs.size(); ++i) {
      if (p.runs[i].cell != c || results[i] == nullptr) continue;
      ret.push_back(results[i]->eval_mean);
      train.push_back(results[i]->train_return);
      env_steps.push_back(results[i]->env_steps);
      eval_steps.push_back(results[i]->eval_steps);
      wall.push_back(results[i]->wall_s);
    }
    const double mean = Mean(ret), hw = HalfWidth95(ret, mean);
    const double lo = ret.empty() ? std::nan("") : *std::min_element(ret.begin(), ret.end());
    const double hi = ret.empty() ? std::nan("") : *std::max_element(ret.begin(), ret.end());
    for (const auto& v : p.cells[c]) {
      csv += CsvField(v) + ",";
      md += "| " + v + " ";
    }
    const char* g = "%.10g";
    csv += std::to_string(ret.size()) + "," + Fmt(g, mean) + "," + Fmt(g, hw) + "," + Fmt(g, lo) + "," + Fmt(g, hi) +
           "," + Fmt(g, Mean(train)) + "," + Fmt(g, Mean(env_steps)) + "," + Fmt(g, Mean(eval_steps)) + "," +
           Fmt(g, Mean(wall)) + "\n";
    md += "| " + std::to_string(ret.size()) + " | " + Fmt("%.2f", mean) + (std::isfinite(hw) ? " ± " : "") +
          Fmt("%.2f", hw) + " | " + Fmt("%.2f", lo) + " | " + Fmt("%.2f", hi) + " | " + Fmt("%.2f", Mean(train)) +
          " | " + Fmt("%.0f", Mean(env_steps)) + " | " + Fmt("%.0f", Mean(eval_steps)) + " | " +
          Fmt("%.1f", Mean(wall)) + " |\n";
  }
  if (auto st = WriteText(o.out + "/table.csv", csv); !st) return std::move(st).error();
  const std::string text = "Final policies on " + std::to_string(o.final_episodes) +
                           " deterministic episodes (pbppo eval --seed " + std::to_string(o.eval_seed) +
                           "), per grid cell over its seeds:\n\n" + md;
  if (auto st = WriteText(o.out + "/table.md", text); !st) return std::move(st).error();
  return text;
}

// Rank 0's look at DIR: refuses another sweep's folder, writes sweep.json (unless a dry run) and
// returns the runs without result.json (leftovers included: RunOne clears their folders).
Result<std::vector<long>> Pending(const SweepOptions& o, const Plan& p) {
  const std::string record = o.out + "/sweep.json";
  std::error_code ec;
  if (fs::exists(record, ec)) {
    auto old = ReadJson(record);
    if (!old) return MakeError(ErrorCode::kFormat, old.error().message);
    for (const auto& [key, value] : p.record.items()) {
      if (old->value(key, Json()) != value)
        return MakeError(ErrorCode::kMismatch, record + " is another sweep's: its " + key + " is " +
                                                   old->value(key, Json()).dump() + ", this command's " + value.dump() +
                                                   " (use another --out, or the same arguments)");
    }
  } else if (fs::exists(o.out, ec) && !fs::is_empty(o.out, ec)) {
    return MakeError(ErrorCode::kMismatch, o.out + " is not a sweep's folder (no sweep.json) and not empty");
  } else if (!o.dry_run) {
    if (fs::create_directories(o.out, ec); ec) return MakeError(ErrorCode::kIo, o.out + ": " + ec.message());
    if (auto st = WriteText(record, p.record.dump(2) + "\n"); !st) return st.error();
  }
  std::vector<long> pending;
  std::size_t finished = 0, leftovers = 0;
  for (std::size_t i = 0; i < p.runs.size(); ++i) {
    const std::string dir = o.out + "/" + p.runs[i].rel;
    const bool done = fs::exists(dir + "/result.json", ec), leftover = !done && fs::exists(dir, ec);
    finished += done;
    leftovers += leftover;
    if (!done) pending.push_back(static_cast<long>(i));
    if (o.dry_run) {
      std::string cmd = "pbppo";
      for (const auto& a : p.runs[i].train_args) cmd += " " + a;
      std::printf("%-8s %s\n         %s\n",
                  done       ? "finished"
                  : leftover ? "redo"
                             : "run",
                  p.runs[i].rel.c_str(), cmd.c_str());
    }
  }
  char line[256];
  std::snprintf(line, sizeof line,
                "%zu runs (%zu grid cells x %zu seeds): %zu finished before, %zu to run (%zu of them "
                "folders of unfinished runs, cleared and redone)",
                p.runs.size(), p.cells.size(), p.seeds.size(), finished, pending.size(), leftovers);
  Say(o.out + ": " + line);
  return pending;
}

}  // namespace

CLI::App* AddSweep(CLI::App& app, SweepOptions& o) {
  auto* s = app.add_subcommand("sweep",
                               "Train a grid of runs (grid values x seeds, each a pbppo train child process), evaluate "
                               "every final policy and tabulate the cells over their seeds; also under mpirun");
  s->add_option("--out", o.out, "Sweep folder: KEY=VALUE/.../seed=N/ per run, sweep.json, table.csv, table.md")
      ->required();
  s->add_option("--grid", o.grid,
                "KEY=V1,V2,...: a pbppo train option (without its dashes) and its values, one axis of the grid "
                "(repeat for more axes; a comma inside a value: '\\,')")
      ->allow_extra_args(false);
  s->add_option("--seeds", o.seeds, "Seeds of every grid cell: 1-5, 1,3,7 or 1-3,8")->default_str(o.seeds);
  s->add_option("--jobs", o.jobs, "Runs at once on this machine (under mpirun: 1, one run per rank)")
      ->check(CLI::Range(1, kMaxJobs))
      ->default_str("1");
  s->add_option("--final-episodes", o.final_episodes,
                "Deterministic episodes of each final policy (pbppo eval --episodes: what the environment counts)")
      ->check(CLI::Range(1, 100000))
      ->default_str("10");
  s->add_option("--eval-seed", o.eval_seed, "Seed of their initial states (pbppo eval --seed)")
      ->check(cli_checks::NonNegativeInteger())
      ->default_str("7");
  s->add_flag("--dry-run", o.dry_run, "Check everything, print each run's state and command, write nothing");
  s->add_option("train_flags", o.train_flags, "After --: pbppo train flags shared by every run (not --out, --seed)");
  return s;
}

int Sweep(const SweepOptions& options) {
  SweepOptions o = options;
  while (o.out.size() > 1 && o.out.back() == '/') o.out.pop_back();  // DIR/ names DIR
  // A refusal before MPI starts is every rank's; rank 0 says it.
  const char* rank_env = std::getenv("OMPI_COMM_WORLD_RANK");
  const bool speaker = rank_env == nullptr || std::string(rank_env) == "0";
  if (o.jobs != 1 && ProcessGroup::UnderMpirun()) {
    if (speaker)
      Say("--jobs " + std::to_string(o.jobs) + ": under mpirun every rank runs one run at a time (start more ranks)");
    return kUsage;
  }
  auto plan = MakePlan(o);
  if (!plan) {
    if (speaker) Say(plan.error().message);
    return kUsage;
  }
  const Plan& p = plan.value();
  const ProcessGroup group;

  // Rank 0 reads the folder; every rank learns the pending runs (a refusal: a lone -1).
  std::vector<long> pending;
  if (group.rank() == 0) {
    auto pend = Pending(o, p);
    if (pend) {
      pending = std::move(pend).value();
    } else {
      Say(pend.error().message);
      pending = {-1};
    }
  }
  group.Broadcast(pending);
  if (pending.size() == 1 && pending[0] < 0) return kUsage;
  if (o.dry_run) return 0;

  std::vector<std::size_t> mine;  // pending[i] runs on rank i % size
  for (std::size_t i = static_cast<std::size_t>(group.rank()); i < pending.size();
       i += static_cast<std::size_t>(group.size()))
    mine.push_back(static_cast<std::size_t>(pending[i]));
  const std::string tag = group.mpi() ? "rank " + std::to_string(group.rank()) + ": " : "";
  if (group.mpi() && !mine.empty())
    Say(tag + std::to_string(mine.size()) + " of the " + std::to_string(pending.size()) + " runs");
  std::vector<Outcome> outcomes;
  bool stopped = false;
  {
    const InterruptScope interrupts;
    outcomes = Execute(o, p, mine, tag);
    stopped = Stopped();
  }

  // Every rank's outcomes to rank 0, which writes the table from them and the runs finished before.
  Json sent = {{"stopped", stopped}, {"outcomes", Json::array()}};
  for (const auto& out : outcomes) sent["outcomes"].push_back({{"run", out.run}, {"rc", out.rc}, {"text", out.result}});
  const auto received = group.Gather(sent.dump());
  std::vector<long> rc = {0};
  if (group.rank() == 0) {
    std::vector<std::optional<RunResult>> results(p.runs.size());
    std::vector<int> codes(p.runs.size(), -1);  // -1: finished before this command
    bool interrupted = false;
    for (const auto& text : received) {
      const Json j = Json::parse(text);
      interrupted |= j["stopped"].get<bool>();
      for (const auto& out : j["outcomes"]) {
        const auto i = out["run"].get<std::size_t>();
        codes[i] = out["rc"].get<int>();
        if (codes[i] != 0) continue;
        auto r = ReadResult(out["text"].get<std::string>(), p, p.runs[i], p.runs[i].rel + "/result.json");
        if (r) results[i] = *r;
      }
    }
    for (long i : pending)
      if (codes[static_cast<std::size_t>(i)] == -1) codes[static_cast<std::size_t>(i)] = kInterrupted;  // not started
    std::size_t failed = 0;
    for (std::size_t i = 0; i < p.runs.size(); ++i) {
      if (codes[i] == -1) {  // finished before: read back
        const std::string path = o.out + "/" + p.runs[i].rel + "/result.json";
        auto text = ReadText(path);
        auto r = text ? ReadResult(*text, p, p.runs[i], path) : Result<RunResult>(std::move(text).error());
        if (r) {
          results[i] = *r;
        } else {
          Say(r.error().message);
          ++failed;
        }
      } else if (codes[i] == kInterrupted) {
        interrupted = true;
      } else if (codes[i] != 0) {
        ++failed;
      }
    }
    std::vector<const RunResult*> ptrs;
    for (const auto& r : results) ptrs.push_back(r ? &*r : nullptr);
    auto table = WriteTables(o, p, ptrs);
    if (table) {
      std::printf("%s\n%s/table.csv, %s/table.md\n", table->c_str(), o.out.c_str(), o.out.c_str());
    } else {
      Say(table.error().message);
      ++failed;
    }
    std::string failures;
    for (std::size_t i = 0; i < p.runs.size(); ++i)
      if (codes[i] > 0 && codes[i] != kInterrupted) failures += " " + p.runs[i].rel;
    if (!failures.empty()) Say("failed runs (redone next time):" + failures);
    if (interrupted) Say("interrupted: the runs not finished are done by the same command again");
    rc[0] = interrupted ? kInterrupted : failed > 0 ? kFailed : 0;
  }
  group.Broadcast(rc);
  return static_cast<int>(rc[0]);
}

}  // namespace pbppo::cli
