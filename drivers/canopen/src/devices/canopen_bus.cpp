#include "saw/canopen/canopen_bus.hpp"

#include <stdexcept>

namespace saw::canopen {
namespace {

TimeNs sync_offset_of(const CanopenBusConfig& c, const TaskConfig& t) {
  const TimeNs route = t.offset.count();
  return c.sync_offset != 0 ? c.sync_offset : route + (t.period.count() - route) / 2;
}

std::shared_ptr<BusTask> open_task(const CanopenBusConfig& c, const TaskConfig& t,
                                   std::unique_ptr<can::Bus> bus) {
  if (!t.is_periodic())
    throw std::invalid_argument("a canopen_bus's task must be periodic (one SYNC per cycle)");
  if (bus == nullptr) {
    can::BusConfig b;
    b.uri = c.uri;
    bus = can::open_bus(b);
  }
  BusTaskConfig k;
  k.period = t.period.count();
  k.node = c.node;
  k.heartbeat_period = c.heartbeat_period;
  k.heartbeat_timeout = c.heartbeat_timeout;
  k.route_offset = t.offset.count();
  k.send_offset = sync_offset_of(c, t);
  return std::make_shared<BusTask>(std::move(bus), k);
}

TaskConfig send_task(const TaskConfig& t, const CanopenBusConfig& c) {
  TaskConfig s = t;
  s.offset = std::chrono::nanoseconds(sync_offset_of(c, t));
  return s;
}

}  // namespace

CanopenBus::CanopenBus(std::string name, TaskConfig task, CanopenBusConfig config,
                       std::unique_ptr<can::Bus> bus)
    : Task(std::move(name), task),
      claim_(config.uri, this->name()),
      task_(open_task(config, task, std::move(bus))),
      send_(this->name() + "_sync", send_task(task, config), *task_) {
  publish_bus_task(this->name(), task_);
  status_.node = config.node;
  provide("canopen_bus")
      .add_command_read("status", state_table().add_column("status", &status_, ColumnUse::summary));
}

CanopenBus::~CanopenBus() { withdraw_bus_task(name()); }

void CanopenBus::run() {
  BusTaskCounters c;
  if (!task_->route(now(), &c)) return;
  status_.bus_state = static_cast<std::uint8_t>(task_->state());
  status_.clients = static_cast<std::uint8_t>(task_->clients());
  status_.syncs = c.syncs;
  status_.heartbeats = c.heartbeats;
  status_.frames_received = c.frames_received;
  status_.frames_sent = c.frames_sent;
  status_.send_refused = c.send_refused;
  status_.foreign_frames = c.foreign_frames;
  status_.dropped = c.dropped;
  status_.phase_skips = c.phase_skips;
}

}  // namespace saw::canopen
