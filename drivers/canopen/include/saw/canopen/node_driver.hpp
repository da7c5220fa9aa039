// The CANopen node driver base: the nodes of one master (or one client of a bus task) — frames in
// and out, NMT state and heartbeats, EMCY, TPDO validity, start-up writes run again after a reboot,
// runtime SDO — with a profile's own work (CiA 402's controller, CiA 401's channels) on top.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/axis.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/frame_counters.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sdo_queue.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// A node's configuration run again from the cycle (a node that rebooted): the start-up's SDO
// writes through its SDO channel, then NMT start and an operational heartbeat.
struct Reconfiguration {
  enum class State : std::uint8_t { idle, busy, done, failed } state = State::idle;
  ObjectAddress object{};           // failed: the write refused (0x0000: no operational heartbeat)
  SdoAbort abort = SdoAbort::none;  // ... and why
};

// The frames' figures (foreign: for no node of this driver), and what only a node driver counts.
struct NodeCounters : FrameCounters {
  std::uint64_t emcy = 0;                      // EMCY messages, error resets included
  std::uint64_t sdo_done = 0, sdo_failed = 0;  // runtime SDO transfers
  std::uint64_t heartbeat_events_dropped = 0;
};

// A node's EMCYs by what they mean (emcy_severity): counters only grow, a reader compares them
// with the values it saw last (several in one cycle: the newest of each kind is kept).
struct NodeEmcys {
  std::uint64_t warnings = 0, faults = 0, resets = 0;
  Emcy last_warning{}, last_fault{};
};

// One node as its driver is made: what errors call it, its node-ID, its PDOs, how long its
// heartbeat may be missing, and its start-up writes (run again after a reboot).
struct NodeSpec {
  std::string who;  // "drive 'elbow' (node 3)": the prefix of its set-up errors
  std::uint8_t node = 1;
  std::vector<PdoMapping> pdos;
  TimeNs heartbeat_timeout = 300'000'000;
  std::vector<StartupWrite> writes;
};

// What differs between profiles' drivers, kept as each was.
struct NodeDriverOptions {
  TimeNs sdo_timeout = 500'000'000;  // each response of a runtime SDO transfer
  std::size_t sdo_capacity = 256;    // bytes a runtime SDO transfer carries at most
  std::size_t sdo_queue = 16;        // runtime SDO requests (and replies) in flight
  std::size_t max_frames = 256;      // frames read per cycle at most; the rest wait a cycle
  bool log_emcy = false;             // an info line per EMCY heard (source: the bus's name)
  // A runtime transfer waits while its node is re-configured (else the re-configuration waits).
  bool sdo_waits_for_reconfiguration = false;
};

// The cycle, on the owner's thread: receive(now) takes every frame that arrived (at most
// max_frames: TPDOs, heartbeats, EMCY, SDO responses; anything else counted foreign) and calls
// on_received(); transmit(now) calls before_rpdos(), sends every node's RPDOs, steps a runtime SDO
// transfer and the re-configurations, adds after_rpdos()'s frames, and sends them all. Neither
// allocates, locks, blocks, prints (but the EMCY line through the RT log) nor throws; nor may the
// hooks. Construction throws std::invalid_argument naming the node (an identifier used twice, a
// start-up value that does not fit its type).
class NodeDriver {
 public:
  virtual ~NodeDriver();
  NodeDriver(const NodeDriver&) = delete;
  NodeDriver& operator=(const NodeDriver&) = delete;

  can::Bus& bus() noexcept { return bus_; }
  std::size_t size() const noexcept { return nodes_.size(); }
  std::uint8_t node_id(std::size_t i) const noexcept { return nodes_[i].spec.node; }

  void receive(TimeNs now) noexcept;
  void transmit(TimeNs now) noexcept;
  // The last frames of a driver that stops: before_shut_down(), every node's RPDOs as set, one
  // SYNC so that the nodes take them at once, then NMT enter pre-operational for every node.
  void shut_down(TimeNs now) noexcept;

  const AxisHealth& health(std::size_t i) const noexcept { return nodes_[i].health; }
  const NodeEmcys& emcys(std::size_t i) const noexcept { return nodes_[i].emcys; }
  bool tpdos_valid(std::size_t i) const noexcept;                       // every TPDO arrived at least once
  bool fresh(std::size_t i) const noexcept { return nodes_[i].fresh; }  // a TPDO in the last receive()
  TimeNs last_received(std::size_t i) const noexcept { return nodes_[i].last_received; }

