// BusMaster's inside, shared by bus_master.cpp and bus_master_reconfigure.cpp (not installed).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "saw/canopen/bus_master.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/log.hpp"

namespace saw::canopen {
namespace detail {

// Where a mapped object sits: which PDO of the axis, which slot of it; pdo < 0: not mapped.
struct Slot {
  int pdo = -1;
  int slot = -1;
  bool mapped() const noexcept { return pdo >= 0; }
};

// What an identifier is to this master.
enum class Route : std::uint8_t { none, tpdo, emcy, heartbeat, sdo_response };
struct RouteEntry {
  Route route = Route::none;
  std::uint8_t axis = 0;
  std::uint8_t pdo = 0;
};

constexpr std::size_t sdo_capacity = 256;

// One start-up write, encoded at construction: the cycle only sends it.
struct EncodedWrite {
  ObjectAddress address;
  std::array<std::uint8_t, 8> bytes{};
  std::size_t size = 0;
  bool optional = false;
};

struct Axis {
  Axis(AxisConfig c, const BusMasterConfig& master)
      : config(std::move(c)),
        controller(master.controller),
        sdo(SdoClientConfig{SdoChannel::of_node(config.node), master.sdo_timeout, sdo_capacity}) {
    for (const PdoMapping& m : config.pdos) {
      if (!m.enabled) continue;
      if (m.kind == PdoKind::rpdo)
        rpdos.emplace_back(m);
      else
        tpdos.emplace_back(m);
    }
  }

  template <class T>
  bool read(Slot s, T& out) const noexcept {
    return s.mapped() &&
           tpdos[static_cast<std::size_t>(s.pdo)].get(static_cast<std::size_t>(s.slot), out) == Codec::ok;
  }

  AxisConfig config;
  std::vector<PdoPacker> rpdos;
  std::vector<PdoUnpacker> tpdos;
  // Every RPDO slot of the controlword and of the mode's target gets the value: a drive applies
  // them in the order its RPDOs come, so a second mapping of either must not carry a stale one.
  std::vector<Slot> controlwords, targets;
  Slot statusword, position, velocity, torque, mode_display, error_code;
  std::uint32_t tpdo_seen = 0;  // bit per TPDO: received at least once
  bool tpdo_this_cycle = false;
  cia402::Controller controller;
  cia402::ControllerOutput control;
  SdoClient sdo;
  AxisFeedback feedback;
  AxisHealth health;
  double setpoint = 0;
  TimeNs previous_time = 0;
  std::int32_t previous_counts = 0;
  // Re-configuration (a drive that rebooted).
  std::vector<EncodedWrite> writes;
  Reconfiguration reconfig;
  std::size_t reconfig_next = 0;
  bool reconfig_started = false, reconfig_starting = false;
  TimeNs reconfig_since = 0;
};

}  // namespace detail

using detail::Axis;
using detail::EncodedWrite;
using detail::Route;
using detail::RouteEntry;
using detail::Slot;

struct BusMaster::Impl {
  Impl(can::Bus& b, BusMasterConfig c)
      : bus(b),
        config(c),
        sync(c.period, c.sync_overflow),
        heartbeat(c.node, c.heartbeat_period),
        queue(c.sdo_queue) {}

  void route(std::uint32_t id, RouteEntry e, const std::string& who) {
    if (routes[id].route != Route::none)
      throw std::invalid_argument(who + ": identifier " + std::to_string(id) + " is used twice on this bus");
    routes[id] = e;
  }
  void on_frame(const can::Frame& f, TimeNs now) noexcept;
  void on_tpdo(Axis& a, std::size_t pdo, const can::Frame& f, TimeNs now) noexcept;
  void on_emcy(Axis& a, const can::Frame& f) noexcept;
  void heartbeat_events(TimeNs now) noexcept;
  void update_feedback(Axis& a, TimeNs now) noexcept;
  void service_sdo(TimeNs now) noexcept;
  void step_reconfiguration(Axis& a, TimeNs now) noexcept;
  void out(const can::Frame& f) noexcept {
    if (out_count < outbox.size()) outbox[out_count++] = f;
  }
  Axis* by_node(std::uint8_t node) noexcept {
    for (auto& a : axes)
      if (a.config.node == node) return &a;
    return nullptr;
  }

  can::Bus& bus;
  BusMasterConfig config;
  std::vector<Axis> axes;
  std::array<RouteEntry, CAN_SFF_MASK + 1> routes{};
  HeartbeatConsumer heartbeats;
  SyncProducer sync;
  HeartbeatProducer heartbeat;
  SdoQueue queue;
  MasterCounters counters;
  std::vector<can::Received> inbox;
  std::vector<can::Frame> outbox;
  std::size_t out_count = 0;
  bool started = false;
  TimeNs first_cycle = 0;
  int sdo_axis = -1;  // the axis running a runtime transfer
  std::uint32_t sdo_tag = 0;
};

}  // namespace saw::canopen
