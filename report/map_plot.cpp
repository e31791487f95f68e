#include <array>
#include <sstream>

#include "report/gnuplot.hpp"
#include "report/plots.hpp"

namespace pbppo::report {

Status PlotMap(const MapPlot& m, const std::string& png_path) {
  using Kind = MapPlot::PathKind;
  std::ostringstream data;
  std::vector<std::string> series;  // plot clauses of the series that have data
  auto block = [&](const std::string& name, const std::string& rows, const std::string& clause) {
    if (rows.empty()) return;
    data << "$" << name << " << EOD\n" << rows << "EOD\n";
    series.push_back("$" + name + " " + clause);
  };
  auto circles = [](const std::vector<MapPlot::Circle>& cs) {
    std::ostringstream o;
    for (const auto& c : cs) o << c.x_m << ' ' << c.y_m << ' ' << c.radius_m << '\n';
    return o.str();
  };
  block("random", circles(m.random_obstacles),
        "using 1:2:3 with circles fs transparent solid 0.12 noborder lc rgb 'gray40' title 'random obstacles'");
  block("obstacles", circles(m.obstacles),
        "using 1:2:3 with circles fs solid 0.6 noborder lc rgb 'gray20' title 'layout obstacles'");
  // Paths: one block per kind, paths separated by blank lines; every path's first point marked.
  const std::array<std::pair<Kind, const char*>, 3> kinds = {
      {{Kind::kSuccess, "success"}, {Kind::kFailure, "failure"}, {Kind::kTrajectory, "trajectory"}}};
  const std::array<const char*, 3> styles = {"with lines lw 1 lc rgb '#2a9d3a' title 'success'",
                                             "with lines lw 1.5 lc rgb '#d62728' title 'failure'",
                                             "with lines lw 2 lc rgb 'blue' title 'trajectory'"};
  std::ostringstream starts;
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    std::ostringstream rows;
    for (const auto& p : m.paths) {
      if (p.kind != kinds[k].first || p.xy.empty()) continue;
      for (const auto& q : p.xy) rows << q.x_m << ' ' << q.y_m << '\n';
      rows << "\n";
    }
    block(kinds[k].second, rows.str(), styles[k]);
  }
  for (const auto& p : m.paths)
    if (!p.xy.empty()) starts << p.xy.front().x_m << ' ' << p.xy.front().y_m << '\n';
  block("starts", starts.str(), "with points pt 7 ps 0.7 lc rgb 'blue' title 'start'");
  std::ostringstream targets;
  for (std::size_t i = 0; i < m.targets.size(); ++i)
    targets << m.targets[i].x_m << ' ' << m.targets[i].y_m << ' ' << i + 1 << '\n';
  block("targets", targets.str(),
        "using 1:2 with points pt 6 ps 3 lw 2 lc rgb 'orange' title 'targets', $targets using 1:2:3 with labels "
        "offset 1.5,1.5 notitle");
  if (m.target_radius_m > 0 && !m.targets.empty()) {
    std::ostringstream r;
    r << "using 1:2:(" << m.target_radius_m << ") with circles fs empty lc rgb 'forest-green' lw 2 notitle";
    series.push_back("$targets " + r.str());
  }

  const auto& a = m.arena;
  std::ostringstream gp;
  gp << data.str() << "set terminal pngcairo size 900,900\nset output " << Quoted(png_path)
     << "\nset termoption noenhanced\nset size ratio -1\nset title " << Quoted(m.title) << "\nset xrange ["
     << a.x_min_m - 1 << ':' << a.x_max_m + 1 << "]\nset yrange [" << a.y_min_m - 1 << ':' << a.y_max_m + 1
     << "]\nset xlabel 'x [m]'\nset ylabel 'y [m]'\nset key outside bottom center horizontal\n"
     << "set object 1 rect from " << a.x_min_m << ',' << a.y_min_m << " to " << a.x_max_m << ',' << a.y_max_m
     << " fs empty border lc rgb 'black' lw 2\n";
  int object = 2;
  for (const auto& b : m.boxes)
    gp << "set object " << object++ << " rect from " << b.x_min_m << ',' << b.y_min_m << " to " << b.x_max_m << ','
       << b.y_max_m << " fc rgb 'gray20' fs solid 0.6 noborder\n";
  if (series.empty()) {
    gp << "plot NaN notitle\n";  // the arena alone
  } else {
    for (std::size_t i = 0; i < series.size(); ++i) gp << (i == 0 ? "plot " : ", ") << series[i];
    gp << "\n";
  }
  if (auto st = RunGnuplot(gp.str(), png_path + ".gp", png_path + ".log"); !st)
    return MakeError(st.error().code, "plot " + png_path + ": " + st.error().message);
  return {};
}

}  // namespace pbppo::report
