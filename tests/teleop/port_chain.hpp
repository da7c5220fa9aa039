// PortChain: a device, its passivity port, an optional simulated link, and a far side that
// requires "arm", on the stepped clock.
#pragma once

#include <chrono>
#include <optional>

#include "saw/manager.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/teleop/passivity_port.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/stepper.hpp"

template <class Far>
struct PortChain {
  explicit PortChain(saw::teleop::PortConfig port_config = {},
                     std::optional<saw::teleop::DelayConfig> link_config = std::nullopt)
      : port("port", period(), port_config) {
    manager.add(device);
    manager.add(port);
    if (link_config) {
      link.emplace("link", period(), *link_config);
      manager.add(*link);
    }
    manager.add(far);
    manager.connect("port", "device", "device", "arm");
    if (link) manager.connect("link", "source", "port", "arm");
    manager.connect(far.name(), "arm", link ? "link" : "port", "arm");
    manager.start_stepped();
  }
  // n periods; a device that does not publish is one that stopped.
  void step(int n = 1, bool publish = true) {
    for (int i = 0; i < n; ++i) publish ? stepper({&device}) : stepper({});
  }
  static saw::TaskConfig period() { return saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0); }

  saw::testing::FakeDevice device{"device"};
  saw::teleop::PassivityPort port;
  std::optional<saw::teleop::DelayTask> link;
  Far far;
  saw::Manager manager;
  saw::testing::Stepper stepper{manager};
};
