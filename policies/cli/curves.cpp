#include "policies/cli/curves.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>

#include "report/plots.hpp"

namespace pbppo::cli {

void AddCurvesOptions(CLI::App& s, CurvesOptions& o) {
  s.add_option("groups", o.groups, "NAME=RUN_DIR[,RUN_DIR...]: one curve per group, its runs' mean and band")
      ->required();
  s.add_option("--out", o.out, "Output PNG (its gnuplot script beside it)")->required();
  s.add_option("--column", o.column, "The log.csv column against env_steps (default train_return_100)");
  s.add_option("--title", o.title, "Title");
  s.add_option("--ylabel", o.ylabel, "y-axis label (default: the column)");
}

int Curves(const CurvesOptions& o) {
  report::CurveBands c;
  c.title = o.title;
  c.column = o.column;
  c.ylabel = o.ylabel;
  for (const auto& g : o.groups) {
    const auto eq = g.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == g.size()) {
      std::fprintf(stderr, "pbppo curves: group '%s' is not NAME=RUN_DIR[,RUN_DIR...]\n", g.c_str());
      return 2;
    }
    report::CurveBands::Group group{g.substr(0, eq), {}};
    std::size_t pos = eq + 1;
    while (pos <= g.size()) {
      const std::size_t comma = std::min(g.find(',', pos), g.size());
      group.runs.push_back(g.substr(pos, comma - pos));
      pos = comma + 1;
    }
    c.groups.push_back(std::move(group));
  }
  if (auto st = report::PlotCurveBands(c, o.out); !st) {
    std::fprintf(stderr, "pbppo curves: %s\n", st.error().message.c_str());
    return st.error().code == ErrorCode::kInvalidValue ? 2 : 1;
  }
  std::printf("%s\n", o.out.c_str());
  return 0;
}

}  // namespace pbppo::cli
