// Running gnuplot: one script per figure (or per set of figures), written beside its output so
// that it can be re-run by hand, with gnuplot's messages in a log file next to it.
#pragma once

#include <string>

#include "runtime/core/result.hpp"

namespace pbppo::report {

// Whether a gnuplot program is on the PATH.
bool GnuplotAvailable();

// Writes `script` to script_path and runs gnuplot on it, its messages into log_path. Errors say
// what failed: gnuplot missing, the script unwritable, or gnuplot's own failure (see the log).
Status RunGnuplot(const std::string& script, const std::string& script_path, const std::string& log_path);

// `text` as a gnuplot single-quoted string (quotes doubled).
std::string Quoted(const std::string& text);

}  // namespace pbppo::report
