// report/: every figure is a real PNG of the size its script asks for (the CI machine has
// gnuplot, so a missing gnuplot fails here), written beside the script that drew it; bad requests
// are refused naming the file.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "report/gnuplot.hpp"
#include "report/plots.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::report {
namespace {

struct PngSize {
  std::uint32_t width = 0, height = 0;
};

// Width and height from the PNG signature and IHDR chunk; zeros when the file is not a PNG.
PngSize ReadPngSize(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  unsigned char h[24] = {};
  f.read(reinterpret_cast<char*>(h), sizeof h);
  const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!f || !std::equal(sig, sig + 8, h) || std::string(reinterpret_cast<char*>(h + 12), 4) != "IHDR") return {};
  auto be32 = [&](int at) {
    return (std::uint32_t{h[at]} << 24) | (std::uint32_t{h[at + 1]} << 16) | (std::uint32_t{h[at + 2]} << 8) |
           std::uint32_t{h[at + 3]};
  };
  return {be32(16), be32(20)};
}

// The plot succeeded and wrote a PNG of this size.
void CheckPng(const Status& st, const std::string& png, std::uint32_t width, std::uint32_t height) {
  REQUIRE_MESSAGE(st.ok(), (st.ok() ? "" : st.error().message));
  const PngSize size = ReadPngSize(png);
  CHECK_MESSAGE(size.width == width, png);
  CHECK_MESSAGE(size.height == height, png);
}

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  return std::string((std::istreambuf_iterator<char>(f)), {});
}

TEST_CASE("gnuplot is installed (the CI machine has it: tools/setup.sh)") {
  REQUIRE(GnuplotAvailable());
}

TEST_CASE("latency histograms: a PNG of every recorded stage, its script beside it") {
  rt::TickProfiler p;
  for (int i = 0; i < 10000; ++i) {
    p.Record(rt::Stage::kReceive, 300 + i % 50);
    p.Record(rt::Stage::kInfer, 9000 + (i % 100) * 10);
    p.Record(rt::Stage::kTick, 12000 + (i % 100) * 10);
  }
  const std::string dir = test::ScratchDir("report_latency");
  CheckPng(PlotLatency(rt::TakeReport(p), dir + "/latency.png", "test's tick"), dir + "/latency.png", 1000, 560);
  const std::string script = ReadText(dir + "/latency.png.gp");
  CHECK(script.find("$infer << EOD") != std::string::npos);
  CHECK(script.find("$observe") == std::string::npos);  // nothing recorded there
  CHECK(script.find("'test''s tick'") != std::string::npos);

  const auto empty = PlotLatency(rt::TakeReport(rt::TickProfiler{}), dir + "/empty.png", "none");
  REQUIRE_FALSE(empty.ok());
  CHECK(empty.error().message == "plot " + dir + "/empty.png: nothing recorded");
  const auto unwritable = PlotLatency(rt::TakeReport(p), dir + "/no/such/dir/l.png", "x");
  REQUIRE_FALSE(unwritable.ok());
  CHECK(unwritable.error().message.find("plot " + dir + "/no/such/dir/l.png: cannot write") == 0);
}

TEST_CASE("training curves: return, clip bound, arm pulls and task success from log.csv by column name") {
  const std::string dir = test::ScratchDir("report_training");
  {
    // Columns in another order than the trainer writes them, with one the plots do not use.
    std::ofstream log(dir + "/log.csv");
    log << "iteration,epsilon,env_steps,unused,feedback,train_return_100,task_success_100\n";
    for (int i = 0; i < 20; ++i)
      log << i << ',' << (i % 3 == 0 ? 0.1 : 0.3) << ',' << 1024 * (i + 1) << ",7," << (i % 2 ? "nan" : "-50") << ','
          << -100 + 4 * i << ',' << i / 20.0 << '\n';
  }
  TrainingCurves c{dir, {0.1, 0.2, 0.3}, {7, 0, 13}, true};
  auto pngs = PlotTrainingCurves(c);
  REQUIRE_MESSAGE(pngs.ok(), (pngs.ok() ? "" : pngs.error().message));
  CHECK(*pngs ==
        std::vector<std::string>{dir + "/return.png", dir + "/epsilon.png", dir + "/arms.png", dir + "/success.png"});
  for (const auto& png : *pngs) CheckPng({}, png, 900, 500);
  const std::string script = ReadText(dir + "/plots.gp");
  CHECK(script.find("$arms << EOD\nepsilon,pulls\n0.1,7\n0.2,0\n0.3,13\nEOD\n") == 0);  // a header: no arm is lost

  // No task success: three figures.
  std::filesystem::remove(dir + "/success.png");
  c.task_success = false;
  pngs = PlotTrainingCurves(c);
  REQUIRE(pngs.ok());
  CHECK(pngs->size() == 3);
  CHECK_FALSE(std::filesystem::exists(dir + "/success.png"));

  c.pulls = {1, 2};
  pngs = PlotTrainingCurves(c);
  REQUIRE_FALSE(pngs.ok());
  CHECK(pngs.error().message == "training curves: 3 arms, 2 pull counts");
  // A log without the columns: gnuplot's own error, in the log the message names.
  const std::string bad = test::ScratchDir("report_training_bad");
  std::ofstream(bad + "/log.csv") << "a,b\n1,2\n";
  pngs = PlotTrainingCurves({bad, {0.2}, {1}, false});
  REQUIRE_FALSE(pngs.ok());
  CHECK(pngs.error().message == "gnuplot failed, see " + bad + "/gnuplot.log");
}

