#include "policies/trainer/logger.hpp"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "report/plots.hpp"
#include "runtime/policy/blob.hpp"

namespace pbppo::trainer {
namespace {

Status WriteText(const std::string& path, const std::string& text) {
  return policy::WriteFileAtomic(path, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace

std::string Logger::CsvHeader(std::size_t arms) {
  std::ostringstream h;
  h << "iteration,env_steps,eval_steps,total_steps,arm,epsilon,feedback,feedback_before,improved,success_rate,"
       "train_return,train_return_100,episodes,approx_kl,clip_fraction,explained_variance,entropy,policy_loss,"
       "value_loss,grad_norm,log_std_mean,steps_per_second,task_success_100,learning_rate,kl,tracking_vx_100,"
       "tracking_vy_100,tracking_yaw_rate_100";
  for (std::size_t i = 0; i < arms; ++i)
    h << ",arm" << i << "_epsilon,arm" << i << "_value,arm" << i << "_bonus,arm" << i << "_count";
  h << "\n";
  return h.str();
}

std::string Logger::CsvRow(const IterationStats& s) {
  std::ostringstream r;
  r.precision(10);
  r << s.iteration << ',' << s.env_steps << ',' << s.eval_steps << ',' << (s.env_steps + s.eval_steps) << ',' << s.arm
    << ',' << s.epsilon << ',' << s.feedback << ',' << s.feedback_before << ',' << (s.improved ? 1 : 0) << ','
    << s.success_rate << ',' << s.train_return << ',' << s.train_return_100 << ',' << s.episodes << ',' << s.approx_kl
    << ',' << s.clip_fraction << ',' << s.explained_variance << ',' << s.entropy << ',' << s.policy_loss << ','
    << s.value_loss << ',' << s.grad_norm << ',' << s.log_std_mean << ',' << s.steps_per_second << ','
    << s.task_success_100 << ',' << s.learning_rate << ',' << s.kl << ',' << s.tracking_error_100[0] << ','
    << s.tracking_error_100[1] << ',' << s.tracking_error_100[2];
  for (const auto& a : s.arms) r << ',' << a.epsilon << ',' << a.value << ',' << a.bonus << ',' << a.count;
  r << "\n";
  return r.str();
}

Status Logger::Open(const std::vector<IterationStats>& resumed) {
  const std::string& dir = o_.out_dir;
  if (dir.empty()) return {};
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return MakeError(ErrorCode::kIo, "--out: cannot create folder '" + dir + "': " + ec.message());
  std::string text = CsvHeader(o_.schedule.arms.size());
  for (const IterationStats& s : resumed) text += CsvRow(s);
  if (auto st = WriteText(dir + "/log.csv", text); !st)
    return MakeError(ErrorCode::kIo, "--out: folder '" + dir + "' is not writable: " + st.error().message);
  csv_.open(dir + "/log.csv", std::ios::app);
  if (!csv_) return MakeError(ErrorCode::kIo, "--out: cannot append to '" + dir + "/log.csv'");
  if (o_.snapshots > 0) {
    std::filesystem::create_directories(dir + "/snapshots", ec);
    if (ec) return MakeError(ErrorCode::kIo, "--snapshots: cannot create '" + dir + "/snapshots': " + ec.message());
  }
  return {};
}

void Logger::Log(const IterationStats& s) {
  if (!csv_.is_open()) return;
  csv_ << CsvRow(s);
  csv_.flush();
}

std::string Logger::Plots(const std::vector<IterationStats>& its) const {
  report::TrainingCurves curves;
  curves.dir = o_.out_dir;
  curves.arms = o_.schedule.arms;
  curves.pulls.assign(curves.arms.size(), 0);
  for (const auto& s : its) curves.pulls[static_cast<std::size_t>(s.arm)]++;
  curves.task_success = !its.empty() && std::isfinite(its.back().task_success_100);
  auto pngs = report::PlotTrainingCurves(curves);
  if (!pngs) return "plots skipped: " + pngs.error().message;
  std::string note = "plots:";
  for (const auto& p : *pngs) note += (note.size() > 6 ? ", " : " ") + p;
  return note;
}

Status Logger::Finish(const std::string& env_name, const std::string& env_provenance, TrainResult& res) {
  if (o_.out_dir.empty()) return {};
  csv_.close();
  res.plots_note = o_.plots ? Plots(res.iterations) : "plots skipped: --no-plots";
  auto or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  nlohmann::json j = OptionsJson(o_);
  j["env"] = env_name;               // the environment's full name, as the blob's provenance has it
  j["provenance"] = env_provenance;  // whole (the blob holds its first 256 bytes)
  j["iterations"] = res.iterations.size();
  j["env_steps"] = res.env_steps;
  j["eval_steps"] = res.eval_steps;
  j["total_env_steps"] = res.env_steps + res.eval_steps;
  j["final_return_last100"] = or_null(res.final_return);
  j["wall_seconds"] = res.wall_seconds;
  j["steps_per_second"] = res.steps_per_second;
  const TimeShares& ts = res.time;
  j["time_seconds"] = {{"rollout", ts.rollout},         {"rollout_policy", ts.rollout_policy},
                       {"rollout_env", ts.rollout_env}, {"returns", ts.returns},
                       {"update", ts.update},           {"evaluation", ts.evaluation},
                       {"exchange", ts.exchange},       {"other", ts.other}};
  j["interrupted"] = res.interrupted;
  j["success_rate"] = res.iterations.empty() ? nlohmann::json() : or_null(res.iterations.back().success_rate);
  std::vector<int> pulls(o_.schedule.arms.size(), 0);
  for (const auto& s : res.iterations) pulls[static_cast<std::size_t>(s.arm)]++;
  if (!res.iterations.empty() && std::isfinite(res.iterations.back().task_success_100))
    j["task_success_100"] = res.iterations.back().task_success_100;
  if (!res.iterations.empty() && std::isfinite(res.iterations.back().tracking_error_100[0])) {
    const auto& t = res.iterations.back().tracking_error_100;
    j["tracking_error_100"] = {{"vx_mps", t[0]}, {"vy_mps", t[1]}, {"yaw_rate_radps", t[2]}};
  }
  j["arm_pulls"] = pulls;
  j["blob"] = o_.out_dir + "/policy.blob";
  j["git_revision"] = res.spec.provenance.git_revision;
  j["plots"] = res.plots_note;
  return WriteText(o_.out_dir + "/summary.json", j.dump(2) + "\n");
}

}  // namespace pbppo::trainer
