// How a CANopen component reaches its bus: a URI it opens and is master of, or a canopen_bus's
// bus task it joins; the process's bus tasks by name and the one master per bus.
#pragma once

#include <memory>
#include <span>
#include <string>

#include "saw/can/bus.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/task.hpp"

namespace saw::canopen {

// The buses of this process by deployment name (a canopen_bus component's), for the components
// that name one as their `bus`. Set-up only (a lock). find() throws std::runtime_error saying
// what is missing.
void publish_bus_task(const std::string& name, std::shared_ptr<BusTask> task);
void withdraw_bus_task(const std::string& name) noexcept;
std::shared_ptr<BusTask> find_bus_task(const std::string& name);

// One master per bus and process: two would both send SYNC and fight over the nodes. Held by
// whoever opens a bus (a canopen_bus, or a component that is master of its own bus); a second
// claim of the same bus throws std::runtime_error naming the holder.
class BusClaim {
 public:
  BusClaim(std::string bus, const std::string& owner);
  ~BusClaim();
  BusClaim(const BusClaim&) = delete;
  BusClaim& operator=(const BusClaim&) = delete;

 private:
  std::string bus_;
};

// The task of a client of bus `bus` (a canopen_bus's name; a URI: `task` as it is). Its period
// must be the bus task's; its offset strictly after the route phase's and before the send
// phase's, so that it reads this period's TPDOs and its RPDOs go out before this period's SYNC.
// An offset of 0 (none given) becomes the middle of the two. Throws std::runtime_error naming
// the client, the bus and both values.
TaskConfig client_task(const std::string& bus, const std::string& client, TaskConfig task);

// The bus a component reaches its nodes through.
struct BusLink {
  std::unique_ptr<can::Bus> owned;  // its own bus (a URI) ...
  std::unique_ptr<BusClaim> claim;  // ... of which it is the master
  std::shared_ptr<BusTask> task;    // or a shared bus task ...
  BusPort* port = nullptr;          // ... and its port there
  can::Bus* bus = nullptr;          // what its drivers use: the bus, or the port
  bool shared() const noexcept { return port != nullptr; }
};
// A bus URI (`virtual:<name>`, `socketcan:<if>`), or else the name of a canopen_bus component.
bool is_bus_uri(const std::string& bus) noexcept;
// A URI: opened and claimed for `client` (throws std::runtime_error: cannot open, or claimed);
// a name: the bus task found and joined with `nodes` and `tpdos` (attach()'s errors). A client
// whose `period` is not the bus task's is refused (std::runtime_error naming both components
// and both periods): each SYNC applies the RPDOs queued in its period, and the client reads the
// TPDOs of one SYNC per cycle. client_task() places the client between the phases.
BusLink link_bus(const std::string& bus, const std::string& client, TimeNs period,
                 std::span<const std::uint8_t> nodes, std::span<const std::uint32_t> tpdos);
// A caller's bus (a test's, a benchmark's), of which `client` is the master as of a URI: claimed
// by its address (two may share a name), owned as a can::BorrowedBus (the caller keeps it alive).
BusLink link_callers_bus(can::Bus& bus, const std::string& client);

}  // namespace saw::canopen
