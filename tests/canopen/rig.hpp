// A bus master and in-process drives on one in-memory network, stepped together by the test.
#pragma once

#include <initializer_list>
#include <memory>
#include <vector>

#include "ring_bus.hpp"
#include "saw/canopen/axis.hpp"
#include "saw/canopen/pdo_text.hpp"
#include "saw/canopen/startup.hpp"
#include "test_drive.hpp"

namespace saw::canopen::test {

inline constexpr TimeNs ms = 1'000'000;

// A rotary axis of 4096 counts per motor turn through a 1:1 gear, 0.5 N·m rated, default PDOs.
inline AxisConfig test_axis(std::uint8_t node, cia402::Mode mode, std::string name = {}) {
  AxisConfig a;
  a.name = name.empty() ? "j" + std::to_string(node) : std::move(name);
  a.node = node;
  a.mode = mode;
  a.units = DriveUnits::rotary(4096, 1, 0.5);
  a.pdos = default_pdo_mappings(mode, node);
  a.heartbeat_period = 10 * ms;
  a.heartbeat_timeout = 30 * ms;
  return a;
}

// The drives answering on `network`, stepped after each master cycle.
struct Drives {
  Drives(RingNetwork& network, const std::vector<AxisConfig>& axes, TestDriveConfig base = {}) {
    for (const AxisConfig& a : axes) {
      TestDriveConfig c = base;
      c.node = a.node;
      list.push_back(std::make_unique<TestDrive>(network, c));
    }
  }
  // Drives at these node-IDs besides those already there.
  void add(RingNetwork& network, std::initializer_list<int> nodes, TestDriveConfig base = {}) {
    for (const int n : nodes) {
      base.node = static_cast<std::uint8_t>(n);
      list.push_back(std::make_unique<TestDrive>(network, base));
    }
  }
  void step(TimeNs now) {
    for (auto& d : list) d->step(now);
  }
  TestDrive& operator[](std::size_t i) { return *list[i]; }
  std::vector<std::unique_ptr<TestDrive>> list;
};

// Runs the start-up on `port` with the drives stepped between its steps, 1 ms apart.
inline void start_up(RingPort& port, const std::vector<AxisConfig>& axes, Drives& drives, TimeNs& now,
                     StartupConfig config = {}) {
  StartupSequence sequence(port, axes, config);
  run_startup(sequence, [&] {
    drives.step(now);
    now += ms;
    port.now = now;
    return now;
  });
}

}  // namespace saw::canopen::test
