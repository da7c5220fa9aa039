// saw-can-sim: simulated CiA 402 servo drives (CANopen slaves) on a CAN bus, stepped in real time.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/cia402.hpp"
#include "saw/canopen/sim/drive_dictionary.hpp"
#include "saw/canopen/sim/sim_config.hpp"
#include "saw/canopen/sim/sim_drive.hpp"
#include "saw/canopen/sim/sim_io_node.hpp"
#include "saw/detail/pacer.hpp"
#include "saw/rt_thread.hpp"

namespace {

using namespace saw::canopen::sim;
using saw::TimeNs;

std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }

struct Simulated {
  std::unique_ptr<saw::can::Bus> bus;  // one attachment per drive: each sees the others' frames
  std::unique_ptr<SimDrive> drive;
};

struct SimulatedIo {
  std::unique_ptr<saw::can::Bus> bus;
  std::unique_ptr<SimIoNode> node;
};

void print_summary(const std::vector<Simulated>& drives, TimeNs elapsed, std::uint64_t cycles,
                   const saw::detail::Pacer& pacer, TimeNs worst_late) {
  std::printf(
      "saw-can-sim: %.3f s, %llu cycles, %llu overruns (%llu periods missed), latest wake-up %.1f us\n",
      static_cast<double>(elapsed) * 1e-9, static_cast<unsigned long long>(cycles),
      static_cast<unsigned long long>(pacer.overruns()),
      static_cast<unsigned long long>(pacer.missed_periods()), static_cast<double>(worst_late) * 1e-3);
  std::printf("%4s  %-15s  %-22s  %4s  %11s  %9s  %9s  %6s  %6s  %6s  %4s  %s\n", "node", "nmt", "cia402",
              "mode", "position", "frames in", "out", "sdo", "rpdo", "tpdo", "emcy", "lost (bus-off)");
  for (const auto& s : drives) {
    const SimDrive& d = *s.drive;
    const SimDriveCounters& c = d.counters();
    std::printf("%4u  %-15s  %-22s  %4d  %11d  %9llu  %9llu  %6llu  %6llu  %6llu  %4llu  %llu\n",
                static_cast<unsigned>(d.node()), std::string(to_string(d.nmt_state())).c_str(),
                std::string(to_string(d.drive_state())).c_str(), static_cast<int>(d.mode_display()),
                d.position_counts(), static_cast<unsigned long long>(c.frames_in),
                static_cast<unsigned long long>(c.frames_out),
                static_cast<unsigned long long>(c.sdo_requests), static_cast<unsigned long long>(c.rpdos),
                static_cast<unsigned long long>(c.tpdos), static_cast<unsigned long long>(c.emcys),
                static_cast<unsigned long long>(c.lost_bus_off));
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-can-sim: simulated CiA 402 servo drives (CANopen slaves) on a sawrt CAN bus"};
  std::string bus, config_file, eds;
  std::vector<std::string> nodes;
  std::vector<std::string> injections;
  double duration = 0, period_us = 250;
  int priority = 0;
  std::optional<int> heartbeat_ms;
  MotorParameters motor;
  bool print_eds = false;
  app.add_option("--bus", bus, "virtual:<name> or socketcan:<ifname> (overrides the config file's)");
  app.add_option("--node", nodes, "a drive: <node-ID 1..127>[:<EDS or DCF>]; repeatable");
  std::vector<int> io_nodes;
  app.add_option("--io", io_nodes,
                 "a generic I/O node (CiA 401: 0x6411:01 output, 0x6401:01 input following it, a "
                 "gripper's controller): its node-ID; repeatable")
      ->check(CLI::Range(1, 127));
  app.add_option("--config", config_file,
                 "YAML: bus, period, drives (node, eds, heartbeat_ms, motor), faults");
  app.add_option("--eds", eds,
                 "EDS/DCF of the --node drives that name none (default: the built-in sim_drive.eds)");
  app.add_option("--heartbeat-ms", heartbeat_ms,
                 "power-on producer heartbeat time 0x1017 of the --node drives")
      ->check(CLI::Range(0, 65535));
  app.add_option("--motor-inertia", motor.motor_inertia, "kg·m², the rotor")->capture_default_str();
  app.add_option("--load-inertia", motor.load_inertia, "kg·m² at the output (through 0x6091's gear)")
      ->capture_default_str();
  app.add_option("--friction", motor.viscous_friction, "viscous friction, N·m·s/rad at the motor")
      ->capture_default_str();
  app.add_option("--load-torque", motor.load_torque, "constant load, N·m at the output")
      ->capture_default_str();
  app.add_option("--period-us", period_us, "the drives' cycle in microseconds (50 .. 100000)")
      ->capture_default_str();
  app.add_option("--priority", priority, "SCHED_FIFO priority of the loop (0: normal scheduling)")
      ->check(CLI::Range(0, 99));
  app.add_option("--duration", duration, "seconds to run (0: until SIGINT/SIGTERM)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--inject", injections,
                 "<node>:<kind>:<at s>[:<duration s>]; kinds over-current, following-error, heartbeat-loss, "
                 "bus-off, sdo-abort=<index>.<sub>[/<code>]; repeatable");
  app.add_flag("--print-eds", print_eds, "print the built-in EDS (for masters to read) and exit");
  CLI11_PARSE(app, argc, argv);

  if (print_eds) {
    std::fwrite(builtin_eds().data(), 1, builtin_eds().size(), stdout);
    return 0;
  }

  SimConfig config;
  std::vector<Simulated> drives;
  std::vector<SimulatedIo> ios;
  try {
    if (!config_file.empty()) config = load_sim_config(config_file);
    if (!bus.empty()) config.bus = bus;
    if (config.bus.empty()) throw std::invalid_argument("no bus: --bus virtual:<name> or socketcan:<ifname>");
    if (app.count("--period-us") > 0 || config_file.empty())
      config.period = static_cast<TimeNs>(period_us * 1e3);
    motor.check();
    for (const std::string& text : nodes) {
      SimDriveConfig d;
      const std::size_t colon = text.find(':');
      const std::string id = text.substr(0, colon);
      const bool number =
          !id.empty() && id.size() <= 3 && id.find_first_not_of("0123456789") == std::string::npos;
      if (!number || std::stoi(id) < 1 || std::stoi(id) > 127)
        throw std::invalid_argument("--node " + text + ": expected <node-ID 1..127>[:<EDS path>]");
      d.node = static_cast<std::uint8_t>(std::stoi(id));
      d.eds = colon == std::string::npos ? eds : text.substr(colon + 1);
      d.motor = motor;
      if (heartbeat_ms) d.heartbeat_ms = static_cast<std::uint16_t>(*heartbeat_ms);
      config.drives.push_back(d);
    }
    for (const auto& text : injections) config.faults.push_back(parse_scheduled_fault(text));
    // The drives' checks, with the I/O nodes' faults set aside (over-current and heartbeat-loss
    // are theirs too).
    SimConfig drives_only = config;
    std::erase_if(drives_only.faults, [&](const ScheduledFault& f) {
      return std::find(io_nodes.begin(), io_nodes.end(), f.node) != io_nodes.end();
    });
    if (!drives_only.drives.empty() || io_nodes.empty()) check(drives_only);
    for (const int n : io_nodes)
      for (const auto& d : config.drives)
        if (d.node == n) throw std::invalid_argument("node " + std::to_string(n) + " is simulated twice");
    for (const int n : io_nodes) {
      SimulatedIo s;
      saw::can::BusConfig bus_config;
      bus_config.uri = config.bus;
      s.bus = saw::can::open_bus(bus_config);
      SimIoNodeConfig c;
      c.node = static_cast<std::uint8_t>(n);
      if (heartbeat_ms) c.heartbeat_ms = static_cast<std::uint16_t>(*heartbeat_ms);
      s.node = std::make_unique<SimIoNode>(c, *s.bus);
      ios.push_back(std::move(s));
    }
    for (const auto& d : config.drives) {
      Simulated s;
      saw::can::BusConfig bus_config;
      bus_config.uri = config.bus;
      s.bus = saw::can::open_bus(bus_config);
      s.drive = std::make_unique<SimDrive>(d, *s.bus);
      drives.push_back(std::move(s));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-can-sim: %s\n", e.what());
    return 2;
  }
  std::stable_sort(config.faults.begin(), config.faults.end(),
                   [](const ScheduledFault& a, const ScheduledFault& b) { return a.at < b.at; });

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (priority > 0) {
    // A simulator still runs without them: say so and go on.
    for (const std::string& error : {saw::rt::lock_memory(), saw::rt::set_fifo(priority)})
      if (!error.empty()) std::fprintf(stderr, "saw-can-sim: warning: %s\n", error.c_str());
    saw::rt::prefault_stack(256 * 1024);
  }

  std::string list;
  for (const auto& s : drives) list += (list.empty() ? "" : ", ") + std::to_string(s.drive->node());
  for (const auto& s : ios) list += (list.empty() ? "" : ", ") + std::to_string(s.node->node()) + " (I/O)";
  // One line on stdout once the drives are on the bus, for scripts that wait for it.
  std::printf("saw-can-sim: %zu drive%s on %s (node%s %s), %.0f us cycle\n", drives.size(),
              drives.size() == 1 ? "" : "s", config.bus.c_str(), drives.size() == 1 ? "" : "s", list.c_str(),
              static_cast<double>(config.period) * 1e-3);
  std::fflush(stdout);
  for (const auto& f : config.faults)
    std::fprintf(stderr, "saw-can-sim: scheduled: %s\n", describe(f).c_str());

  const TimeNs start = saw::monotonic_now();
  const TimeNs end = duration > 0 ? start + static_cast<TimeNs>(duration * 1e9) : 0;
  saw::detail::Pacer pacer(start, config.period);
  std::size_t next_fault = 0;
  std::uint64_t cycles = 0;
  TimeNs worst_late = 0;
  TimeNs now = start;
  while (!stop_requested.load(std::memory_order_relaxed) && (end == 0 || now < end)) {
    const timespec wake = saw::to_timespec(pacer.next_wakeup());
    if (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) == EINTR) continue;
    now = saw::monotonic_now();
    worst_late = std::max(worst_late, now - pacer.next_wakeup());
    for (; next_fault < config.faults.size() && config.faults[next_fault].at <= now - start; ++next_fault) {
      const ScheduledFault& f = config.faults[next_fault];
      for (auto& s : drives)
        if (s.drive->node() == f.node) s.drive->inject(f.fault);
      for (auto& s : ios)
        if (s.node->node() == f.node) s.node->inject(f.fault);
      std::fprintf(stderr, "saw-can-sim: %.3f s: injected %s\n", static_cast<double>(now - start) * 1e-9,
                   describe(f).c_str());
    }
    for (auto& s : drives) s.drive->step(now);
    for (auto& s : ios) s.node->step(now);
    ++cycles;
    pacer.finish_cycle(saw::monotonic_now());
  }
  print_summary(drives, saw::monotonic_now() - start, cycles, pacer, worst_late);
  for (const auto& s : ios)
    std::printf(
        "I/O node %u: %s, output %d, input %d, %llu SYNC, %llu SDO requests, %llu EMCY, %llu heartbeat "
        "events\n",
        unsigned{s.node->node()}, std::string(to_string(s.node->nmt_state())).c_str(), int{s.node->output()},
        int{s.node->input()}, static_cast<unsigned long long>(s.node->syncs()),
        static_cast<unsigned long long>(s.node->sdo_requests()),
        static_cast<unsigned long long>(s.node->emcys()),
        static_cast<unsigned long long>(s.node->heartbeat_events()));
  return 0;
}
