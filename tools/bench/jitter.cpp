// saw-jitter: a sawrt periodic task at 1 kHz beside cyclictest at the same priority and CPU, for
// the same duration, idle or under load (stress-ng): both wake-up histograms in cyclictest's
// format, and the ratios of our p99, p99.9 and max to cyclictest's, with our overrun count.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "saw/manager.hpp"

extern char** environ;

namespace {

// A wake-up latency histogram in 1 µs bins, from either source.
struct Hist {
  std::vector<std::uint64_t> bins;
  std::uint64_t overflows = 0, total = 0;
  long long min_us = 0, max_us = 0;
  double avg_us = 0;
  // µs below which a fraction q of wake-ups fall (bin upper edge); max past the bins.
  double percentile(double q) const {
    const auto want = static_cast<std::uint64_t>(q * static_cast<double>(total));
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < bins.size(); ++i) {
      seen += bins[i];
      if (seen >= want && seen > 0) return static_cast<double>(i + 1);
    }
    return static_cast<double>(max_us);
  }
};

// Adds `h`'s wake-ups to `into` (same bins).
void merge(Hist& into, const Hist& h) {
  if (into.total == 0) {
    into = h;
    return;
  }
  for (std::size_t i = 0; i < into.bins.size() && i < h.bins.size(); ++i) into.bins[i] += h.bins[i];
  const double n = static_cast<double>(into.total), m = static_cast<double>(h.total);
  if (n + m > 0) into.avg_us = (into.avg_us * n + h.avg_us * m) / (n + m);
  into.total += h.total;
  into.overflows += h.overflows;
  into.min_us = std::min(into.min_us, h.min_us);
  into.max_us = std::max(into.max_us, h.max_us);
}

// In cyclictest's -h format.
void write_histogram(const std::string& path, const Hist& h) {
  std::ofstream f(path);
  f << "# Histogram\n";
  for (std::size_t i = 0; i < h.bins.size(); ++i) {
    char b[64];
    std::snprintf(b, sizeof b, "%06zu %06llu\n", i, static_cast<unsigned long long>(h.bins[i]));
    f << b;
  }
  f << "# Total: " << h.total << "\n# Min Latencies: " << h.min_us
    << "\n# Avg Latencies: " << static_cast<long long>(h.avg_us) << "\n# Max Latencies: " << h.max_us
    << "\n# Histogram Overflows: " << h.overflows << "\n";
}

Hist from(const saw::LatencyHistogram& h) {
  Hist r;
  for (std::size_t i = 0; i < h.bins(); ++i) r.bins.push_back(h.count(i));
  r.overflows = h.overflows();
  r.total = h.total();
  r.min_us = h.min() / 1000;
  r.max_us = h.max() / 1000;
  r.avg_us = h.mean() / 1000;
  return r;
}

// cyclictest's -h output: "NNNNNN count" rows, then "# Max Latencies: X" etc.
Hist parse_cyclictest(const std::string& text, std::size_t bins) {
  Hist r;
  r.bins.assign(bins, 0);
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    unsigned long long a = 0, b = 0;
    if (line.size() > 7 && line[0] != '#' && std::sscanf(line.c_str(), "%llu %llu", &a, &b) == 2 &&
        a < bins) {
      r.bins[a] = b;
    } else if (std::sscanf(line.c_str(), "# Total: %llu", &a) == 1) {
      r.total = a;
    } else if (std::sscanf(line.c_str(), "# Min Latencies: %llu", &a) == 1) {
      r.min_us = static_cast<long long>(a);
    } else if (std::sscanf(line.c_str(), "# Avg Latencies: %llu", &a) == 1) {
      r.avg_us = static_cast<double>(a);
    } else if (std::sscanf(line.c_str(), "# Max Latencies: %llu", &a) == 1) {
      r.max_us = static_cast<long long>(a);
    } else if (std::sscanf(line.c_str(), "# Histogram Overflows: %llu", &a) == 1) {
      r.overflows = a;
    }
  }
  if (r.total == 0)
    for (auto c : r.bins) r.total += c;
  return r;
}

