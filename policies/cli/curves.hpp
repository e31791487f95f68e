// `pbppo curves`: training runs drawn against each other, a group per schedule (or any other
// choice), each the mean of a log.csv column over its runs with a one-sd band (report/).
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct CurvesOptions {
  std::vector<std::string> groups;  // NAME=RUN_DIR[,RUN_DIR...]
  std::string out;
  std::string column = "train_return_100";
  std::string title;
  std::string ylabel;
};
void AddCurvesOptions(CLI::App& sub, CurvesOptions& o);
int Curves(const CurvesOptions& o);

}  // namespace pbppo::cli