TEST_CASE("map: arena, obstacles, targets and paths of every kind") {
  MapPlot m;
  m.title = "a map";
  m.arena = {0, 40, 0, 30};
  m.boxes = {{10, 12, 5, 25}};
  m.obstacles = {{20, 15, 2}};
  m.random_obstacles = {{30, 10, 1}, {30, 20, 1.5}};
  m.targets = {{35, 25}, {5, 25}};
  m.target_radius_m = 1.5;
  m.paths = {{{{2, 2}, {8, 3}, {20, 28}, {35, 25}}, MapPlot::PathKind::kSuccess},
             {{{2, 3}, {9, 10}}, MapPlot::PathKind::kFailure},
             {{{1, 1}, {5, 5}}, MapPlot::PathKind::kTrajectory}};
  const std::string dir = test::ScratchDir("report_map");
  CheckPng(PlotMap(m, dir + "/map.png"), dir + "/map.png", 900, 900);
  // The arena alone (no series at all) is still a figure.
  MapPlot empty;
  empty.arena = {0, 10, 0, 10};
  CheckPng(PlotMap(empty, dir + "/empty.png"), dir + "/empty.png", 900, 900);
}

TEST_CASE("time series: stacked panels of commanded (dashed) and measured series, one colour per group") {
  TimeSeriesPlot p;
  p.title = "two robots";
  for (const char* label : {"vx [m/s]", "yaw rate [rad/s]"}) {
    TimeSeriesPlot::Panel panel;
    panel.ylabel = label;
    for (int robot = 0; robot < 2; ++robot) {
      TimeSeriesPlot::Series command{"robot " + std::to_string(robot) + " command", robot, true, {}, {}};
      TimeSeriesPlot::Series measured{"robot " + std::to_string(robot) + " measured", robot, false, {}, {}};
      for (int k = 0; k < 50; ++k) {
        command.x.push_back(0.02 * k);
        command.y.push_back(robot + 0.5);
        measured.x.push_back(0.02 * k);
        measured.y.push_back((robot + 0.5) * (1 - std::exp(-0.1 * k)));
      }
      panel.series.push_back(command);
      panel.series.push_back(measured);
    }
    p.panels.push_back(panel);
  }
  const std::string dir = test::ScratchDir("report_time_series");
  CheckPng(PlotTimeSeries(p, dir + "/ts.png"), dir + "/ts.png", 1100, 600);  // 300 per panel
  p.panels[0].series[1].y.pop_back();
  auto st = PlotTimeSeries(p, dir + "/bad.png");
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message == "plot " + dir + "/bad.png: series 'robot 0 measured' has 50 x and 49 y values");
  st = PlotTimeSeries(TimeSeriesPlot{}, dir + "/none.png");
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message == "plot " + dir + "/none.png: no panel");
}

TEST_CASE("curve bands: each group's mean over its runs with a one-sd band, NaN rows left out") {
  const std::string dir = test::ScratchDir("report_bands");
  // Three runs of one group (the third with a NaN row and one step fewer) and one of another.
  auto run = [&](const std::string& name, double offset, int rows) {
    std::filesystem::create_directories(dir + "/" + name);
    std::ofstream log(dir + "/" + name + "/log.csv");
    log << "iteration,env_steps,train_return_100\n";
    for (int i = 0; i < rows; ++i)
      log << i << ',' << 100 * (i + 1) << ',' << (i == 2 ? "nan" : "") << offset + i << '\n';
    return dir + "/" + name;
  };
  CurveBands c;
  c.title = "two groups";
  c.groups = {{"a", {run("a1", 0, 10), run("a2", 2, 10), run("a3", 4, 9)}}, {"b", {run("b1", -5, 10)}}};
  CheckPng(PlotCurveBands(c, dir + "/bands.png"), dir + "/bands.png", 900, 500);
  const std::string script = ReadText(dir + "/bands.png.gp");
  CHECK(script.find("$g0 << EOD\n100 2 0 4\n200 3 1 5\n400 5 3 7\n") == 0);  // the NaN row (300) is left out
  CHECK(script.find("1000 10 8.58579 11.4142\n") != std::string::npos);      // two runs reach 1000 steps
  CHECK(script.find("$g1 << EOD\n100 -5 -5 -5\n") != std::string::npos);     // one run: no band
  CHECK(script.find("title 'a (3 runs)'") != std::string::npos);

  c.column = "missing";
  auto st = PlotCurveBands(c, dir + "/bad.png");
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message == "curves: " + dir + "/a1/log.csv has no column 'missing'");
  c.column = "train_return_100";
  c.groups[1].runs.push_back(dir + "/nowhere");
  st = PlotCurveBands(c, dir + "/bad.png");
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message == "curves: cannot read " + dir + "/nowhere/log.csv");
}

}  // namespace
}  // namespace pbppo::report
