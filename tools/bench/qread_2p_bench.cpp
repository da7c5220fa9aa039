// saw-bench-2p: the paper's "Local 2P": a qualified read of a double from another process on
// this host through the shared-memory bridge (10,000 calls × 5), and a bare futex ping-pong
// between two processes in the same run as the floor for a sleeping waiter.
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <thread>

#include "ping_pong.hpp"
#include "saw/bridge/exporter.hpp"
#include "saw/bridge/futex.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/manager.hpp"
#include "saw/rt_thread.hpp"
#include "stats.hpp"

namespace {

using namespace std::chrono_literals;

class Server : public saw::Task {
 public:
  explicit Server(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    provide("bench").add_command_qualified_read<double, double>(
        "add_one", [](const double& q, double& r) { r = q + 1; });
  }
};

class Caller : public saw::Component {
 public:
  Caller() : Component("caller") { require("bench").add_function("add_one", add_one); }
  saw::FunctionQualifiedRead<double, double> add_one;
};

[[noreturn]] void serve(const std::string& name, int cpu) {
  if (cpu >= 0) (void)saw::rt::set_affinity(cpu);
  Server s(name);
  saw::bridge::Exporter exporter(s, "bench");
  saw::Manager m;
  m.add(s);
  m.start();
  pause();  // until the parent kills us
  std::_Exit(0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-bench-2p: the paper's Local 2P qualified read over the shared-memory bridge"};
  int n = 10000, reps = 5;
  bool markdown = false;
  app.add_option("--calls", n, "calls per repetition");
  app.add_option("--reps", reps, "repetitions");
  app.add_flag("--markdown", markdown, "Markdown table");
  CLI11_PARSE(app, argc, argv);
  saw::rt::DmaLatencyHold dma;  // as saw-rt holds it while running
  const std::string name = "bench2p" + std::to_string(getpid());
  const pid_t server = fork();
  if (server == 0) serve(name, 1);
  (void)saw::rt::set_affinity(0);
  Caller caller;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(caller);
  for (int attempt = 0;; ++attempt) {
    try {
      m.connect("caller", "bench", name, "bench");
      break;
    } catch (const saw::ConnectError&) {
      if (attempt > 500) throw;
      std::this_thread::sleep_for(10ms);
    }
  }
  std::printf("# saw-bench-2p: %d × %d calls, caller on CPU 0, server process on CPU 1%s\n", reps, n,
              dma.error().empty() ? ", cpu_dma_latency held at 0" : "");
  std::vector<std::int64_t> qread, futex;
  std::uint64_t failed = 0;
  double x = 0;
  for (int r = 0; r < reps; ++r) {
    for (int i = 0; i < n; ++i) {
      const auto t0 = saw::monotonic_now();
      double out = 0;
      if (caller.add_one(x, out) != saw::Status::ok) ++failed;
      qread.push_back(saw::monotonic_now() - t0);
      x = out * 0.5;
    }
    auto f = saw::bench::futex_ping_pong(n, 1);
    futex.insert(futex.end(), f.begin(), f.end());
  }
  kill(server, SIGKILL);
  waitpid(server, nullptr, 0);
  saw::bench::print_header(markdown);
  saw::bench::print_row(markdown, "qualified read<double>, Local 2P (bridge)", saw::bench::summarize(qread));
  saw::bench::print_row(markdown, "bare futex ping-pong (round trip)", saw::bench::summarize(futex));
  std::printf("\nfailed calls: %llu\n", static_cast<unsigned long long>(failed));
  return failed == 0 ? 0 : 1;
}
