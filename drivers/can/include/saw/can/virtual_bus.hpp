// The virtual CAN bus: vcan's behaviour in user space, a broadcast ring in POSIX shared memory.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/detail/virtual_bus_layout.hpp"

namespace saw::can {

namespace detail {
// A process's mapping of one bus segment, shared by its attachments; what was validated at attach.
struct VirtualBusMapping {
  VirtualBusMapping(void* b, std::size_t s, dev_t d, ino_t i) : base(b), size(s), dev(d), ino(i) {}
  ~VirtualBusMapping();
  VirtualBusMapping(const VirtualBusMapping&) = delete;
  VirtualBusMapping& operator=(const VirtualBusMapping&) = delete;
  void* base;
  std::size_t size;
  dev_t dev;
  ino_t ino;
  std::uint64_t capacity = 0;
};
}  // namespace detail

// What a virtual bus attachment does beyond the Bus seam's BusConfig.
struct VirtualBusOptions {
  // The dead-producer rule's grace: a slot a producer took but has not completed for this long,
  // while later frames wait behind it, is skipped (and counted). A producer that completes it
  // later has lost that frame for the readers that moved on. See docs/can.md.
  TimeNs incomplete_grace = 50'000'000;
  // How long attaching waits for a segment that another process is creating to be published.
  TimeNs attach_timeout = 1'000'000'000;
};

// One process's attachment to /dev/shm/saw-can.<name> (created by the first opener, never
// unlinked on close). Every frame a peer sends is seen once by every other attachment, not by
// its sender; a reader more than a ring behind skips ahead and counts the frames as overruns.
// receive() is called by one thread at a time, send() by one thread at a time (they may be two
// threads); state(), counters() and the statistics below from any thread.
class VirtualBus final : public Bus {
 public:
  // Creates or attaches; throws std::runtime_error naming the bus and what is wrong.
  VirtualBus(const BusConfig& config, std::string_view bus_name, const VirtualBusOptions& options = {});
  ~VirtualBus() override;
  VirtualBus(const VirtualBus&) = delete;
  VirtualBus& operator=(const VirtualBus&) = delete;

  std::size_t receive(std::span<Received> out) noexcept override;
  std::size_t send(std::span<const Frame> frames) noexcept override;
  BusState state() const noexcept override { return BusState::error_active; }
  BusCounters counters() const noexcept override;
  const std::string& name() const noexcept override { return name_; }

  // Whether this attachment created the segment (the others found it and validated it).
  bool created() const noexcept { return created_; }
  std::uint64_t capacity() const noexcept { return mask_ + 1; }
  std::uint32_t attachment_id() const noexcept { return id_; }
  // Where this process mapped the segment: the same for all its attachments to one bus.
  const void* mapping_address() const noexcept { return header_; }
  // Tickets skipped by the dead-producer rule (also counted in overruns).
  std::uint64_t abandoned() const noexcept { return abandoned_.load(std::memory_order_relaxed); }
  // This attachment's sends that a full ring of newer traffic overtook before they completed
  // (counted as sent: the ring took them, as it takes a frame no reader reads in time).
  std::uint64_t lapped_sends() const noexcept { return lapped_.load(std::memory_order_relaxed); }

 private:
  bool accepts(const Frame& f) const noexcept;
  bool write_one(const Frame& f, TimeNs now) noexcept;
  // A counter written by one thread and read by any: a relaxed load and store, no RMW.
  static void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
    c.store(c.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
  }

  std::string name_;
  std::string shm_name_;
  bool fd_;
  std::vector<BusConfig::Filter> filters_;
  VirtualBusOptions options_;
  bool created_ = false;
  // The mapping and what was validated at attach: private copies, never read back.
  std::shared_ptr<detail::VirtualBusMapping> mapping_;
  detail::VirtualBusHeader* header_ = nullptr;
  detail::VirtualBusSlot* slots_ = nullptr;
  std::uint64_t mask_ = 0;
  std::uint32_t id_ = 0;

  // The reader's private cursor and its wait on an incomplete slot (receive()'s thread only).
  alignas(cache_line) std::uint64_t next_ = 0;
  std::uint64_t waiting_ticket_ = ~std::uint64_t{0};
  TimeNs waiting_since_ = 0;

  alignas(cache_line) std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> malformed_{0};
  std::atomic<std::uint64_t> abandoned_{0};
  alignas(cache_line) std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<std::uint64_t> lapped_{0};
};

// The shared-memory object's name, "/saw-can.<name>" (it appears as /dev/shm/saw-can.<name>).
// Throws std::invalid_argument for a name that is empty, longer than 64 bytes, or has characters
// outside [A-Za-z0-9_.-].
std::string virtual_bus_shm_name(std::string_view name);

// Unlinks a virtual bus (for tests and tools): attachments keep their mapping; the next opener
// creates a new segment. Returns whether a segment was there.
bool remove_virtual_bus(std::string_view name);

}  // namespace saw::can
