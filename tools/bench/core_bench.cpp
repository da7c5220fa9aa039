// saw-bench-core: the paper's "Local 1P" qualified read and the core's other costs, with the
// timer's own overhead and a cisst-style relative-sleep loop measured beside them.
#include <sys/utsname.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <random>
#include <thread>

#include "saw/manager.hpp"
#include "saw/rt_thread.hpp"
#include "stats.hpp"

namespace {

using namespace std::chrono_literals;
using saw::TimeNs;
using saw::bench::print_row;
using saw::bench::summarize;

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

// The server: a 1 kHz task offering each kind of command the benchmark calls.
class Server : public saw::Task {
 public:
  Server(saw::TaskConfig c, std::size_t stamps) : Task("server", c) {
    auto& p = provide("bench");
    p.set_mailbox_capacity(16384);
    p.add_command_qualified_read<double, double>("add_one", [](const double& q, double& r) { r = q + 1.0; });
    p.add_command_read("position", state_table().add_column("position", &position_));
    p.add_command_write<double>("set", [this](const double& v) { last_ = v; });
    p.add_command_write<TimeNs>("stamp", [this](const TimeNs& t) {
      const auto i = stamped_.load(std::memory_order_relaxed);
      if (i < latencies_.size()) latencies_[i] = saw::monotonic_now() - t;
      stamped_.store(i + 1, std::memory_order_release);
    });
    latencies_.resize(stamps);
  }
  void run() override {
    position_.x += 1;
    position_.y = position_.x * 2;
    position_.z = position_.x * 3;
    const auto n = cycles_.load(std::memory_order_relaxed) + 1;
    // Wake-ups skipped so far (from this task's own statistics row, one cycle old), so that the
    // drift figure counts grid periods, not only the cycles that ran.
    saw::TaskStatistics st;
    if (state_table().read_latest(statistics_column(), st) == saw::Status::ok)
      missed_.store(st.missed_periods);
    last_wake_.store(now(), std::memory_order_relaxed);
    cycles_.store(n, std::memory_order_release);
  }
  std::vector<TimeNs> latencies_;
  std::atomic<std::size_t> stamped_{0};
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<TimeNs> last_wake_{0};
  std::atomic<std::uint64_t> missed_{0};

 private:
  Vec3 position_;
  double last_ = 0;
};

class Client : public saw::Component {
 public:
  Client() : Component("client") {
    auto& r = require("bench");
    r.add_function("add_one", add_one);
    r.add_function("position", position);
    r.add_function("set", set);
    r.add_function("stamp", stamp);
  }
  saw::FunctionQualifiedRead<double, double> add_one;
  saw::FunctionRead<Vec3> position;
  saw::FunctionWrite<double> set;
  saw::FunctionWrite<TimeNs> stamp;
};

// Times each call of f with clock_gettime around it, as the paper did.
template <class F>
std::vector<std::int64_t> time_calls(int n, F&& f) {
  std::vector<std::int64_t> out(static_cast<std::size_t>(n));
  for (auto& s : out) {
    const TimeNs t0 = saw::monotonic_now();
    f();
    s = saw::monotonic_now() - t0;
  }
  return out;
}

// A loop that sleeps one period relative to each wake-up, as cisst's periodic tasks did.
double relative_sleep_rate(int cycles, int priority, int cpu) {
  double rate = 0;
  std::thread t([&] {
    if (priority > 0) (void)saw::rt::set_fifo(priority);
    if (cpu >= 0) (void)saw::rt::set_affinity(cpu);
    const TimeNs start = saw::monotonic_now();
    for (int i = 1; i < cycles; ++i) {
      const timespec ts = saw::to_timespec(1'000'000);
      clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, nullptr);
    }
    rate = (cycles - 1) / (static_cast<double>(saw::monotonic_now() - start) * 1e-9);
  });
  t.join();
  return rate;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-bench-core: Local 1P latencies of the rt core"};
  int calls = 10000, reps = 5, drift_cycles = 10000, priority = 80, stamps = 2000;
  bool quick = false, markdown = false;
  app.add_option("--calls", calls, "calls per repetition");
  app.add_option("--reps", reps, "repetitions");
  app.add_option("--drift-cycles", drift_cycles, "cycles of the drift measurement");
  app.add_option("--priority", priority, "SCHED_FIFO priority of the server (0: none)")
      ->check(CLI::Range(0, 99));
  app.add_flag("--quick", quick, "1,000 calls × 2, 500 drift cycles (smoke run)");
  app.add_flag("--markdown", markdown, "print tables as Markdown");
  CLI11_PARSE(app, argc, argv);
  if (quick) calls = 1000, reps = 2, drift_cycles = 500, stamps = 200;

  utsname u{};
  uname(&u);
  const int ncpu = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  const int server_cpu = ncpu > 1 ? 1 : -1, client_cpu = ncpu > 1 ? 0 : -1;
  std::printf("# saw-bench-core: kernel %s %s, %d CPUs, server SCHED_FIFO %d on CPU %d, caller on CPU %d\n",
              u.release, u.version, ncpu, priority, server_cpu, client_cpu);

