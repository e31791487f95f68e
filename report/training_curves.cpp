#include <sstream>

#include "report/gnuplot.hpp"
#include "report/plots.hpp"

namespace pbppo::report {

Result<std::vector<std::string>> PlotTrainingCurves(const TrainingCurves& c) {
  if (c.arms.empty() || c.arms.size() != c.pulls.size())
    return MakeError(ErrorCode::kInvalidValue, "training curves: " + std::to_string(c.arms.size()) + " arms, " +
                                                   std::to_string(c.pulls.size()) + " pull counts");
  const std::string log = Quoted(c.dir + "/log.csv");
  std::vector<std::string> pngs;
  auto output = [&](const char* name) {
    pngs.push_back(c.dir + "/" + name);
    return "set output " + Quoted(pngs.back()) + "\n";
  };
  std::ostringstream gp;
  // With `autotitle columnhead` the first row of every data set is its header: the arms' too.
  gp << "$arms << EOD\nepsilon,pulls\n";
  for (std::size_t i = 0; i < c.arms.size(); ++i) gp << c.arms[i] << ',' << c.pulls[i] << "\n";
  gp << "EOD\n"
     << "set datafile separator ','\nset terminal png size 900,500\nset termoption noenhanced\n"
     << "set key autotitle columnhead\nset grid\nset xlabel 'environment steps'\n"
     // Return: the last 100 training episodes, and the bandit's feedback where it has one.
     << output("return.png") << "set ylabel 'return'\nplot " << log
     << " using 'env_steps':'train_return_100' with lines title 'training return (last 100 episodes)', '' using "
        "'env_steps':'feedback' with linespoints pt 7 ps 0.4 title 'feedback R'\n"
     << output("epsilon.png") << "set ylabel 'clip bound'\nplot " << log
     << " using 'env_steps':'epsilon' with steps title 'chosen epsilon'\n"
     << output("arms.png") << "set xlabel 'arm (clip bound)'\nset ylabel 'pulls'\nset style fill solid\n"
     << "set boxwidth 0.6\nunset key\nset xrange [-0.5:" << static_cast<double>(c.arms.size()) - 0.5
     << "]\nset yrange [0:*]\nplot $arms using 0:2:xtic(1) with boxes\n";
  if (c.task_success) {
    gp << output("success.png") << "set key\nset autoscale x\nset xtics auto\nset yrange [-0.02:1.02]\n"
       << "set xlabel 'environment steps'\nset ylabel 'fraction'\nset style fill empty\nplot " << log
       << " using 'env_steps':'task_success_100' with lines title 'task success (last 100 training episodes)'\n";
  }
  if (auto st = RunGnuplot(gp.str(), c.dir + "/plots.gp", c.dir + "/gnuplot.log"); !st) return st.error();
  return pngs;
}

}  // namespace pbppo::report
