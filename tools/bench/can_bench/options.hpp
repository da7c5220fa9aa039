// The run's settings from the command line, as the I/O windows and the end-to-end run take them.
#pragma once

#include <string>

namespace saw::bench::can_bench {

struct Options {
  double seconds = 1.0;
  int rounds = 2, priority = 80, cpu = 1, other_cpu = 0, sim_priority = 70, max_drives = 6;
  std::string sim_exe, config = "config/canopen-sim.yaml", log_dir;
};

}  // namespace saw::bench::can_bench