pid_t spawn(std::vector<std::string> args, const std::string& out_file = "") {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (!out_file.empty())
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  if (posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

class Idle : public saw::Task {
 public:
  Idle(int priority, int cpu)
      : Task("jitter", saw::TaskConfig::periodic(std::chrono::milliseconds(1), priority, cpu)) {}
  void run() override {}
};

struct Run {
  Hist saw, cyclic;
  std::uint64_t overruns = 0, cycles = 0;
};

// sawrt and cyclictest in turn, `chunks` times each (seconds in all for each), so that a slow
// stretch of the machine falls on both alike; the histograms are summed.
Run run_both(double seconds, int chunks, int priority, int cpu, std::size_t bins, const std::string& dir,
             const std::string& tag) {
  Run r;
  const double part = seconds / chunks;
  const std::string out = dir + "/cyclictest-" + tag + ".txt";
  for (int k = 0; k < chunks; ++k) {
    {
      Idle task(priority, cpu);
      saw::Manager m;
      m.add(task);
      m.start();
      std::this_thread::sleep_for(std::chrono::duration<double>(part));
      m.stop();
      merge(r.saw, from(task.wakeup_histogram()));
      r.overruns += task.statistics().overruns;
      r.cycles += task.statistics().cycles;
    }
    const pid_t c = spawn(
        {"cyclictest", "-m", "-q", "-p", std::to_string(priority), "-a", std::to_string(cpu), "-i", "1000",
         "-l", std::to_string(static_cast<long long>(part * 1000)), "-h", std::to_string(bins), "-t", "1"},
        out);
    if (c > 0) waitpid(c, nullptr, 0);
    std::ifstream in(out);
    std::stringstream ss;
    ss << in.rdbuf();
    merge(r.cyclic, parse_cyclictest(ss.str(), bins));
  }
  // Both summed, in cyclictest's format, for the same tools (and tools/plot_jitter.py).
  write_histogram(out, r.cyclic);
  write_histogram(dir + "/saw-" + tag + ".txt", r.saw);
  return r;
}

void print(bool markdown, const std::string& label, const Run& r) {
  const double p99 = r.saw.percentile(0.99), c99 = r.cyclic.percentile(0.99);
  const double p999 = r.saw.percentile(0.999), c999 = r.cyclic.percentile(0.999);
  if (markdown) {
    std::printf("| %s | sawrt | %llu | %.1f | %.0f | %.0f | %lld | %llu |\n", label.c_str(),
                static_cast<unsigned long long>(r.saw.total), r.saw.avg_us, p99, p999, r.saw.max_us,
                static_cast<unsigned long long>(r.overruns));
    std::printf("| %s | cyclictest | %llu | %.1f | %.0f | %.0f | %lld | – |\n", label.c_str(),
                static_cast<unsigned long long>(r.cyclic.total), r.cyclic.avg_us, c99, c999, r.cyclic.max_us);
  } else {
    std::printf("%-6s sawrt       n=%llu avg %.1f p99 %.0f p99.9 %.0f max %lld us, %llu overruns\n",
                label.c_str(), static_cast<unsigned long long>(r.saw.total), r.saw.avg_us, p99, p999,
                r.saw.max_us, static_cast<unsigned long long>(r.overruns));
    std::printf("%-6s cyclictest  n=%llu avg %.1f p99 %.0f p99.9 %.0f max %lld us\n", label.c_str(),
                static_cast<unsigned long long>(r.cyclic.total), r.cyclic.avg_us, c99, c999, r.cyclic.max_us);
  }
}

void print_ratios(const std::string& label, const Run& r) {
  const auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
  const double p99 = ratio(r.saw.percentile(0.99), r.cyclic.percentile(0.99));
  std::printf(
      "%s ratios sawrt/cyclictest: p99 %.2f (goal ≤ 1.2: %s), p99.9 %.2f, max %.2f; sawrt overruns %llu in "
      "%llu cycles\n\n",
      label.c_str(), p99, p99 <= 1.2 ? "met" : "missed",
      ratio(r.saw.percentile(0.999), r.cyclic.percentile(0.999)),
      ratio(static_cast<double>(r.saw.max_us), static_cast<double>(r.cyclic.max_us)),
      static_cast<unsigned long long>(r.overruns), static_cast<unsigned long long>(r.cycles));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-jitter: a sawrt 1 kHz task beside cyclictest, same priority, CPU and duration"};
  double seconds = 60;
  int priority = 80, cpu = 1;
  bool load = false, markdown = false;
  std::string dir = "build/jitter";
  app.add_option("--duration", seconds, "seconds per run (each of sawrt and cyclictest)")
      ->check(CLI::PositiveNumber);
  app.add_option("--priority", priority, "SCHED_FIFO priority of both")->check(CLI::Range(1, 99));
  app.add_option("--cpu", cpu, "CPU both run on");
  app.add_flag("--load", load, "also run under load: stress-ng --cpu 2 --vm 1 (must be installed)");
  int chunks = 6;
  app.add_option("--chunks", chunks, "alternate sawrt and cyclictest this many times per condition")
      ->check(CLI::PositiveNumber);
  app.add_option("--out", dir, "directory for the histograms (cyclictest format)");
  app.add_flag("--markdown", markdown, "Markdown table");
  CLI11_PARSE(app, argc, argv);
  std::filesystem::create_directories(dir);
  constexpr std::size_t bins = 2000;
  if (markdown)
    std::printf(
        "| load | who | wake-ups | avg µs | p99 µs | p99.9 µs | max µs | overruns "
        "|\n|---|---|---|---|---|---|---|---|\n");
  const Run idle = run_both(seconds, chunks, priority, cpu, bins, dir, "idle");
  print(markdown, "idle", idle);
  Run loaded;
  if (load) {
    const pid_t stress = spawn({"stress-ng", "--cpu", "2", "--vm", "1", "--vm-bytes", "256M", "--timeout",
                                std::to_string(static_cast<int>(2 * seconds + 10)) + "s"});
    if (stress <= 0) {
      std::fprintf(stderr, "saw-jitter: stress-ng could not be started (apt install stress-ng)\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
    loaded = run_both(seconds, chunks, priority, cpu, bins, dir, "load");
    kill(stress, SIGTERM);
    waitpid(stress, nullptr, 0);
    print(markdown, "load", loaded);
  }
  std::printf("\n");
  print_ratios("idle", idle);
  if (load) print_ratios("load", loaded);
  std::printf("histograms (cyclictest format): %s/{saw,cyclictest}-*.txt\n", dir.c_str());
  return 0;
}
