#include <algorithm>
#include <sstream>

#include "report/gnuplot.hpp"
#include "report/plots.hpp"

namespace pbppo::report {

Status PlotTimeSeries(const TimeSeriesPlot& p, const std::string& png_path) {
  if (p.panels.empty()) return MakeError(ErrorCode::kInvalidValue, "plot " + png_path + ": no panel");
  static const char* const kColours[] = {"#1f77b4", "#d62728", "#2a9d3a", "#9467bd", "#ff7f0e"};
  std::ostringstream data, plots;
  int block = 0;
  for (const auto& panel : p.panels) {
    plots << "set ylabel " << Quoted(panel.ylabel) << "\n";
    std::vector<std::string> clauses;
    for (const auto& s : panel.series) {
      if (s.x.size() != s.y.size())
        return MakeError(ErrorCode::kInvalidValue, "plot " + png_path + ": series '" + s.title + "' has " +
                                                       std::to_string(s.x.size()) + " x and " +
                                                       std::to_string(s.y.size()) + " y values");
      if (s.x.empty()) continue;
      data << "$s" << block << " << EOD\n";
      for (std::size_t i = 0; i < s.x.size(); ++i) data << s.x[i] << ' ' << s.y[i] << '\n';
      data << "EOD\n";
      std::ostringstream c;
      c << "$s" << block++ << " using 1:2 with lines " << (s.dashed ? "dt 2 lw 1.5" : "lw 1") << " lc rgb '"
        << kColours[static_cast<std::size_t>(std::max(s.group, 0)) % 5] << "' title " << Quoted(s.title);
      clauses.push_back(c.str());
    }
    if (clauses.empty()) clauses.push_back("NaN notitle");
    for (std::size_t i = 0; i < clauses.size(); ++i) plots << (i == 0 ? "plot " : ", ") << clauses[i];
    plots << "\n";
  }
  std::ostringstream gp;
  gp << data.str() << "set terminal pngcairo size 1100," << 300 * p.panels.size() << "\nset output " << Quoted(png_path)
     << "\nset termoption noenhanced\nset multiplot layout " << p.panels.size() << ",1 title " << Quoted(p.title)
     << "\nset grid\nset xlabel " << Quoted(p.xlabel)
     << "\nset key below horizontal\nset lmargin 10\nset rmargin 3\n"  // every panel the same width: time aligned
     << plots.str() << "unset multiplot\n";
  if (auto st = RunGnuplot(gp.str(), png_path + ".gp", png_path + ".log"); !st)
    return MakeError(st.error().code, "plot " + png_path + ": " + st.error().message);
  return {};
}

}  // namespace pbppo::report
