// BusMaster's inside: the CiA 402 part of each drive (not installed).
#pragma once

#include <vector>

#include "saw/canopen/bus_master.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/sync.hpp"

namespace saw::canopen::detail {

// Where a mapped object sits: which PDO of the axis, which slot of it; pdo < 0: not mapped.
struct Slot {
  int pdo = -1;
  int slot = -1;
  bool mapped() const noexcept { return pdo >= 0; }
};

struct Axis {
  Axis(AxisConfig c, const BusMasterConfig& master) : config(std::move(c)), controller(master.controller) {}

  AxisConfig config;
  // Every RPDO slot of the controlword and of the mode's target gets the value: a drive applies
  // them in the order its RPDOs come, so a second mapping of either must not carry a stale one.
  std::vector<Slot> controlwords, targets;
  Slot statusword, position, velocity, torque, mode_display, error_code;
  cia402::Controller controller;
  cia402::ControllerOutput control;
  AxisFeedback feedback;
  double setpoint = 0;
  TimeNs previous_time = 0;
  std::int32_t previous_counts = 0;
};

}  // namespace saw::canopen::detail

namespace saw::canopen {

struct BusMaster::Impl {
  explicit Impl(BusMasterConfig c)
      : config(c), sync(c.period, c.sync_overflow), heartbeat(c.node, c.heartbeat_period) {}

  BusMasterConfig config;
  std::vector<detail::Axis> axes;
  SyncProducer sync;
  HeartbeatProducer heartbeat;
  std::uint16_t shut_down_controlword = 0;
};

}  // namespace saw::canopen
