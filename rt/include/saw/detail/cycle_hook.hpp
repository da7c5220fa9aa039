// CycleHook: code run at the end of every cycle of a component, after its state row (internal).
#pragma once

#include "saw/clock.hpp"

namespace saw {
class Component;
}

namespace saw::detail {

// The bridge's exporter publishes state and takes remote commands here, in the component's
// thread. Added before start (Access::add_cycle_hook); each must be RT-safe.
struct CycleHook {
  virtual ~CycleHook() = default;
  virtual void after_cycle(Component& c, TimeNs time) noexcept = 0;
};

}  // namespace saw::detail
