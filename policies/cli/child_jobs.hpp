// `pbppo` started again as child processes, one per job slot, and Ctrl-C for all of them: used by
// `pbppo sweep` to run its trainings and evaluations.
#pragma once

#include <csignal>
#include <string>
#include <vector>

namespace pbppo::cli {

inline constexpr int kMaxJobs = 256;  // job slots

// While it lives, SIGINT and SIGTERM (what mpirun sends its ranks on Ctrl-C) set Stopped() and
// pass SIGINT on to every running child (pbppo train takes a second one within a second, as from
// the terminal's process group, as the same); the previous handlers come back at its end.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  struct sigaction previous_int_ = {}, previous_term_ = {};
};

// Whether a Ctrl-C came while an InterruptScope lived (reset when the next one starts).
bool Stopped() noexcept;

// Runs this program again (the file it was started from, even if rebuilt since) with ARGS (argv[0]
// "pbppo") in job slot `slot` (0 .. kMaxJobs - 1) to its end: stdin from /dev/null, stdout into OUT
// and stderr into ERR (one file when equal), nothing blocked and SIGINT at its default. Returns its
// exit status (128 + N: killed by signal N; -1 with `error` set: not started).
int RunChild(const std::vector<std::string>& args, const std::string& out, const std::string& err, int slot,
             std::string* error);

}  // namespace pbppo::cli
