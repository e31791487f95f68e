// The recording's command-line options, the same in every program that records a loop
// (pbppo-controller, pbppo_bench_soak): --record LOG [--record-max-mb MB [--record-rotate N]].
// Header-only; include it only where CLI11 is used (the runtime libraries do not).
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <string>

#include "runtime/loop/log.hpp"

namespace pbppo::loop {

struct RecordCli {
  std::string path;        // --record ("": none)
  double max_mb = 0;       // --record-max-mb (0: one file)
  std::uint32_t keep = 0;  // --record-rotate (0: every file)

  RecordOptions options() const {
    RecordOptions o;
    o.max_file_bytes = static_cast<std::uint64_t>(std::llround(max_mb * 1048576.0));
    o.keep_files = keep;
    return o;
  }
};

inline void AddRecordOptions(CLI::App& app, RecordCli& r) {
  auto* record = app.add_option("--record", r.path, "Record every input and command to a log (pbppo replay)");
  auto* max_mb = app.add_option("--record-max-mb", r.max_mb,
                                "Rotate the log: files of at most this many MiB (LOG, then LOG.1, LOG.2 ... before "
                                "the extension), each beginning with the loop's state, so that each replays alone")
                     ->check(CLI::Range(0.01, 1048576.0))
                     ->needs(record);
  app.add_option("--record-rotate", r.keep, "Keep only the newest N files of a rotated log (the oldest deleted)")
      ->check(CLI::Range(1u, 1000000u))
      ->needs(max_mb);
}

}  // namespace pbppo::loop
