// Figures 1 and 2: the CAN I/O of a 1 kHz cycle, and the SYNC period the bus stamped, per drive count.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "options.hpp"
#include "saw/clock.hpp"

namespace saw::bench::can_bench {

struct IoSample {
  TimeNs io = 0, rx = 0, tx = 0;  // receive + setpoints + transmit; receive; setpoints + transmit
  TimeNs bus_rx = 0, bus_tx = 0;  // of which inside the bus's receive() and send()
  TimeNs floor = 0;               // the same three clock reads around nothing
  TimeNs wakeup = 0;              // the previous cycle's wake-up latency (the task's statistics)
  TimeNs compute = 0;             // the whole cycle two cycles back, wake-up to sleep (ditto)
  std::uint32_t frames_in = 0, frames_out = 0;
};

// One drive count, pooled over its windows.
struct IoRun {
  int drives = 0;
  std::vector<IoSample> samples;
  std::vector<std::int64_t> sync_deviation;  // |SYNC interval − period|, ns
  std::uint64_t syncs = 0, sync_gaps = 0;    // intervals counted; intervals ≥ 1.5 periods
  std::uint64_t send_refused = 0, listener_overruns = 0, sim_overruns = 0, windows = 0;
  std::vector<std::string> failures;
};

// One window of `run.drives` drives (0: the empty cycle) on a bus of its own, pooled into `run`.
// A window that fails is kept in run.failures, not thrown: the other windows still run.
void io_window(const Options& o, IoRun& run, int round);

}  // namespace saw::bench::can_bench
