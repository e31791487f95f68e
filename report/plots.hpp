// The project's figures, drawn with gnuplot (report/gnuplot.hpp): training curves from a run's
// log.csv, latency histograms from a tick profile, maps of a navigation task with trajectories, and
// time series in stacked panels.
// Each writes its PNGs and the gnuplot script that drew them; errors name the file and the cause.
#pragma once

#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/rt/tick_profiler.hpp"

namespace pbppo::report {

// Groups of runs against each other (one group per clip schedule, say, one run per seed): per group
// the mean over its runs of one log.csv column against env_steps, with a band of one standard
// deviation over the runs either side where two runs or more have a value there (NaN rows are left
// out). Errors name the run and the missing file or column.
struct CurveBands {
  struct Group {
    std::string name;
    std::vector<std::string> runs;  // run folders, each holding log.csv
  };
  std::string title;
  std::string column = "train_return_100";
  std::string ylabel;  // empty: the column's name
  std::vector<Group> groups;
};
Status PlotCurveBands(const CurveBands& bands, const std::string& png_path);

// A training run's curves, from DIR/log.csv (the trainer's per-iteration log, read by column name):
// return.png (last-100 training return and the bandit feedback over environment steps), epsilon.png
// (the clip bound chosen each iteration), arms.png (pulls per candidate clip bound) and, where the
// task reports success, success.png. The script is DIR/plots.gp, gnuplot's messages DIR/gnuplot.log.
struct TrainingCurves {
  std::string dir;
  std::vector<double> arms;  // candidate clip bounds
  std::vector<int> pulls;    // per arm
  bool task_success = false;
};
// The PNGs written, in the order above.
Result<std::vector<std::string>> PlotTrainingCurves(const TrainingCurves& curves);

// The histogram of every stage that recorded something (log-scale counts over log-scale
// microseconds) into png_path; its script (data inline) is png_path + ".gp".
Status PlotLatency(const rt::ProfileReport& report, const std::string& png_path, const std::string& title);

// A top view of a navigation task: the arena's walls, obstacles (circles and boxes), numbered
// targets and trajectories, at equal scale on both axes. Script (data inline): png_path + ".gp".
struct MapPlot {
  struct Point {
    double x_m = 0, y_m = 0;
  };
  struct Circle {
    double x_m = 0, y_m = 0, radius_m = 0;
  };
  struct Rect {
    double x_min_m = 0, x_max_m = 0, y_min_m = 0, y_max_m = 0;
  };
  enum class PathKind { kTrajectory, kSuccess, kFailure };
  struct Path {
    std::vector<Point> xy;
    PathKind kind = PathKind::kTrajectory;
  };

  std::string title;
  Rect arena;
  std::vector<Rect> boxes;
  std::vector<Circle> obstacles;         // the layout's
  std::vector<Circle> random_obstacles;  // drawn light: drawn anew each episode
  std::vector<Point> targets;            // labelled 1, 2, ...
  double target_radius_m = 0;            // > 0: also draw each target's acceptance circle
  std::vector<Path> paths;               // each starts with a dot
};
Status PlotMap(const MapPlot& map, const std::string& png_path);

// Stacked panels sharing the x axis (time), each with its series: for instance commanded (dashed)
// against measured (solid) velocities of a few robots. Series of the same `group` share a colour.
// Script (data inline): png_path + ".gp".
struct TimeSeriesPlot {
  struct Series {
    std::string title;
    int group = 0;
    bool dashed = false;
    std::vector<double> x, y;
  };
  struct Panel {
    std::string ylabel;
    std::vector<Series> series;
  };
  std::string title;
  std::string xlabel = "time [s]";
  std::vector<Panel> panels;
};
Status PlotTimeSeries(const TimeSeriesPlot& plot, const std::string& png_path);

}  // namespace pbppo::report
