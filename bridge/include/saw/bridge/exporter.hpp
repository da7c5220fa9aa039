// Exporter: publishes one provided interface of a local task in a shared-memory segment.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "saw/bridge/layout.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/component.hpp"

namespace saw::bridge {

// The segment is "/saw.<component>". Each cycle of the exporting task, after its state row,
// the exporter (in that task's thread, RT-safe: no allocation, lock or blocking call) refreshes
// the heartbeat, copies the read commands' newest values into the state mirror, and runs the
// void/write commands that client processes left in their slots' rings. Events emitted by the
// task are copied into every claimed slot's event ring as they happen. A non-RT service thread
// answers qualified reads (const and thread-safe by contract) and reclaims dead clients' slots.
struct ExportOptions {
  std::uint32_t slots = 8;           // client processes at once
  std::uint32_t ring_capacity = 64;  // per slot and direction
  TimeNs service_spin = 0;           // the query thread stays awake this long after a query
};

class Exporter : public Component::CycleHook {
 public:
  // Before the manager starts. Throws BridgeError if the name is held by a live process, or a
  // type has no layout version.
  Exporter(Component& component, const std::string& provided, ExportOptions options = {});
  Exporter(Component& component, const std::string& provided, std::uint32_t slots)
      : Exporter(component, provided, ExportOptions{slots}) {}
  ~Exporter() override;

  void after_cycle(Component& c, TimeNs time) noexcept override;
  const std::string& segment_name() const noexcept { return segment_.name(); }
  std::uint64_t commands_run() const noexcept { return commands_run_; }
  std::uint64_t events_refused() const noexcept { return events_refused_; }

 private:
  struct Read {
    const Command* command;
    std::uint32_t offset, size;
  };
  struct Slot {
    std::uint32_t generation = 0;
    std::unique_ptr<SpscRing> commands, events;
  };
  void emit(std::uint32_t index, const void* arg, std::size_t size) noexcept;
  // The view of slot i if a client holds it (resynced to a new owner), else nullptr.
  Slot* claimed(std::uint32_t i) noexcept;
  void serve();

  TimeNs service_spin_;
  ShmSegment segment_;
  std::vector<Command*> commands_;  // by wire index; events take the indices after commands
  std::vector<Read> reads_;
  std::vector<std::byte> staging_;
  std::vector<Slot> slots_;
  struct EventTap {
    Exporter* exporter;
    std::uint32_t index;
    std::uint32_t size;
  };
  std::vector<std::unique_ptr<EventTap>> taps_;
  std::uint64_t commands_run_ = 0, events_refused_ = 0;
  std::atomic<bool> stop_{false};
  std::thread service_;
};

}  // namespace saw::bridge