  // Starts running node i's configuration again (a node that rebooted: its PDOs, heartbeat and
  // consumer are gone), stepped by transmit(); its TPDOs count as not received until they come again.
  void reconfigure(std::size_t i, TimeNs now) noexcept;
  const Reconfiguration& reconfiguration(std::size_t i) const noexcept { return nodes_[i].reconfig; }

  const NodeCounters& counters() const noexcept { return counters_; }
  // Runtime SDO: non-RT code submits here, the cycle runs one transfer at a time.
  SdoQueue& sdo_queue() noexcept { return queue_; }

 protected:
  NodeDriver(can::Bus& bus, NodeDriverOptions options, std::vector<NodeSpec> nodes);

  std::vector<PdoPacker>& rpdos(std::size_t i) noexcept { return nodes_[i].rpdos; }
  const std::vector<PdoUnpacker>& tpdos(std::size_t i) const noexcept { return nodes_[i].tpdos; }
  const NodeSpec& spec(std::size_t i) const noexcept { return nodes_[i].spec; }
  void out(const can::Frame& f) noexcept {
    if (out_count_ < outbox_.size()) outbox_[out_count_++] = f;
  }
  NodeCounters& counters_for_profile() noexcept { return counters_; }

  // Hooks, each noexcept and allocation-free.
  virtual void on_first_cycle(TimeNs) noexcept {}
  virtual void on_received(std::size_t, TimeNs) noexcept {}  // after receive(), for each node
  virtual void before_rpdos(std::size_t, TimeNs) noexcept {}
  virtual void after_rpdos(TimeNs) noexcept {}  // the cycle's last frames (SYNC, ...)
  virtual void before_shut_down(std::size_t, TimeNs) noexcept {}
  virtual can::Frame shut_down_sync() noexcept { return shut_down_sync_.extra(); }
  virtual void on_reconfigure(std::size_t) noexcept {}           // a re-configuration begins
  virtual void on_reconfigured(std::size_t, TimeNs) noexcept {}  // ... and is done

 private:
  // One start-up write, encoded at construction: the cycle only sends it.
  struct Encoded {
    ObjectAddress address;
    std::array<std::uint8_t, 8> bytes{};
    std::size_t size = 0;
    bool optional = false;
  };
  struct Node {
    Node(NodeSpec s, const NodeDriverOptions& o);
    NodeSpec spec;
    std::vector<PdoPacker> rpdos;
    std::vector<PdoUnpacker> tpdos;
    std::uint32_t tpdo_seen = 0;  // bit per TPDO: received at least once
    bool fresh = false;
    TimeNs last_received = 0;
    AxisHealth health;
    NodeEmcys emcys;
    SdoClient sdo;
    std::vector<Encoded> writes;
    Reconfiguration reconfig;
    std::size_t next = 0;
    bool started = false, starting = false;
    TimeNs since = 0;
  };
  // What an identifier is to this driver.
  enum class Route : std::uint8_t { none, tpdo, emcy, heartbeat, sdo_response };
  struct RouteEntry {
    Route route = Route::none;
    std::uint8_t node = 0;  // index
    std::uint8_t pdo = 0;
  };
  void route(std::uint32_t id, RouteEntry e, const std::string& who);
  void on_frame(const can::Frame& f, TimeNs now) noexcept;
  void on_emcy(Node& n, const can::Frame& f) noexcept;
  void heartbeat_events(TimeNs now) noexcept;
  void service_sdo(TimeNs now) noexcept;
  void step_reconfiguration(std::size_t i, TimeNs now) noexcept;
  void send() noexcept;
  int index_of(std::uint8_t node) const noexcept { return node < by_node_.size() ? by_node_[node] : -1; }

  can::Bus& bus_;
  NodeDriverOptions options_;
  std::vector<Node> nodes_;
  std::vector<RouteEntry> routes_;  // by identifier (11 bits)
  std::array<std::int8_t, 128> by_node_{};
  HeartbeatConsumer heartbeats_;
  SyncProducer shut_down_sync_{1'000'000};  // shut_down()'s one SYNC (counter-less)
  SdoQueue queue_;
  NodeCounters counters_;
  std::vector<can::Received> inbox_;
  std::vector<can::Frame> outbox_;
  std::size_t out_count_ = 0;
  bool started_ = false;
  TimeNs first_cycle_ = 0;
  int sdo_node_ = -1;  // the node running a runtime transfer
  std::uint32_t sdo_tag_ = 0;
};

}  // namespace saw::canopen
