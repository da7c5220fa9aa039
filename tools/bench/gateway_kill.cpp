// saw-gateway-kill: does a 1 kHz task keep its rate when its gateway dies? A SCHED_FIFO task
// exported through the bridge with a real saw-gateway process attached, in rounds of two
// windows side by side: the gateway running throughout (baseline), then the gateway killed with
// SIGKILL half-way (the rest of the window runs without it). Each round starts a new gateway,
// which must attach to the same, still-running segment. Prints cycles, overruns and wake-up
// latency per window kind; figures, not assertions.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/latency_histogram.hpp"
#include "saw/manager.hpp"
#include "saw/testing/dds_domain.hpp"

namespace {

using namespace std::chrono_literals;
enum Window { baseline = 0, killed = 1, setup = 2 };

// The task: a count for the gateway to publish; each cycle's wake-up latency and overruns are
// booked to the window the main thread has set (atomics only: this is the RT path).
class Probe : public saw::Task {
 public:
  Probe(std::string name, int priority, int cpu)
      : Task(std::move(name), saw::TaskConfig::periodic(1ms, priority, cpu)) {
    provide("arm").add_command_read("count", state_table().add_column("count", &count_));
  }
  void run() override {
    ++count_;
    const int w = window.load(std::memory_order_relaxed);
    hist[w].record(statistics().last_wakeup_latency);
    const auto o = statistics().overruns;
    if (o != seen_overruns_) {
      overruns[w].fetch_add(o - seen_overruns_, std::memory_order_relaxed);
      seen_overruns_ = o;
    }
  }
  std::atomic<int> window{setup};
  std::array<saw::LatencyHistogram, 3> hist;  // 1 µs bins to 1 ms; the maximum is kept beyond
  std::array<std::atomic<std::uint64_t>, 3> overruns{};

 private:
  std::int64_t count_ = 0;
  std::uint64_t seen_overruns_ = 0;
};

// Starts saw-gateway --attach name; returns its pid once it has printed that it is attached
// (-1 if it did not within 10 s).
pid_t start_gateway(const std::string& exe, const std::string& name, int domain) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    const std::string d = std::to_string(domain);
    execl(exe.c_str(), exe.c_str(), "--attach", name.c_str(), "--wait", "5", "--domain", d.c_str(),
          static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  close(fds[1]);
  std::string line;
  char ch;
  bool attached = false;
  while (read(fds[0], &ch, 1) == 1) {
    if (ch != '\n') {
      line.push_back(ch);
      continue;
    }
    if (line.rfind("saw-gateway ", 0) == 0) {
      attached = true;
      break;
    }
    line.clear();
  }
  close(fds[0]);  // the gateway's later output goes nowhere (SIGPIPE is ignored below)
  if (attached) return pid;
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-gateway-kill: a 1 kHz task beside its gateway's kill -9, against a baseline"};
  int rounds = 10, priority = 80, cpu = 1;
  double window_s = 2.0;
  app.add_option("--rounds", rounds, "baseline + kill windows")->check(CLI::PositiveNumber);
  app.add_option("--window", window_s, "seconds per window")->check(CLI::PositiveNumber);
  app.add_option("--priority", priority, "SCHED_FIFO priority of the task")->check(CLI::Range(1, 99));
  app.add_option("--cpu", cpu, "CPU of the task");
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGPIPE, SIG_IGN);
  const auto exe = std::filesystem::canonical("/proc/self/exe").parent_path() / "../../bin/saw-gateway";
  if (!std::filesystem::exists(exe)) {
    std::fprintf(stderr, "saw-gateway-kill: %s not found (build the saw-gateway target)\n", exe.c_str());
    return 2;
  }
  const std::string name = "gwkill" + std::to_string(getpid());
  const saw::testing::DdsDomain claim;  // a DDS domain no test or benchmark beside this run holds
  const int domain = claim.id();
  Probe probe(name, priority, cpu);
  saw::bridge::Exporter exporter(probe, "arm");
  saw::Manager m;
  m.add(probe);
  m.start();
  const auto half = std::chrono::duration<double>(window_s / 2);
  int attached = 0;
  for (int r = 0; r < rounds; ++r) {
    probe.window.store(setup);
    const pid_t g = start_gateway(exe.string(), name, domain);
    if (g < 0) continue;
    ++attached;
    std::this_thread::sleep_for(200ms);  // its first samples out
    probe.window.store(baseline);
    std::this_thread::sleep_for(2 * half);
    probe.window.store(killed);
    std::this_thread::sleep_for(half);
    kill(g, SIGKILL);
    waitpid(g, nullptr, 0);
    std::this_thread::sleep_for(half);
  }
  probe.window.store(setup);
  m.stop();
  std::printf(
      "# saw-gateway-kill: %d rounds of %.1f s windows; task 1 kHz SCHED_FIFO %d on CPU %d; "
      "saw-gateway attached %d of %d times (each a new process on the running segment)\n\n",
      rounds, window_s, priority, cpu, attached, rounds);
  std::printf(
      "| window | cycles | overruns | wake-up p99 µs | p99.9 µs | max µs |\n|---|---|---|---|---|---|\n");
  const char* names[] = {"gateway running (baseline)", "gateway killed half-way"};
  for (int w : {baseline, killed}) {
    const auto& h = probe.hist[static_cast<std::size_t>(w)];
    std::printf("| %s | %llu | %llu | %.0f | %.0f | %.0f |\n", names[w],
                static_cast<unsigned long long>(h.total()),
                static_cast<unsigned long long>(probe.overruns[static_cast<std::size_t>(w)].load()),
                static_cast<double>(h.percentile(0.99)) / 1e3, static_cast<double>(h.percentile(0.999)) / 1e3,
                static_cast<double>(h.max()) / 1e3);
  }
  std::printf(
      "\nexporter: %llu events refused (rings of killed gateways, until their slots were reclaimed)\n",
      static_cast<unsigned long long>(exporter.events_refused()));
  return attached == rounds ? 0 : 1;
}
