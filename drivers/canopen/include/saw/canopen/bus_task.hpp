// The task of one CAN bus that several components share: the bus's only reader and writer, SYNC, the master's
// heartbeat.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/frame_counters.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/clock.hpp"
#include "saw/task.hpp"

namespace saw::canopen {

struct BusTaskConfig {
  TimeNs period = 1'000'000;  // one SYNC per cycle
  // The master's own heartbeat (CiA 301): its node-ID (no node of any client may have it), its
  // period (0: none), and the consumer time every client writes to its nodes' 0x1016:01.
  std::uint8_t node = 127;
  TimeNs heartbeat_period = 100'000'000;
  TimeNs heartbeat_timeout = 300'000'000;
  std::size_t max_frames = 256;  // frames read per cycle at most; the rest wait a cycle
  std::size_t ring = 512;        // frames in flight per client and direction
  // A canopen_bus runs the period in two phases, each its own task on the period's grid: at
  // route_offset the frames received are routed to the clients, at send_offset the clients'
  // queued frames go out, then SYNC. Its clients run between the two, so what a client computes
  // from this period's TPDOs goes out before this period's SYNC. send_offset 0: no phases
  // (cycle() does both, as a component that runs the task of its own bus in its cycle).
  TimeNs route_offset = 0;
  TimeNs send_offset = 0;
};

// The frames' figures (foreign: for no client), and what only a bus task counts.
struct BusTaskCounters : FrameCounters {
  std::uint64_t dropped = 0;  // frames for a client whose ring was full
  // A phase that found the other one still running (a late wake-up, an overrun) and skipped
  // its turn: its frames wait for its next one.
  std::uint64_t phase_skips = 0;
};

class BusTask;

// A client's bus: a can::Bus whose frames are its own nodes' (their EMCY, heartbeat, SDO
// responses, TPDOs). While the client cycles (set_cycling(true), from its first RT cycle on) it
// reads what the bus task's route phase routed to it and queues what it sends for its send
// phase (lock-free rings, one writer each). Before (the client's start-up) and after (its last frames
// at exit, once every task's thread has ended) it reads and writes the bus itself: then no
// thread cycles, so nobody else touches the bus; a frame it reads then for another client's
// node goes to that client's in-ring (its first cycle reads it), a full ring counting it dropped.
class BusPort final : public can::Bus {
 public:
  std::size_t receive(std::span<can::Received> out) noexcept override;
  std::size_t send(std::span<const can::Frame> frames) noexcept override;
  can::BusState state() const noexcept override;
  can::BusCounters counters() const noexcept override;
  const std::string& name() const noexcept override;

  void set_cycling(bool on) noexcept { cycling_.store(on, std::memory_order_release); }
  bool cycling() const noexcept { return cycling_.load(std::memory_order_acquire); }
  // The client walked its nodes to their safe state and NMT pre-operational.
  void mark_shut_down() noexcept { shut_down_ = true; }
  const std::string& client() const noexcept { return client_; }
  std::span<const std::uint8_t> nodes() const noexcept { return nodes_; }
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

  ~BusPort() override;
  BusPort(const BusPort&) = delete;
  BusPort& operator=(const BusPort&) = delete;

 private:
  friend class BusTask;
  template <class T>
  struct Ring;  // single producer, single consumer, fixed capacity
  BusPort(BusTask& task, std::string client, std::vector<std::uint8_t> nodes, std::size_t ring);

  BusTask& task_;
  std::string client_;
  std::vector<std::uint8_t> nodes_;
  std::unique_ptr<Ring<can::Received>> in_;  // bus task → client
  std::unique_ptr<Ring<can::Frame>> out_;    // client → bus task
  std::atomic<bool> cycling_{false};
  std::atomic<std::uint64_t> dropped_{0};
  bool shut_down_ = false;
};

// One bus and the clients on it. Its period has two phases: route() checks every received frame
// and routes it to the client whose node sent it; send() sends every client's queued frames in
// the order queued, then SYNC — after the clients' RPDOs, so that each SYNC applies what they
// queued before it — and the master's heartbeat when due. A canopen_bus runs them in two tasks
// (route at the period's route_offset, send at its send_offset), its clients between them;
// cycle() runs both back to back (one thread). The phases never touch the bus at the same time:
// each takes a flag that the other holds while it runs (an atomic exchange, never a wait); a
// phase that finds it taken skips its turn and counts it (phase_skips). None of them allocates,
// locks, blocks, prints or throws. attach() is set-up.
class BusTask {
 public:
  BusTask(std::unique_ptr<can::Bus> bus, BusTaskConfig config);
  // Sends NMT enter pre-operational to every node whose client never shut it down (a client
  // that failed before its start-up, or never ran): no node of the bus is left operational.
  ~BusTask();
  BusTask(const BusTask&) = delete;
  BusTask& operator=(const BusTask&) = delete;

  // A client with its nodes and the TPDO identifiers it receives (besides its nodes' EMCY,
  // heartbeat and SDO responses). Throws std::invalid_argument naming both clients when a node
  // or an identifier is another client's, or a node is the master's own node-ID.
  BusPort& attach(const std::string& client, std::span<const std::uint8_t> nodes,
                  std::span<const std::uint32_t> tpdos);

  // Each false when it skipped (the other phase was running). `seen`: the counters as this
  // phase left them (read under the flag: a copy without a race).
  bool route(TimeNs now, BusTaskCounters* seen = nullptr) noexcept;
  bool send(TimeNs now, BusTaskCounters* seen = nullptr) noexcept;
  void cycle(TimeNs now) noexcept {
    (void)route(now);
    (void)send(now);
  }

  can::Bus& bus() noexcept { return *bus_; }
  const BusTaskConfig& config() const noexcept { return config_; }
  // From the thread that runs the phases, or once they have stopped (else: route()'s `seen`).
  BusTaskCounters counters() const noexcept;
  std::size_t clients() const noexcept { return ports_.size(); }
  const BusPort& port(std::size_t i) const noexcept { return *ports_[i]; }
  // The bus's state as the last cycle saw it (read by the clients' threads).
  can::BusState state() const noexcept { return state_.load(std::memory_order_acquire); }

 private:
  friend class BusPort;
  void flush(std::span<const can::Frame> frames) noexcept;
  // The bus read for a client that does not cycle: its frames (and those of no client) in
  // `out`, the other clients' to their in-rings.
  std::size_t receive_for(BusPort& port, std::span<can::Received> out) noexcept;
  bool enter() noexcept;  // the phases' flag: false (and counted) when taken
  void leave(BusTaskCounters* seen) noexcept;

  std::unique_ptr<can::Bus> bus_;
  BusTaskConfig config_;
  std::vector<std::unique_ptr<BusPort>> ports_;
  std::array<std::uint8_t, 2048> routes_{};  // 11-bit identifier → port index + 1; 0: none
  SyncProducer sync_;
  HeartbeatProducer heartbeat_;
  BusTaskCounters counters_;
  std::vector<can::Received> inbox_;
  std::array<can::Frame, 64> outbox_{};
  std::size_t out_count_ = 0;
  bool started_ = false;
  std::atomic<bool> busy_{false};  // a phase runs
  std::atomic<std::uint64_t> phase_skips_{0};
  std::atomic<can::BusState> state_{can::BusState::error_active};
};

}  // namespace saw::canopen
