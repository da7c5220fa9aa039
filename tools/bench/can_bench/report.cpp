#include "report.hpp"

#include <cstdint>
#include <cstdio>
#include <fstream>

#include "../stats.hpp"
#include "rt_warnings.hpp"

namespace saw::bench::can_bench {
namespace {

std::string json_summary(const Summary& s) {
  char b[200];
  std::snprintf(b, sizeof b, R"({"p50": %.3f, "p99": %.3f, "max": %.3f, "n": %zu})", s.median_us, s.p99_us,
                s.max_us, s.n);
  return b;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out + "\"";
}

template <class F>
Summary column(const std::vector<IoSample>& v, F field) {
  std::vector<std::int64_t> x;
  x.reserve(v.size());
  for (const auto& s : v) x.push_back(field(s));
  return summarize(x);
}

double mean_frames(const std::vector<IoSample>& v, bool in) {
  double sum = 0;
  for (const auto& s : v) sum += in ? s.frames_in : s.frames_out;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

struct IoFigures {
  Summary io, rx, tx, bus_rx, bus_tx, floor, compute, wakeup, sync;
  double in = 0, out = 0;
};

IoFigures figures(const IoRun& r) {
  IoFigures f;
  f.io = column(r.samples, [](const IoSample& s) { return s.io; });
  f.rx = column(r.samples, [](const IoSample& s) { return s.rx; });
  f.tx = column(r.samples, [](const IoSample& s) { return s.tx; });
  f.bus_rx = column(r.samples, [](const IoSample& s) { return s.bus_rx; });
  f.bus_tx = column(r.samples, [](const IoSample& s) { return s.bus_tx; });
  f.floor = column(r.samples, [](const IoSample& s) { return s.floor; });
  f.compute = column(r.samples, [](const IoSample& s) { return s.compute; });
  f.wakeup = column(r.samples, [](const IoSample& s) { return s.wakeup; });
  auto dev = r.sync_deviation;
  f.sync = summarize(dev);
  f.in = mean_frames(r.samples, true);
  f.out = mean_frames(r.samples, false);
  return f;
}

const char* verdict(bool met) { return met ? "met" : "missed"; }

// What the tables and the JSON both show, computed once.
struct Figures {
  std::vector<IoFigures> io;  // one per run
  std::size_t big = 0;        // the run the goals are judged on
  double add50 = 0, add99 = 0, sync_ratio = 0;
  bool io_met = false, io_met_p50 = false, sync_met = false;
  Summary total, to_command, to_rpdo;  // end to end, if it ran
};

Figures compute(const std::vector<IoRun>& runs, const E2eRun& e2e_run) {
  Figures out;
  auto& fig = out.io;
  for (const auto& r : runs) fig.push_back(figures(r));
  // The goals, on the largest drive count.
  const std::size_t big = runs.size() - 1;
  out.big = big;
  out.add50 = fig[big].io.median_us - fig[0].io.median_us;
  out.add99 = fig[big].io.p99_us - fig[0].io.p99_us;
  out.sync_ratio = fig[big].wakeup.p99_us > 0 ? fig[big].sync.p99_us / fig[big].wakeup.p99_us : 0;
  out.io_met = !runs[big].samples.empty() && out.add99 <= 10.0;
  out.io_met_p50 = !runs[big].samples.empty() && out.add50 <= 10.0;
  out.sync_met = fig[big].sync.n > 0 && out.sync_ratio <= 1.2;
  if (e2e_run.ran) {
    auto total = e2e_run.total, to_command = e2e_run.to_command, to_rpdo = e2e_run.to_rpdo;
    out.total = summarize(total);
    out.to_command = summarize(to_command);
    out.to_rpdo = summarize(to_rpdo);
  }
  return out;
}

void print_io(const Options& o, const RunInfo& info, const std::vector<IoRun>& runs, const Figures& figs) {
  const auto& fig = figs.io;
  std::printf(
      "# saw-bench-can: %d × %.1f s per drive count in turns; master task 1 kHz SCHED_FIFO %d on CPU %d; "
      "saw-can-sim (250 µs cycle, SCHED_FIFO %d) and the listener on CPU %d; virtual bus\n",
      o.rounds, o.seconds, o.priority, o.cpu, o.sim_priority, o.other_cpu);
  std::printf("# load average (1, 5, 15 min) before %s, after %s; %d CPUs\n", info.load_before.c_str(),
              info.load_after.c_str(), info.cpus);
  for (const auto& w : rt_warnings()) std::printf("# warning: %s\n", w.c_str());
  std::printf("\n");
  std::printf(
      "CAN I/O per cycle (receive + setpoints + transmit; bus: inside the bus's receive() and send()), µs;\n"
      "whole cycle: wake-up to sleep\n");
  std::printf("%-18s %8s %8s %8s %8s %8s %8s %8s %9s %9s %9s %8s %7s %7s\n", "drives", "I/O p50", "p99",
              "max", "rx p50", "bus rx", "tx p50", "bus tx", "cycle p50", "p99", "max", "wake p99", "in/cyc",
              "out/cyc");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& f = fig[i];
    const std::string label = runs[i].drives == 0 ? "0 (empty cycle)" : std::to_string(runs[i].drives);
    std::printf("%-18s %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %9.3f %9.3f %9.3f %8.1f %7.1f %7.1f\n",
                label.c_str(), f.io.median_us, f.io.p99_us, f.io.max_us, f.rx.median_us, f.bus_rx.median_us,
                f.tx.median_us, f.bus_tx.median_us, f.compute.median_us, f.compute.p99_us, f.compute.max_us,
                f.wakeup.p99_us, f.in, f.out);
  }
  std::printf("the same three clock reads around nothing, in the %d-drive cycles: p50 %.3f p99 %.3f µs\n",
              runs.back().drives, fig.back().floor.median_us, fig.back().floor.p99_us);
  std::printf(
      "\nSYNC period as the bus stamped it: |interval − 1 ms|, µs, beside the same cycles' wake-up\n");
  std::printf("%-8s %8s %8s %8s %8s %6s %9s %9s %9s\n", "drives", "n", "p50", "p99", "max", "gaps",
              "wake p99", "wake max", "ratio");
  for (std::size_t i = 1; i < runs.size(); ++i) {
    const auto& f = fig[i];
    std::printf("%-8d %8zu %8.1f %8.1f %8.1f %6llu %9.1f %9.1f %9.2f\n", runs[i].drives, f.sync.n,
                f.sync.median_us, f.sync.p99_us, f.sync.max_us,
                static_cast<unsigned long long>(runs[i].sync_gaps), f.wakeup.p99_us, f.wakeup.max_us,
                f.wakeup.p99_us > 0 ? f.sync.p99_us / f.wakeup.p99_us : 0.0);
  }
  for (const auto& r : runs) {
    for (const auto& e : r.failures) std::printf("window with %d drives failed: %s\n", r.drives, e.c_str());
    // A lapped listener misses SYNCs: its gaps would be its own, not the sender's.
    if (r.listener_overruns > 0)
      std::printf("the listener lost %llu frames with %d drives: its SYNC gaps are not all the sender's\n",
                  static_cast<unsigned long long>(r.listener_overruns), r.drives);
  }
}

void print_goals(const std::vector<IoRun>& runs, const Figures& figs) {
  const auto& fig = figs.io;
  const std::size_t big = figs.big;
  std::printf(
      "\ngoal: CAN I/O with %d drives adds ≤ 10 µs to a cycle: +%.3f µs at p50 (%s), +%.3f µs at p99 (%s)\n",
      runs[big].drives, figs.add50, verdict(figs.io_met_p50), figs.add99, verdict(figs.io_met));
  std::printf(
      "goal: SYNC jitter p99 ≤ 1.2 × the task's wake-up p99 (%d drives): %.1f / %.1f µs = %.2f (%s)\n",
      runs[big].drives, fig[big].sync.p99_us, fig[big].wakeup.p99_us, figs.sync_ratio,
      verdict(figs.sync_met));
}

void print_e2e(const Options& o, const RunInfo& info, const E2eRun& e2e_run, const Figures& figs) {
  std::printf("\nEnd to end, %s on %s (%.1f s): µs\n", o.config.c_str(), e2e_run.bus.c_str(),
              info.e2e_seconds);
  if (!e2e_run.failure.empty()) std::printf("failed: %s\n", e2e_run.failure.c_str());
  std::printf("%-46s %9s %9s %9s %7s\n", "path", "p50", "p99", "max", "n");
  const auto row = [](const char* name, const Summary& s) {
    std::printf("%-46s %9.1f %9.1f %9.1f %7zu\n", name, s.median_us, s.p99_us, s.max_us, s.n);
  };
  row("master row -> RPDO on the bus (end to end)", figs.total);
  row("master row -> teleop cycle's end (command sent)", figs.to_command);
  row("teleop cycle's end -> RPDO on the bus", figs.to_rpdo);
  std::printf(
      "teleop cycles %llu: matched %llu, superseded %llu, ambiguous %llu, master row changed mid-cycle "
      "%llu\n",
      static_cast<unsigned long long>(e2e_run.teleop_cycles),
      static_cast<unsigned long long>(e2e_run.matched), static_cast<unsigned long long>(e2e_run.superseded),
      static_cast<unsigned long long>(e2e_run.ambiguous),
      static_cast<unsigned long long>(e2e_run.row_changed));
  std::printf("teleop's own figure, master sample -> force command: mean %.1f µs, max %.1f µs\n",
              e2e_run.teleop_age_mean_us, e2e_run.teleop_age_max_us);
  std::printf("wake-up p99 µs: master %.1f, slave %.1f, teleop %.1f; saw-can-sim overruns %llu\n",
              e2e_run.master_p99, e2e_run.slave_p99, e2e_run.teleop_p99,
              static_cast<unsigned long long>(e2e_run.sim_overruns));
}

void write_json(const std::string& path, const Options& o, const RunInfo& info,
                const std::vector<IoRun>& runs, const E2eRun& e2e_run, const Figures& figs) {
  const auto& fig = figs.io;
  const std::size_t big = figs.big;
  const auto& warnings = rt_warnings();
  std::ofstream j(path);
  j << "{\n  \"command\": " << json_string(info.command) << ",\n";
  j << "  \"seconds\": " << o.seconds << ", \"rounds\": " << o.rounds << ", \"priority\": " << o.priority
    << ", \"load_before\": " << json_string(info.load_before)
    << ", \"load_after\": " << json_string(info.load_after) << ", \"cpus\": " << info.cpus
    << ", \"cpu\": " << o.cpu << ", \"other_cpu\": " << o.other_cpu
    << ", \"sim_priority\": " << o.sim_priority << ",\n  \"warnings\": [";
  for (std::size_t k = 0; k < warnings.size(); ++k) j << (k ? ", " : "") << json_string(warnings[k]);
  j << "],\n  \"io\": [\n";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& f = fig[i];
    const auto& r = runs[i];
    j << "    {\"drives\": " << r.drives << ", \"windows\": " << r.windows
      << ", \"io\": " << json_summary(f.io) << ", \"rx\": " << json_summary(f.rx)
      << ", \"tx\": " << json_summary(f.tx) << ", \"bus_rx\": " << json_summary(f.bus_rx)
      << ", \"bus_tx\": " << json_summary(f.bus_tx) << ", \"floor\": " << json_summary(f.floor)
      << ", \"cycle\": " << json_summary(f.compute) << ", \"wakeup\": " << json_summary(f.wakeup)
      << ", \"sync\": " << json_summary(f.sync) << ", \"sync_gaps\": " << r.sync_gaps
      << ", \"frames_in\": " << f.in << ", \"frames_out\": " << f.out
      << ", \"send_refused\": " << r.send_refused << ", \"listener_overruns\": " << r.listener_overruns
      << ", \"sim_overruns\": " << r.sim_overruns << ", \"failures\": [";
    for (std::size_t k = 0; k < r.failures.size(); ++k) j << (k ? ", " : "") << json_string(r.failures[k]);
    j << "]}" << (i + 1 < runs.size() ? "," : "") << "\n";
  }
  j << "  ],\n  \"goals\": {\"io\": {\"drives\": " << runs[big].drives << ", \"added_p50\": " << figs.add50
    << ", \"added_p99\": " << figs.add99
    << ", \"limit\": 10, \"met_p50\": " << (figs.io_met_p50 ? "true" : "false")
    << ", \"met\": " << (figs.io_met ? "true" : "false") << "}, \"sync\": {\"drives\": " << runs[big].drives
    << ", \"sync_p99\": " << fig[big].sync.p99_us << ", \"wakeup_p99\": " << fig[big].wakeup.p99_us
    << ", \"ratio\": " << figs.sync_ratio
    << ", \"limit\": 1.2, \"met\": " << (figs.sync_met ? "true" : "false") << "}}";
  if (e2e_run.ran) {
    j << ",\n  \"e2e\": {\"config\": " << json_string(o.config) << ", \"bus\": " << json_string(e2e_run.bus)
      << ", \"seconds\": " << info.e2e_seconds << ", \"failure\": " << json_string(e2e_run.failure)
      << ", \"total\": " << json_summary(figs.total) << ", \"to_command\": " << json_summary(figs.to_command)
      << ", \"to_rpdo\": " << json_summary(figs.to_rpdo) << ", \"teleop_cycles\": " << e2e_run.teleop_cycles
      << ", \"matched\": " << e2e_run.matched << ", \"superseded\": " << e2e_run.superseded
      << ", \"ambiguous\": " << e2e_run.ambiguous << ", \"row_changed\": " << e2e_run.row_changed
      << ", \"teleop_age_mean\": " << e2e_run.teleop_age_mean_us
      << ", \"teleop_age_max\": " << e2e_run.teleop_age_max_us
      << ", \"wakeup_p99\": {\"master\": " << e2e_run.master_p99 << ", \"slave\": " << e2e_run.slave_p99
      << ", \"teleop\": " << e2e_run.teleop_p99 << "}, \"sim_overruns\": " << e2e_run.sim_overruns << "}";
  }
  j << "\n}\n";
}

}  // namespace

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

void report(const Options& o, const RunInfo& info, const std::vector<IoRun>& runs, const E2eRun& e2e_run,
            const std::string& json) {
  const Figures figs = compute(runs, e2e_run);
  print_io(o, info, runs, figs);
  print_goals(runs, figs);
  if (e2e_run.ran) print_e2e(o, info, e2e_run, figs);
  if (!json.empty()) write_json(json, o, info, runs, e2e_run, figs);
}

}  // namespace saw::bench::can_bench
