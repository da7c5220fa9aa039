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
#include "saw/detail/cycle_hook.hpp"
#include "saw/detail/spsc_ring.hpp"

namespace saw::bridge {

// The segment is "/saw.<component>". Each cycle of the exporting task, after its state row,
// the exporter (in that task's thread, RT-safe: no allocation, lock or blocking call) refreshes
// the heartbeat, copies the read commands' newest values into the state mirror's next row (it
// keeps the last `history_rows`), and runs the
// void/write commands that client processes left in their slots' rings. Events emitted by the
// task are copied into every claimed slot's event ring as they happen. A non-RT service thread
// answers qualified reads (const and thread-safe by contract) and frees the slots of clients
// whose heartbeat stopped. A task's `period_statistics` read (its `task` interface) is carried
// too, after the interface's own commands: its health crosses with the one exported interface.
//
// Nothing a client writes is trusted: the exporter keeps every offset, size and index of its
// own in private memory, copies each record out of the segment before looking at it, and runs a
// command only if its index names a command and its argument passes its type's check (finite
// numbers, valid enumerators and bools) and the limits the component declared. Refusals are
// counted.
struct ExportOptions {
  std::uint32_t slots = 8;              // client processes at once
  std::uint32_t ring_capacity = 64;     // per slot and direction
  TimeNs service_spin = 0;              // the query thread stays awake this long after a query
  TimeNs client_timeout = 500'000'000;  // a client slot whose heartbeat is older is freed
  // Rows of state the mirror keeps (1 s of a 1 kHz task): a client that falls behind (a gateway
  // descheduled) reads every row it missed, as long as it is fewer than this.
  std::uint32_t history_rows = 1024;
};

class Exporter : public detail::CycleHook {
 public:
  // Before the manager starts. Throws BridgeError if the name is held by a live process, a
  // type is not registered for other processes (type_info.hpp), or a name (of the component,
  // the interface, a command or a type) is longer than its manifest field: never truncated.
  Exporter(Component& component, const std::string& provided, ExportOptions options = {});
  Exporter(Component& component, const std::string& provided, std::uint32_t slots)
      : Exporter(component, provided, ExportOptions{slots}) {}
  ~Exporter() override;

  const std::string& segment_name() const noexcept { return segment_.name(); }

  // Counters, readable from any thread.
  std::uint64_t commands_run() const noexcept { return load(commands_run_); }
  // Records decoded from a client's ring and not run: no such command, or an argument that
  // failed its type's check or the declared limits.
  std::uint64_t commands_refused() const noexcept { return load(commands_refused_); }
  std::uint64_t events_refused() const noexcept { return load(events_refused_); }
  // Qualified-read requests refused (no such query, or an invalid argument).
  std::uint64_t queries_refused() const noexcept { return load(queries_refused_); }
  // A client's ring index that no producer or consumer could have published.
  std::uint64_t ring_errors() const noexcept;
  std::uint64_t slots_reclaimed() const noexcept { return load(slots_reclaimed_); }

 private:
  void after_cycle(Component& c, TimeNs time) noexcept override;

  struct Read {
    const Command* command;
    std::uint32_t offset, size;
  };
  struct Slot {
    std::unique_ptr<detail::SpscRing> commands, events;  // consumer and producer views, own indices private
  };
  using Counter = std::atomic<std::uint64_t>;
  static std::uint64_t load(const Counter& c) noexcept { return c.load(std::memory_order_relaxed); }
  static void bump(Counter& c) noexcept {  // one writer per counter
    c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
  void describe(const Component& component, const ProvidedInterface& p);
  void emit(std::uint32_t index, const void* arg, std::size_t size) noexcept;
  void run_commands(Slot& slot) noexcept;
  bool answer_queries();  // true if it answered any
  void serve();

  TimeNs service_spin_;
  TimeNs client_timeout_;
  ShmSegment segment_;
  SegmentView view_;                // the layout this process computed; never re-read from the segment
  std::uint64_t mirror_rows_ = 0;   // rows written to the state mirror
  std::vector<Command*> commands_;  // by wire index; events take the indices after commands
  std::vector<Read> reads_;
  std::vector<std::byte> staging_;  // the mirror's next contents
  std::vector<std::byte> record_;   // one command record, copied out of the segment
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> last_reply_;  // per slot, the service thread's
  struct EventTap {
    Exporter* exporter;
    std::uint32_t index;
    std::uint32_t size;
  };
  std::vector<std::unique_ptr<EventTap>> taps_;
  Counter commands_run_{0}, commands_refused_{0}, events_refused_{0}, queries_refused_{0},
      slots_reclaimed_{0};
  std::atomic<bool> stop_{false};
  std::thread service_;
};

}  // namespace saw::bridge
