// saw-candump: prints the frames on a sawrt CAN bus in candump -L's format.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <thread>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/candump.hpp"

namespace {
std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "saw-candump: print the frames on a CAN bus (virtual:<name> or socketcan:<ifname>) as candump -L does"};
  std::string uri;
  std::uint64_t count = 0;
  double timeout = 0;
  bool classic = false;
  app.add_option("bus", uri, "virtual:<name> or socketcan:<ifname>")->required();
  app.add_option("-n,--count", count, "exit after this many frames (0: never)");
  app.add_option("--timeout", timeout,
                 "exit after this many seconds (0: never); status 1 if -n was not reached")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--classic", classic, "do not receive CAN FD frames");
  CLI11_PARSE(app, argc, argv);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  saw::can::BusConfig config;
  config.uri = uri;
  config.fd = !classic;
  std::unique_ptr<saw::can::Bus> bus;
  try {
    bus = saw::can::open_bus(config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-candump: %s\n", e.what());
    return 2;
  }
  const std::string channel = uri.substr(uri.find(':') + 1);
  // On stderr, so that a script can wait for it before it sends: frames sent earlier are not seen.
  std::fprintf(stderr, "saw-candump: listening on %s\n", uri.c_str());
  std::fflush(stderr);
  const saw::TimeNs to_wall = saw::can::wall_clock_offset();
  const saw::TimeNs deadline =
      timeout > 0 ? saw::monotonic_now() + static_cast<saw::TimeNs>(timeout * 1e9) : INT64_MAX;
  std::vector<saw::can::Received> batch(64);
  std::uint64_t seen = 0;
  while (!stop_requested.load(std::memory_order_relaxed) && (count == 0 || seen < count)) {
    if (saw::monotonic_now() > deadline) break;
    const std::size_t n = bus->receive(batch);
    for (std::size_t i = 0; i < n && (count == 0 || seen < count); ++i, ++seen)
      std::printf("%s\n",
                  saw::can::format_log_line(batch[i].time + to_wall, channel, batch[i].frame).c_str());
    if (n == 0) {
      std::fflush(stdout);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  std::fflush(stdout);
  const auto c = bus->counters();
  if (c.overruns > 0 || c.malformed > 0)
    std::fprintf(stderr, "saw-candump: %llu frames lost (overrun), %llu malformed dropped\n",
                 static_cast<unsigned long long>(c.overruns), static_cast<unsigned long long>(c.malformed));
  return count > 0 && seen < count ? 1 : 0;
}
