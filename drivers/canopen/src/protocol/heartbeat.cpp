#include "saw/canopen/heartbeat.hpp"

#include <stdexcept>
#include <string>

#include "saw/canopen/cob.hpp"

namespace saw::canopen {

std::optional<can::Frame> HeartbeatProducer::poll(TimeNs now, NmtState state) noexcept {
  if (period_ <= 0 || now < next_) return std::nullopt;
  next_ += period_;
  if (next_ <= now) next_ = now + period_;
  return heartbeat_frame(node_, state);
}

std::string_view to_string(HeartbeatEvent::Kind k) noexcept {
  switch (k) {
    case HeartbeatEvent::Kind::appeared:
      return "appeared";
    case HeartbeatEvent::Kind::lost:
      return "lost";
    case HeartbeatEvent::Kind::back:
      return "back";
    case HeartbeatEvent::Kind::boot_up:
      return "boot-up";
    case HeartbeatEvent::Kind::state_changed:
      return "state changed";
  }
  return "unknown";
}

void HeartbeatConsumer::watch(std::uint8_t node, TimeNs consumer_time) {
  if (!valid_node_id(node))
    throw std::invalid_argument("heartbeat consumer: node-ID " + std::to_string(node) + " is not 1..127");
  if (consumer_time <= 0)
    throw std::invalid_argument("heartbeat consumer: node " + std::to_string(node) +
                                ": consumer time must be above 0");
  nodes_[node] = NodeHeartbeat{};
  nodes_[node].consumer_time = consumer_time;
}

void HeartbeatConsumer::push(const HeartbeatEvent& e) noexcept {
  if (count_ == events_.size()) {
    ++dropped_;
    return;
  }
  events_[(head_ + count_) % events_.size()] = e;
  ++count_;
}

void HeartbeatConsumer::on_frame(const can::Frame& f, TimeNs now) noexcept {
  const auto hb = parse_heartbeat(f);
  if (!hb) return;
  NodeHeartbeat& n = nodes_[hb->node];
  if (n.consumer_time == 0) return;
  HeartbeatEvent e;
  e.node = hb->node;
  e.state = hb->state;
  e.previous = n.state;
  e.time = now;
  if (!n.seen) {
    e.kind = HeartbeatEvent::Kind::appeared;
    push(e);
  } else if (n.lost) {
    e.kind = HeartbeatEvent::Kind::back;
    e.silent_for = now - n.last_seen;
    push(e);
  }
  if (hb->boot_up()) {
    e.kind = HeartbeatEvent::Kind::boot_up;
    push(e);
  } else if (n.seen && hb->state != n.state) {
    e.kind = HeartbeatEvent::Kind::state_changed;
    push(e);
  }
  n.seen = true;
  n.lost = false;
  n.state = hb->state;
  n.last_seen = now;
}

std::optional<HeartbeatEvent> HeartbeatConsumer::poll(TimeNs now) noexcept {
  for (std::size_t id = 1; id <= max_node_id; ++id) {
    NodeHeartbeat& n = nodes_[id];
    if (n.consumer_time == 0 || !n.seen || n.lost) continue;
    const TimeNs deadline = n.last_seen + n.consumer_time;
    if (now <= deadline) continue;
    n.lost = true;
    ++n.losses;
    HeartbeatEvent e;
    e.kind = HeartbeatEvent::Kind::lost;
    e.node = static_cast<std::uint8_t>(id);
    e.state = e.previous = n.state;
    e.time = now;
    e.silent_for = now - n.last_seen;
    e.late_by = now - deadline;
    push(e);
  }
  if (count_ == 0) return std::nullopt;
  const HeartbeatEvent e = events_[head_];
  head_ = (head_ + 1) % events_.size();
  --count_;
  return e;
}

}  // namespace saw::canopen
