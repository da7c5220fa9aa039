// Heartbeats (CiA 301 7.2.8.3.2): a producer, and a consumer that reports lost and returning nodes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "saw/can/frame.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// Sends the node's state every period (0x1017 producer heartbeat time; 0: off).
class HeartbeatProducer {
 public:
  HeartbeatProducer(std::uint8_t node, TimeNs period) noexcept : node_(node), period_(period) {}
  // (Re)starts the schedule: the first heartbeat is due one period after `now` (after boot-up).
  void start(TimeNs now) noexcept { next_ = now + period_; }
  void set_period(TimeNs period, TimeNs now) noexcept {
    period_ = period;
    start(now);
  }
  // The heartbeat, when one is due. A producer that fell behind (a stalled simulation) sends one
  // and resumes a period later rather than bursting the ones it missed.
  std::optional<can::Frame> poll(TimeNs now, NmtState state) noexcept;

 private:
  std::uint8_t node_;
  TimeNs period_;
  TimeNs next_ = 0;
};

// What the consumer has to say about a node.
struct HeartbeatEvent {
  enum class Kind : std::uint8_t {
    appeared,       // first heartbeat seen: monitoring starts (CiA 301: not before)
    lost,           // nothing within the consumer time
    back,           // a heartbeat after lost
    boot_up,        // the node (re)started: whatever was configured in it is gone
    state_changed,  // a heartbeat with another state than the last
  };
  Kind kind = Kind::appeared;
  std::uint8_t node = 0;
  NmtState state = NmtState::initialising;     // the node's state (last known, for lost)
  NmtState previous = NmtState::initialising;  // state_changed: the state before
  TimeNs time = 0;                             // when it was seen or detected
  TimeNs silent_for = 0;                       // lost and back: time since the heartbeat before
  TimeNs late_by = 0;                          // lost: how far past the consumer time it was detected
};
std::string_view to_string(HeartbeatEvent::Kind k) noexcept;

// What the consumer knows about one node.
struct NodeHeartbeat {
  TimeNs consumer_time = 0;  // 0: not watched
  bool seen = false;
  bool lost = false;
  NmtState state = NmtState::initialising;
  TimeNs last_seen = 0;
  std::uint32_t losses = 0;
};

// Watches nodes' heartbeats (0x1016 consumer heartbeat time). Fixed memory (one slot per node
// ID, a bounded event queue): on_frame() and poll() neither allocate, lock nor throw.
class HeartbeatConsumer {
 public:
  static constexpr std::size_t event_capacity = 64;

  // Set-up: expect `node`'s heartbeat at least every `consumer_time`; throws
  // std::invalid_argument for a node-ID outside 1..127 or a time not above 0.
  void watch(std::uint8_t node, TimeNs consumer_time);

  void on_frame(const can::Frame& f, TimeNs now) noexcept;
  // Detects silent nodes, then returns the oldest event not yet taken.
  std::optional<HeartbeatEvent> poll(TimeNs now) noexcept;

  const NodeHeartbeat& node(std::uint8_t id) const noexcept { return nodes_[id & 0x7F]; }
  // Events that did not fit the queue (the caller polls too rarely).
  std::uint64_t dropped_events() const noexcept { return dropped_; }

 private:
  void push(const HeartbeatEvent& e) noexcept;

  std::array<NodeHeartbeat, 128> nodes_{};
  std::array<HeartbeatEvent, event_capacity> events_{};
  std::size_t head_ = 0, count_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace saw::canopen
