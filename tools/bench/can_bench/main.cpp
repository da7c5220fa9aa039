// saw-bench-can: what CANopen costs the 1 kHz cycle on sawrt's virtual CAN bus, with the drives
// simulated by saw-can-sim in another process. Three figures, each beside a baseline from the
// same run (a noisy VM's absolute tails are the machine's, not the code's):
//   1. the BusMaster's receive + transmit per cycle (PDO unpack and pack, the CiA 402
//      controllers, SYNC) for 1, 3 and 6 drives, beside an empty cycle timed the same way;
//   2. the SYNC period as the bus stamped each SYNC, beside the sending task's wake-up latency;
//   3. end to end in config/canopen-sim.yaml's teleoperation: a master sample's row time to the
//      RPDO that carries the command computed from it, as the bus stamped that RPDO.
// Figures, not assertions: goals are printed as met or missed.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "end_to_end.hpp"
#include "io_cycle.hpp"
#include "options.hpp"
#include "report.hpp"
#include "saw/rt_context.hpp"
#include "saw/rt_thread.hpp"

int main(int argc, char** argv) {
  using saw::bench::can_bench::cycle_observer;
  using saw::bench::can_bench::e2e;
  using saw::bench::can_bench::E2eRun;
  using saw::bench::can_bench::io_window;
  using saw::bench::can_bench::IoRun;
  using saw::bench::can_bench::load_average;
  using saw::bench::can_bench::Options;
  using saw::bench::can_bench::report;
  using saw::bench::can_bench::RunInfo;
  CLI::App app{
      "saw-bench-can: the CANopen cycle's cost, SYNC jitter and end-to-end latency on a virtual bus"};
  Options o;
  std::vector<int> drive_counts{1, 3, 6};
  double e2e_seconds = 4;
  std::string json;
  app.add_option("--seconds", o.seconds, "measured seconds per window (each drive count, each round)")
      ->check(CLI::PositiveNumber);
  app.add_option("--rounds", o.rounds, "windows per drive count, taken in turns")->check(CLI::PositiveNumber);
  app.add_option("--drives", drive_counts, "drive counts (each beside the empty cycle)")
      ->check(CLI::Range(1, 64));
  app.add_option("--e2e-seconds", e2e_seconds, "measured seconds of the teleoperation (0: skip it)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--config", o.config,
                 "the teleoperation's deployment (its bus virtual:canopen-sim is renamed)");
  app.add_option("--priority", o.priority, "SCHED_FIFO priority of the master's task")
      ->check(CLI::Range(1, 99));
  app.add_option("--cpu", o.cpu, "CPU of the master's task (saw-can-sim and the listener: the other one)");
  app.add_option("--sim-priority", o.sim_priority, "SCHED_FIFO priority of saw-can-sim")
      ->check(CLI::Range(0, 99));
  app.add_option("--json", json, "also write the figures as JSON here (tools/write_performance.py)");
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGPIPE, SIG_IGN);

  const auto bin = std::filesystem::canonical("/proc/self/exe").parent_path() / "../../bin";
  o.sim_exe = (bin / "saw-can-sim").lexically_normal().string();
  if (!std::filesystem::exists(o.sim_exe)) {
    std::fprintf(stderr, "saw-bench-can: %s not found (build the saw-can-sim target)\n", o.sim_exe.c_str());
    return 2;
  }
  o.log_dir =
      (std::filesystem::temp_directory_path() / ("saw-bench-can-" + std::to_string(getpid()))).string();
  std::filesystem::create_directories(o.log_dir);
  const int ncpu = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  if (ncpu < 2) {
    o.cpu = o.other_cpu = -1;
  } else {
    o.other_cpu = o.cpu == 0 ? 1 : 0;
  }
  if (o.other_cpu >= 0) (void)saw::rt::set_affinity(o.other_cpu);
  saw::set_rt_cycle_observer(&cycle_observer);  // installed before any task starts

  // 1 and 2: the empty cycle and each drive count in turns, so that a slow stretch of the
  // machine falls on all of them alike.
  o.max_drives = *std::max_element(drive_counts.begin(), drive_counts.end());
  const std::string load_before = load_average();
  std::vector<IoRun> runs(1 + drive_counts.size());
  for (std::size_t i = 0; i < drive_counts.size(); ++i) runs[i + 1].drives = drive_counts[i];
  for (int r = 0; r < o.rounds; ++r)
    for (auto& run : runs) io_window(o, run, r);
  E2eRun e2e_run;
  if (e2e_seconds > 0) e2e(o, e2e_seconds, e2e_run);
  std::filesystem::remove_all(o.log_dir);
  const std::string load_after = load_average();

  std::string command;
  for (int i = 0; i < argc; ++i) command += (i ? " " : "") + std::string(argv[i]);
  const RunInfo info{.command = command,
                     .load_before = load_before,
                     .load_after = load_after,
                     .cpus = ncpu,
                     .e2e_seconds = e2e_seconds};
  report(o, info, runs, e2e_run, json);
  bool failed = !e2e_run.failure.empty();
  for (const auto& r : runs) failed = failed || !r.failures.empty();
  return failed ? 1 : 0;
}
