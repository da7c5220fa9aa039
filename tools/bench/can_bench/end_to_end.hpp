// Figure 3: end to end in the canopen-sim teleoperation, a master row to the RPDO that carries its command.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "options.hpp"
#include "saw/rt_context.hpp"

namespace saw::bench::can_bench {

struct E2eRun {
  bool ran = false;
  std::string failure;
  std::vector<std::int64_t> total, to_command, to_rpdo;  // ns
  std::uint64_t teleop_cycles = 0, matched = 0, superseded = 0, ambiguous = 0, row_changed = 0;
  double teleop_age_mean_us = 0, teleop_age_max_us = 0;
  double master_p99 = 0, slave_p99 = 0, teleop_p99 = 0;  // wake-up latency, µs
  std::uint64_t sim_overruns = 0, listener_overruns = 0;
  std::string bus;
};

// How e2e() sees the slave's and the teleoperation's cycles. An observer is installed before any
// task starts (saw::set_rt_cycle_observer), so main installs this one for the whole run.
extern const saw::RtCycleObserver cycle_observer;

// `seconds` of o.config's teleoperation with its drives in saw-can-sim, on a bus of its own.
// A failure is kept in out.failure, not thrown: the figures before it are still reported.
void e2e(const Options& o, double seconds, E2eRun& out);

}  // namespace saw::bench::can_bench
