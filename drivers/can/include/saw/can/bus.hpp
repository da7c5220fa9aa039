// A CAN bus as the RT cycle sees it: non-blocking batches of frames in and out, and its state.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "saw/can/frame.hpp"

namespace saw::can {

// ISO 11898 error states as the controller reports them (SocketCAN error frames), or, for the
// virtual bus, as its ring reports them.
enum class BusState : std::uint8_t { error_active, error_warning, error_passive, bus_off, down };
std::string_view to_string(BusState s) noexcept;

// Counters since open; each only grows. Read from any thread (relaxed: figures, not sync).
struct BusCounters {
  std::uint64_t received = 0;      // frames handed to receive()'s caller
  std::uint64_t sent = 0;          // frames the bus accepted
  std::uint64_t send_refused = 0;  // frames send() could not queue (full, down): the caller's error
  std::uint64_t overruns = 0;      // frames lost before we read them (ring overflow, socket drops)
  std::uint64_t malformed = 0;     // frames from outside that failed well_formed(), dropped
  std::uint64_t error_frames = 0;  // error frames seen (state changes, bus errors)
};

// The seam between CANopen and a bus. receive() and send() are the only calls made in the RT
// cycle: non-blocking, no allocation, no lock, no throw. Opening and closing happen outside it.
class Bus {
 public:
  virtual ~Bus() = default;
  // Up to out.size() frames that arrived since the last call, oldest first; 0 when none.
  // Malformed frames are dropped and counted, never returned.
  virtual std::size_t receive(std::span<Received> out) noexcept = 0;
  // Queues frames in order; returns how many were accepted (the rest are counted as refused).
  virtual std::size_t send(std::span<const Frame> frames) noexcept = 0;
  virtual BusState state() const noexcept = 0;
  virtual BusCounters counters() const noexcept = 0;
  virtual const std::string& name() const noexcept = 0;
};

// Which bus to open: `socketcan:<ifname>` (a kernel interface such as can0 or vcan0) or
// `virtual:<name>` (sawrt's shared-memory bus, for machines without AF_CAN).
struct BusConfig {
  std::string uri;
  bool fd = false;          // accept and send CAN FD frames
  std::size_t ring = 4096;  // the virtual bus's frames in flight (a power of two)
  // Receive filters (SocketCAN semantics: (received_id & mask) == (id & mask)); empty: all.
  struct Filter {
    std::uint32_t id = 0;
    std::uint32_t mask = 0;
  };
  std::vector<Filter> filters;
};

// Opens a bus before the RT cycle starts; throws std::runtime_error naming the bus and the reason
// (no such interface, AF_CAN unsupported by this kernel, a virtual bus segment that fails checks).
std::unique_ptr<Bus> open_bus(const BusConfig& config);

}  // namespace saw::can
