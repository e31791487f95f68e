#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "report/gnuplot.hpp"
#include "report/plots.hpp"

namespace pbppo::report {
namespace {

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> cells(1);
  for (char ch : line) {
    if (ch == ',') {
      cells.emplace_back();
    } else {
      cells.back().push_back(ch);
    }
  }
  return cells;
}

// (env_steps, value) of every row of RUN/log.csv where the column holds a finite number.
Result<std::vector<std::pair<long long, double>>> ReadColumn(const std::string& run, const std::string& column) {
  const std::string path = run + "/log.csv";
  std::ifstream f(path);
  if (!f) return MakeError(ErrorCode::kIo, "curves: cannot read " + path);
  std::string line;
  std::getline(f, line);
  const auto header = SplitCsv(line);
  long steps_at = -1, column_at = -1;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == "env_steps") steps_at = static_cast<long>(i);
    if (header[i] == column) column_at = static_cast<long>(i);
  }
  if (steps_at < 0 || column_at < 0)
    return MakeError(ErrorCode::kFormat,
                     "curves: " + path + " has no column '" + (steps_at < 0 ? std::string("env_steps") : column) + "'");
  std::vector<std::pair<long long, double>> out;
  while (std::getline(f, line)) {
    const auto cells = SplitCsv(line);
    if (static_cast<long>(cells.size()) <= std::max(steps_at, column_at)) continue;
    char* end = nullptr;
    const double v = std::strtod(cells[static_cast<std::size_t>(column_at)].c_str(), &end);
    if (std::isfinite(v)) out.emplace_back(std::atoll(cells[static_cast<std::size_t>(steps_at)].c_str()), v);
  }
  return out;
}

}  // namespace

Status PlotCurveBands(const CurveBands& c, const std::string& png_path) {
  if (c.groups.empty()) return MakeError(ErrorCode::kInvalidValue, "curves: no group of runs");
  static const char* const kColours[] = {"#1f77b4", "#d62728", "#2a9d3a", "#9467bd", "#ff7f0e", "#8c564b"};
  std::ostringstream data, plot;
  for (std::size_t g = 0; g < c.groups.size(); ++g) {
    const auto& group = c.groups[g];
    if (group.runs.empty()) return MakeError(ErrorCode::kInvalidValue, "curves: group '" + group.name + "' has no run");
    std::map<long long, std::vector<double>> at;  // env_steps -> one value per run
    for (const auto& run : group.runs) {
      auto rows = ReadColumn(run, c.column);
      if (!rows) return rows.error();
      for (const auto& [steps, v] : *rows) at[steps].push_back(v);
    }
    // steps, mean, mean - sd, mean + sd (sd 0 where one run has a value)
    data << "$g" << g << " << EOD\n";
    for (const auto& [steps, vs] : at) {
      double m = 0;
      for (double v : vs) m += v;
      m /= static_cast<double>(vs.size());
      double var = 0;
      for (double v : vs) var += (v - m) * (v - m);
      const double sd = vs.size() > 1 ? std::sqrt(var / static_cast<double>(vs.size() - 1)) : 0.0;
      data << steps << ' ' << m << ' ' << m - sd << ' ' << m + sd << '\n';
    }
    data << "EOD\n";
    const char* colour = kColours[g % 6];
    const std::string title = group.name + " (" + std::to_string(group.runs.size()) + " runs)";
    plot << (g == 0 ? "plot " : ", ") << "$g" << g << " using 1:3:4 with filledcurves fs transparent solid 0.2 "
         << "noborder lc rgb '" << colour << "' notitle, $g" << g << " using 1:2 with lines lw 2 lc rgb '" << colour
         << "' title " << Quoted(title);
  }
  std::ostringstream gp;
  gp << data.str() << "set terminal pngcairo size 900,500\nset output " << Quoted(png_path)
     << "\nset termoption noenhanced\nset title " << Quoted(c.title) << "\nset grid\nset key left top\n"
     << "set xlabel 'environment steps'\nset ylabel " << Quoted(c.ylabel.empty() ? c.column : c.ylabel) << "\n"
     << plot.str() << "\n";
  if (auto st = RunGnuplot(gp.str(), png_path + ".gp", png_path + ".log"); !st)
    return MakeError(st.error().code, "plot " + png_path + ": " + st.error().message);
  return {};
}

}  // namespace pbppo::report
