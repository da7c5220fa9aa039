// The report of a run: its tables and goals on stdout, and the same figures as JSON.
#pragma once

#include <string>
#include <vector>

#include "end_to_end.hpp"
#include "io_cycle.hpp"
#include "options.hpp"

namespace saw::bench::can_bench {

// How the run went besides its options: the report's heading and the JSON's first fields.
struct RunInfo {
  std::string command;                  // the command line, for the JSON to say how it was made
  std::string load_before, load_after;  // load_average() around the measurements
  int cpus = 0;
  double e2e_seconds = 0;
};

// "0.52 0.58 0.59": the 1, 5 and 15 minute load averages (this benchmark's company).
std::string load_average();

// Prints the figures, and writes them to `json` too unless it is empty (tools/write_performance.py).
void report(const Options& o, const RunInfo& info, const std::vector<IoRun>& runs, const E2eRun& e2e_run,
            const std::string& json);

}  // namespace saw::bench::can_bench
