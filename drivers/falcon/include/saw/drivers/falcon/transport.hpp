// FalconTransport: the seam between the driver and a Falcon (USB, or the simulated firmware).
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "saw/drivers/falcon/packet.hpp"

namespace saw::drivers::falcon {

// What open() throws: the message says what was searched or tried and what to do about it.
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ExchangeStatus : std::uint8_t {
  ok,            // a report of `bytes` bytes arrived (the codec still checks it)
  no_answer,     // the command went out, no complete report within the bound
  usb_error,     // a transfer failed
  disconnected,  // the device is gone (unplugged)
};
const char* to_string(ExchangeStatus s) noexcept;

struct ExchangeResult {
  ExchangeStatus status = ExchangeStatus::ok;
  std::size_t bytes = 0;  // of `in` filled
  int error = 0;          // the backend's error code (libusb_error), 0 if none
};

// open() runs before the RT task starts (it may block, allocate and throw); exchange() runs in
// the cycle: it sends one command packet and returns at most one report, bounded in time.
class FalconTransport {
 public:
  virtual ~FalconTransport() = default;
  // Finds, claims and configures the device and loads its firmware. Throws TransportError.
  virtual void open() = 0;
  virtual ExchangeResult exchange(const Packet& out, Packet& in) noexcept = 0;
  virtual void close() noexcept = 0;
  // What this transport talks to, for logs ("usb bus 1 address 4", "simulated firmware").
  virtual std::string describe() const = 0;
  // How often a device that went away was opened again (ThreadedTransport's reconnect). RT-safe.
  virtual std::uint64_t reopened() const noexcept { return 0; }
  // False while a device that went away is not back (unplugged, or being found and opened again
  // by ThreadedTransport's reconnect): an enable then has nothing to enable. RT-safe.
  virtual bool connected() const noexcept { return true; }
};

}  // namespace saw::drivers::falcon
