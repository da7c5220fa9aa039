#include "saw/canopen/node_monitor.hpp"

#include "saw/log.hpp"

namespace saw::canopen {

NodeMonitor::NodeMonitor(const NodeDriver& nodes, const char* source, std::vector<const char*> names)
    : driver_(nodes), source_(source) {
  nodes_.resize(nodes.size());
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    nodes_[i].name = i < names.size() ? names[i] : nullptr;
    nodes_[i].id = nodes.node_id(i);
  }
}

// Each line in two literal forms (the log keeps the format's pointer): with the node's name
// first, or the node alone.
template <class... Args>
void NodeMonitor::say(LogLevel level, std::size_t i, const char* named, const char* plain,
                      Args... args) const noexcept {
  const Node& n = nodes_[i];
  if (n.name != nullptr)
    saw::log(level, source_, named, n.name, n.id, args...);
  else
    saw::log(level, source_, plain, n.id, args...);
}

void NodeMonitor::look(std::size_t i, bool enabling) noexcept {
  Node& n = nodes_[i];
  const AxisHealth& h = driver_.health(i);
  if (h.boot_ups == n.boot_ups_seen) return;
  n.boot_ups_seen = h.boot_ups;
  n.rebooted = true;
  n.reconfiguring = false;  // a configuration under way starts over: the node lost what it had
  if (enabling)
    say(LogLevel::warning, i, "{} (node {}) rebooted (boot-up seen) during the enable: configuring it again",
        "node {} rebooted (boot-up seen) during the enable: configuring it again");
}

void NodeMonitor::say_rebooted(std::size_t i) const noexcept {
  say(LogLevel::error, i, "{} (node {}) rebooted (boot-up seen): its configuration is gone",
      "node {} rebooted (boot-up seen): its configuration is gone");
}

bool NodeMonitor::left_operational(std::size_t i, bool says) const noexcept {
  const AxisHealth& h = driver_.health(i);
  if (!h.heartbeat_seen || h.nmt_state == NmtState::operational || h.nmt_state == NmtState::initialising)
    return false;
  if (says)
    say(LogLevel::error, i, "{} (node {}) left operational: its heartbeat says {}",
        "node {} left operational: its heartbeat says {}", to_string(h.nmt_state).data());
  return true;
}

NodeMonitor::Step NodeMonitor::reconfigure(NodeDriver& driver, std::size_t i, TimeNs now) noexcept {
  Node& n = nodes_[i];
  if (!n.rebooted) return Step::not_rebooted;
  if (!n.reconfiguring) {
    driver.reconfigure(i, now);
    n.reconfiguring = true;
  }
  const Reconfiguration& r = driver.reconfiguration(i);
  switch (r.state) {
    case Reconfiguration::State::idle:
    case Reconfiguration::State::busy:
      return Step::busy;
    case Reconfiguration::State::done:
      n.rebooted = n.reconfiguring = false;
      say(LogLevel::info, i, "{} (node {}) configured again after its reboot",
          "node {} configured again after its reboot");
      return Step::done;
    case Reconfiguration::State::failed:
      n.reconfiguring = false;  // the next enable tries again
      say(LogLevel::error, i, "{} (node {}): configuring it again failed at {:x}:{}: {}",
          "node {}: configuring it again failed at {:x}:{}: {}", unsigned{r.object.index},
          unsigned{r.object.subindex},
          r.object.index == 0 ? "no operational heartbeat" : to_string(r.abort).data());
      return Step::failed;
  }
  return Step::busy;
}

}  // namespace saw::canopen
