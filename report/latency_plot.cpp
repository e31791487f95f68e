#include <sstream>

#include "report/gnuplot.hpp"
#include "report/plots.hpp"

namespace pbppo::report {

Status PlotLatency(const rt::ProfileReport& r, const std::string& png_path, const std::string& title) {
  std::ostringstream data, plot;
  int blocks = 0;
  for (std::size_t i = 0; i < rt::kStageCount; ++i) {
    const auto buckets = r.snapshots[i].NonEmptyBuckets();
    if (buckets.empty()) continue;
    const char* stage = rt::ToString(static_cast<rt::Stage>(i));
    data << "$" << stage << " << EOD\n";
    for (const auto& b : buckets)
      data << static_cast<double>(b.lower_ns) / 1000.0 << ' ' << static_cast<double>(b.lower_ns + b.width_ns) / 1000.0
           << ' ' << b.count << "\n";
    data << "EOD\n";
    plot << (blocks == 0 ? "plot " : ", ") << "$" << stage << " using 1:3 with steps lw 1.5 title '" << stage << "'";
    ++blocks;
  }
  if (blocks == 0) return MakeError(ErrorCode::kInvalidValue, "plot " + png_path + ": nothing recorded");
  std::ostringstream gp;
  gp << data.str() << "set terminal png size 1000,560\nset output " << Quoted(png_path)
     << "\nset termoption noenhanced\n"
     << "set title " << Quoted(title) << "\nset logscale x\nset logscale y\nset xlabel 'latency (us)'\n"
     << "set ylabel 'count'\nset grid\nset key top right\n"
     << plot.str() << "\n";
  if (auto st = RunGnuplot(gp.str(), png_path + ".gp", png_path + ".log"); !st)
    return MakeError(st.error().code, "plot " + png_path + ": " + st.error().message);
  return {};
}

}  // namespace pbppo::report
