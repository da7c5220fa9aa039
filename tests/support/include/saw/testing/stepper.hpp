// Stepper: the stepped clock of a rig of fake devices, one 1 ms period at a time.
#pragma once

#include <initializer_list>

#include "saw/manager.hpp"
#include "saw/testing/fake_device.hpp"

namespace saw::testing {

// Steps a stepped manager by one 1 ms period, publishing the devices first unless frozen.
struct Stepper {
  Manager& manager;
  TimeNs next = 0;
  void operator()(std::initializer_list<FakeDevice*> publish) {
    for (auto* d : publish) d->publish(next);
    manager.step_until(next);
    next += 1'000'000;
  }
};

}  // namespace saw::testing
