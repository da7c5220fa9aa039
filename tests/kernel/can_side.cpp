// saw-kernel-can-side: our end of a SocketCAN bus in the PREEMPT_RT guest's checks
// (tests/kernel/can_peers.py), written only against the public saw/can/bus.hpp API. The peers
// (can-utils, python-can) are the script's; this program is what sawrt does with the bus:
//
//   receive: open (with --fd, --filter), say "open" on stderr, send the --send frames, then
//            print each frame received (candump -L form) until --count frames or --timeout;
//            a last line `end state=… error_frames=… received=… sent=… refused=…`.
//   cycle:   a 1 kHz cycle as an RT task runs it (receive, then send one frame) for --seconds;
//            prints each state change with the cycle's time, and at the end the cycles run,
//            the frames refused and the longest receive()/send() call: the bus going down must
//            show as state `down` and refused frames, never as a call that blocks or spins.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <span>
#include <thread>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/candump.hpp"

namespace {

using saw::TimeNs;
using namespace saw::can;

void print_end(const Bus& bus) {
  const BusCounters c = bus.counters();
  std::printf("end state=%s error_frames=%llu received=%llu sent=%llu refused=%llu\n",
              std::string(to_string(bus.state())).c_str(), static_cast<unsigned long long>(c.error_frames),
              static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.sent),
              static_cast<unsigned long long>(c.send_refused));
  std::fflush(stdout);
}

int receive(Bus& bus, const std::vector<Frame>& to_send, std::size_t count, double timeout) {
  if (!to_send.empty() && bus.send(to_send) != to_send.size()) {
    std::fprintf(stderr, "saw-kernel-can-side: the bus refused a frame (state %s)\n",
                 std::string(to_string(bus.state())).c_str());
    print_end(bus);
    return 1;
  }
  const std::string channel = bus.name().substr(bus.name().find(':') + 1);
  const TimeNs to_wall = wall_clock_offset();
  const TimeNs deadline = saw::monotonic_now() + static_cast<TimeNs>(timeout * 1e9);
  std::vector<Received> batch(64);
  std::size_t seen = 0;
  while (seen < count && saw::monotonic_now() < deadline) {
    const std::size_t n = bus.receive(batch);
    for (std::size_t i = 0; i < n && seen < count; ++i, ++seen)
      std::printf("%s\n", format_log_line(batch[i].time + to_wall, channel, batch[i].frame).c_str());
    if (n == 0) {
      std::fflush(stdout);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  print_end(bus);
  return seen < count ? 1 : 0;
}

int cycle(Bus& bus, double seconds) {
  const Frame beat = classic(0x7f0, std::vector<std::uint8_t>{0xbe, 0xa7});
  std::vector<Received> batch(64);
  const TimeNs start = saw::monotonic_now();
  const TimeNs end = start + static_cast<TimeNs>(seconds * 1e9);
  TimeNs next = start, longest = 0;
  std::uint64_t cycles = 0, refused = 0;
  BusState last = bus.state();
  std::printf("state %s at 0 ms\n", std::string(to_string(last)).c_str());
  while (next < end) {
    next += 1'000'000;
    const timespec ts{static_cast<time_t>(next / 1'000'000'000), static_cast<long>(next % 1'000'000'000)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const TimeNs t0 = saw::monotonic_now();
    (void)bus.receive(batch);
    if (bus.send(std::span<const Frame>(&beat, 1)) == 0) ++refused;
    longest = std::max(longest, saw::monotonic_now() - t0);
    ++cycles;
    if (const BusState s = bus.state(); s != last) {
      std::printf("state %s at %lld ms\n", std::string(to_string(s)).c_str(),
                  static_cast<long long>((t0 - start) / 1'000'000));
      std::fflush(stdout);
      last = s;
    }
  }
  std::printf("cycles=%llu refused_in_cycle=%llu longest_call_us=%lld\n",
              static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(refused),
              static_cast<long long>(longest / 1000));
  print_end(bus);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-kernel-can-side: our end of a SocketCAN bus for the PREEMPT_RT guest's checks"};
  app.require_subcommand(1);
  std::string uri;
  bool fd = false;
  std::vector<std::string> filters, sends;
  std::size_t count = 0;
  double timeout = 5, seconds = 3;
  app.add_option("bus", uri, "socketcan:<ifname> (or virtual:<name>)")->required();
  app.add_flag("--fd", fd, "CAN FD frames too");
  app.add_option("--filter", filters, "ID:MASK, as candump's (repeatable)");
  auto* rx = app.add_subcommand("receive", "send --send frames, then print frames received");
  rx->add_option("--send", sends, "a frame in cansend's form (repeatable)");
  rx->add_option("--count", count, "frames to receive")->required();
  rx->add_option("--timeout", timeout, "seconds");
  auto* cy = app.add_subcommand("cycle", "a 1 kHz receive/send cycle; state changes as they happen");
  cy->add_option("--seconds", seconds, "how long");
  CLI11_PARSE(app, argc, argv);

  BusConfig config;
  config.uri = uri;
  config.fd = fd;
  for (const auto& f : filters) {
    const auto colon = f.find(':');
    if (colon == std::string::npos) {
      std::fprintf(stderr, "saw-kernel-can-side: --filter %s: not ID:MASK\n", f.c_str());
      return 2;
    }
    config.filters.push_back({static_cast<std::uint32_t>(std::stoul(f.substr(0, colon), nullptr, 16)),
                              static_cast<std::uint32_t>(std::stoul(f.substr(colon + 1), nullptr, 16))});
  }
  std::vector<Frame> frames;
  for (const auto& s : sends) {
    std::string error;
    const auto f = parse_frame(s, &error);
    if (!f) {
      std::fprintf(stderr, "saw-kernel-can-side: --send %s: %s\n", s.c_str(), error.c_str());
      return 2;
    }
    frames.push_back(*f);
  }
  std::unique_ptr<Bus> bus;
  try {
    bus = open_bus(config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-kernel-can-side: %s\n", e.what());
    return 2;
  }
  // The script waits for this line before its peers send: frames sent earlier are not ours.
  std::fprintf(stderr, "open %s\n", uri.c_str());
  std::fflush(stderr);
  if (rx->parsed()) return receive(*bus, frames, count, timeout);
  return cycle(*bus, seconds);
}
