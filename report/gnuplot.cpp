#include "report/gnuplot.hpp"

#include <cstdlib>
#include <fstream>

namespace pbppo::report {
namespace {

std::string ShellQuoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

bool GnuplotAvailable() {
  return std::system("command -v gnuplot >/dev/null 2>&1") == 0;
}

std::string Quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

Status RunGnuplot(const std::string& script, const std::string& script_path, const std::string& log_path) {
  if (!GnuplotAvailable())
    return MakeError(ErrorCode::kUnsupported, "gnuplot not found (install gnuplot-nox, see tools/setup.sh)");
  {
    std::ofstream f(script_path);
    f << script;
    if (!f.good()) return MakeError(ErrorCode::kIo, "cannot write " + script_path);
  }
  const std::string cmd = "gnuplot " + ShellQuoted(script_path) + " 2>" + ShellQuoted(log_path);
  if (std::system(cmd.c_str()) != 0) return MakeError(ErrorCode::kIo, "gnuplot failed, see " + log_path);
  return {};
}

}  // namespace pbppo::report
