// The node health rules a CANopen device applies to the nodes of its node driver, written once: a
// boot-up, a node that left NMT operational, and the re-configuration an enable runs for a node
// that rebooted, each with its log line.
#pragma once

#include <cstdint>
#include <vector>

#include "saw/canopen/node_driver.hpp"
#include "saw/clock.hpp"
#include "saw/log.hpp"

namespace saw::canopen {

// A node that rebooted lost its PDO maps, heartbeats and mode: it is `rebooted` until an enable
// configures it again (a FAULT otherwise, which the device raises). RT after construction:
// nothing allocates, locks or throws.
class NodeMonitor {
 public:
  // `source`: the log's source (the component's name); `names[i]`: node i's name in its log
  // lines ("elbow (node 3) ..."), or nullptr ("node 3 ..."). The pointers are kept: the log keeps
  // them until it is drained.
  NodeMonitor(const NodeDriver& nodes, const char* source, std::vector<const char*> names);

  // A boot-up of node i since the last look: rebooted from now on. During an enable no FAULT
  // says it (the enable configures the node again and goes on): the log does.
  void look(std::size_t i, bool enabling) noexcept;
  bool rebooted(std::size_t i) const noexcept { return nodes_[i].rebooted; }
  // The log line of a rebooted node's FAULT.
  void say_rebooted(std::size_t i) const noexcept;
  // Node i's heartbeat says it left operational (its own error behaviour, another master's NMT
  // command): it takes no PDOs. Logged when `says`.
  bool left_operational(std::size_t i, bool says) const noexcept;

  // The enable's step for node i: its configuration run again through `driver` if it rebooted.
  enum class Step : std::uint8_t { not_rebooted, busy, done, failed };
  // done: configured again this cycle; failed: driver.reconfiguration(i) says where (both logged;
  // after a failure the next enable tries again).
  Step reconfigure(NodeDriver& driver, std::size_t i, TimeNs now) noexcept;

 private:
  struct Node {
    const char* name = nullptr;
    unsigned id = 0;
    std::uint32_t boot_ups_seen = 0;
    bool rebooted = false;
    bool reconfiguring = false;  // this enable re-runs its configuration
  };
  template <class... Args>
  void say(LogLevel level, std::size_t i, const char* named, const char* plain, Args... args) const noexcept;

  const NodeDriver& driver_;
  const char* source_;
  std::vector<Node> nodes_;
};

}  // namespace saw::canopen
