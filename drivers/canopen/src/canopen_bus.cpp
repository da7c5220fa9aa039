#include "saw/canopen/canopen_bus.hpp"

#include <stdexcept>

namespace saw::canopen {
namespace {

std::shared_ptr<BusTask> open_task(const CanopenBusConfig& c, const TaskConfig& t) {
  if (!t.is_periodic())
    throw std::invalid_argument("a canopen_bus's task must be periodic (one SYNC per cycle)");
  can::BusConfig b;
  b.uri = c.uri;
  BusTaskConfig k;
  k.period = t.period.count();
  k.node = c.node;
  k.heartbeat_period = c.heartbeat_period;
  k.heartbeat_timeout = c.heartbeat_timeout;
  return std::make_shared<BusTask>(can::open_bus(b), k);
}

}  // namespace

CanopenBus::CanopenBus(std::string name, TaskConfig task, CanopenBusConfig config)
    : Task(std::move(name), task), claim_(config.uri, this->name()), task_(open_task(config, task)) {
  publish_bus_task(this->name(), task_);
  status_.node = config.node;
  provide("canopen_bus")
      .add_command_read("status", state_table().add_column("status", &status_, ColumnUse::summary));
}

CanopenBus::~CanopenBus() { withdraw_bus_task(name()); }

void CanopenBus::run() {
  task_->cycle(now());
  const BusTaskCounters& c = task_->counters();
  status_.bus_state = static_cast<std::uint8_t>(task_->state());
  status_.clients = static_cast<std::uint8_t>(task_->clients());
  status_.syncs = c.syncs;
  status_.heartbeats = c.heartbeats;
  status_.frames_received = c.frames_received;
  status_.frames_sent = c.frames_sent;
  status_.send_refused = c.send_refused;
  status_.foreign_frames = c.foreign_frames;
  status_.dropped = c.dropped;
}

}  // namespace saw::canopen