  Server server(saw::TaskConfig::periodic(1ms, priority, server_cpu), static_cast<std::size_t>(stamps));
  Client client;
  saw::Manager m;
  m.add(server);
  m.add(client);
  m.connect("client", "bench", "server", "bench");
  m.start();
  for (const auto& w : m.rt_warnings()) std::printf("# warning: %s\n", w.c_str());
  if (client_cpu >= 0) (void)saw::rt::set_affinity(client_cpu);
  while (server.cycles_.load() < 5) std::this_thread::sleep_for(1ms);

  double sink = 0;
  std::vector<std::int64_t> timer_all, qread_all, read_all, write_all;
  std::uint64_t write_refused = 0;
  for (int r = 0; r < reps; ++r) {
    auto timer = time_calls(calls, [] {});
    auto qread = time_calls(calls, [&] {
      double out = 0;
      (void)client.add_one(sink, out);
      sink = out * 1e-9;
    });
    auto read = time_calls(calls, [&] {
      Vec3 v;
      (void)client.position(v);
      sink += v.y;
    });
    auto write = time_calls(calls, [&] {
      if (client.set(sink) != saw::Status::ok) ++write_refused;
    });
    if (!markdown) {
      print_row(false, "rep " + std::to_string(r + 1) + " qualified read<double>", summarize(qread));
      print_row(false, "rep " + std::to_string(r + 1) + " state read<3 doubles>", summarize(read));
    }
    timer_all.insert(timer_all.end(), timer.begin(), timer.end());
    qread_all.insert(qread_all.end(), qread.begin(), qread.end());
    read_all.insert(read_all.end(), read.begin(), read.end());
    write_all.insert(write_all.end(), write.begin(), write.end());
    std::this_thread::sleep_for(20ms);  // let the server drain the queued writes
  }

  // Enqueue → execute: commands sent at irregular times run at the start of the next cycle.
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> gap_us(0, 1500);
  for (int i = 0; i < stamps; ++i) {
    (void)client.stamp(saw::monotonic_now());
    std::this_thread::sleep_for(std::chrono::microseconds(gap_us(rng)));
  }
  while (server.stamped_.load(std::memory_order_acquire) < static_cast<std::size_t>(stamps))
    std::this_thread::sleep_for(1ms);
  std::vector<std::int64_t> exec(server.latencies_.begin(), server.latencies_.end());

  // Drift: wall time of drift_cycles cycles of the 1 kHz task, from its first to its last wake-up.
  const auto c0 = server.cycles_.load(std::memory_order_acquire);
  const TimeNs t0 = server.last_wake_.load();
  const auto m0 = server.missed_.load();
  while (server.cycles_.load(std::memory_order_acquire) < c0 + static_cast<std::uint64_t>(drift_cycles) - 1)
    std::this_thread::sleep_for(1ms);
  const auto c1 = server.cycles_.load(std::memory_order_acquire);
  const TimeNs t1 = server.last_wake_.load();
  const auto m1 = server.missed_.load();
  m.stop();
  const double measured = static_cast<double>(t1 - t0) * 1e-9;
  const auto periods = (c1 - c0) + (m1 - m0);  // cycles run plus wake-ups skipped after overruns
  const double ideal = static_cast<double>(periods) * 1e-3;
  const double baseline_rate = relative_sleep_rate(drift_cycles, priority, server_cpu);

  std::printf("\n## pooled over %d × %d calls\n", reps, calls);
  saw::bench::print_header(markdown);
  print_row(markdown, "timer overhead (empty call)", summarize(timer_all));
  print_row(markdown, "qualified read<double> (Local 1P)", summarize(qread_all));
  print_row(markdown, "state read<3 doubles>", summarize(read_all));
  print_row(markdown, "write command call (enqueue)", summarize(write_all));
  print_row(markdown, "write command enqueue→execute", summarize(exec));
  std::printf("\nwrite calls refused (queue full): %llu\n", static_cast<unsigned long long>(write_refused));
  const auto s = server.statistics();
  const auto& h = server.wakeup_histogram();
  std::printf(
      "drift: %llu grid periods (%llu cycles run, %llu skipped after overruns) took %.6f s, ideal %.6f s: "
      "error %+.3f periods, grid rate %.3f Hz\n",
      static_cast<unsigned long long>(periods), static_cast<unsigned long long>(c1 - c0),
      static_cast<unsigned long long>(m1 - m0), measured, ideal, (measured - ideal) / 1e-3,
      static_cast<double>(periods) / measured);
  std::printf("baseline, sleep 1 ms relative to each wake-up (cisst-style), same priority: %.3f Hz\n",
              baseline_rate);
  std::printf(
      "server task: overruns %llu, missed periods %llu, wake-up latency us: min %.1f mean %.1f p99 %.1f max "
      "%.1f\n",
      static_cast<unsigned long long>(s.overruns), static_cast<unsigned long long>(s.missed_periods),
      static_cast<double>(h.min()) / 1e3, h.mean() / 1e3, static_cast<double>(h.percentile(0.99)) / 1e3,
      static_cast<double>(h.max()) / 1e3);
  return sink == 12345.678 ? 1 : 0;
}
