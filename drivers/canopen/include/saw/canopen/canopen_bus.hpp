// CanopenBus: the bus task of one CAN bus as a periodic RT component that other CANopen components name as
// their `bus`.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "saw/canopen/bus_link.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/task.hpp"

namespace saw::canopen {

// The bus task's figures: a summary column (printed when a run ends).
struct CanopenBusStatus {
  static constexpr std::string_view type_name = "saw::canopen::CanopenBusStatus";
  static constexpr std::uint32_t layout_version = 2;
  std::uint8_t bus_state = 0;  // can::BusState
  std::uint8_t clients = 0;
  std::uint8_t node = 0;  // the master's heartbeat node-ID
  std::uint64_t syncs = 0, heartbeats = 0;
  std::uint64_t frames_received = 0, frames_sent = 0, send_refused = 0, foreign_frames = 0, dropped = 0;
  std::uint64_t phase_skips = 0;  // a phase skipped: the other one still ran (BusTaskCounters)
  static constexpr auto fields = std::tuple{
      &CanopenBusStatus::bus_state,   &CanopenBusStatus::clients,      &CanopenBusStatus::node,
      &CanopenBusStatus::syncs,       &CanopenBusStatus::heartbeats,   &CanopenBusStatus::frames_received,
      &CanopenBusStatus::frames_sent, &CanopenBusStatus::send_refused, &CanopenBusStatus::foreign_frames,
      &CanopenBusStatus::dropped,     &CanopenBusStatus::phase_skips};
};

struct CanopenBusConfig {
  std::string uri;  // "virtual:<name>" or "socketcan:<if>"
  std::uint8_t node = 127;
  TimeNs heartbeat_period = 100'000'000;
  TimeNs heartbeat_timeout = 300'000'000;
  // The send phase's offset in the period (its second task); 0: halfway between the route
  // phase's (the task's offset) and the period's end.
  TimeNs sync_offset = 0;
};

// Opens the bus (claimed: no other master of it in this process) and publishes its BusTask
// under the component's name; the components whose `bus` is that name attach to it when they are
// built, and run between its two phases (client_task()). Its own cycle, at its task's offset, is
// BusTask::route(); a second task of the same period and priority, `<name>_sync` (a companion the
// manager adds right after it), runs BusTask::send() at sync_offset. Provided "canopen_bus":
// status (CanopenBusStatus). `bus`, when given, is used instead of opening config.uri (tests).
class CanopenBus : public Task {
 public:
  CanopenBus(std::string name, TaskConfig task, CanopenBusConfig config,
             std::unique_ptr<can::Bus> bus = nullptr);
  ~CanopenBus() override;
  BusTask& bus_task() noexcept { return *task_; }
  const CanopenBusStatus& status() const noexcept { return status_; }
  Task& sync_task() noexcept { return send_; }

  void run() override;  // the route phase: BusTask::route()
  std::vector<Component*> companions() override { return {&send_}; }

 private:
  // The send phase: the clients' frames, SYNC, the master's heartbeat.
  class Send final : public Task {
   public:
    Send(std::string name, TaskConfig task, BusTask& bus) : Task(std::move(name), task), bus_(bus) {}
    void run() override { (void)bus_.send(now()); }

   private:
    BusTask& bus_;
  };

  BusClaim claim_;
  std::shared_ptr<BusTask> task_;
  Send send_;
  CanopenBusStatus status_{};
};

}  // namespace saw::canopen
