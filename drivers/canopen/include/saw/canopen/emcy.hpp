// Emergency messages (CiA 301 7.2.7): decoding, names for CiA 301/402 error codes, a producer.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "saw/can/frame.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

struct Emcy {
  std::uint8_t node = 0;
  std::uint16_t code = 0;           // 0x0000: error reset (the node has no error left)
  std::uint8_t error_register = 0;  // 0x1001
  std::array<std::uint8_t, 5> manufacturer{};
  bool is_reset() const noexcept { return code == 0; }
};

// An EMCY frame, checked: identifier 0x081..0x0FF (0x080 is SYNC), exactly 8 bytes.
std::optional<Emcy> parse_emcy(const can::Frame& f) noexcept;
can::Frame emcy_frame(const Emcy& e) noexcept;

// The class of an error code (CiA 301 table 21), e.g. "current, device output side" for 0x23xx.
std::string_view emcy_class_name(std::uint16_t code) noexcept;
// The most specific standard name known: 0x2310 is "continuous over-current (device output
// side)", 0x8611 "following error"; a code not in the tables gets its class's name.
std::string_view emcy_name(std::uint16_t code) noexcept;

// Codes the master acts on by themselves.
namespace emcy_code {
// CiA 301: an RPDO's deadline (its event timer, 0x1400 + n - 1 sub 05h) passed without an RPDO:
// the node says this master's RPDOs stopped coming, and has reacted (a CiA 402 drive: 0x6007).
inline constexpr std::uint16_t rpdo_timeout = 0x8250;
}  // namespace emcy_code

// What an EMCY means for a component that has nothing else to judge it by (an I/O node has no
// CiA 402 statusword that says whether the node faulted).
enum class EmcySeverity : std::uint8_t {
  reset,    // code 0x0000: error reset or no error (CiA 301 7.2.7.1)
  warning,  // the node goes on: its error register is 0, or a CAN error-passive or overrun
  fault,    // any other code with a non-zero error register
};
// Code 0x0000 is the reset. A non-zero error register is a fault except for 0x8110 (CAN overrun:
// frames lost, the node still communicates; a lasting loss shows as stale TPDOs or a lost
// heartbeat) and 0x8120 (CAN error passive: still on the bus). 0x8130 (heartbeat or life guard
// error: the node lost the master and took its error values), 0x8140 (recovered from bus off:
// it was off the bus), 0x8150 (CAN-ID collision), 0x8250 (RPDO timeout: the node stopped getting
// the master's RPDOs and took its error values) and 0x8100 (generic) mean lost communication:
// faults.
EmcySeverity emcy_severity(const Emcy& e) noexcept;
const char* to_string(EmcySeverity s) noexcept;  // "reset", "warning", "fault"

// Bits of the error register (0x1001).
namespace error_register {
inline constexpr std::uint8_t generic = 0x01;
inline constexpr std::uint8_t current = 0x02;
inline constexpr std::uint8_t voltage = 0x04;
inline constexpr std::uint8_t temperature = 0x08;
inline constexpr std::uint8_t communication = 0x10;
inline constexpr std::uint8_t device_profile = 0x20;
inline constexpr std::uint8_t manufacturer = 0x80;
}  // namespace error_register
// "generic, current" (not for RT paths: it allocates).
std::string describe_error_register(std::uint8_t reg);

// Sends EMCY messages no closer together than the inhibit time (0x1015, CiA 301: in 100 µs),
// queueing the rest. Fixed memory: raise() and poll() neither allocate nor throw.
class EmcyProducer {
 public:
  static constexpr std::size_t queue_capacity = 8;

  EmcyProducer(std::uint8_t node, TimeNs inhibit = 0) noexcept : node_(node), inhibit_(inhibit) {}
  // Queues an emergency; false when the queue is full (counted in dropped()).
  bool raise(std::uint16_t code, std::uint8_t error_register,
             std::array<std::uint8_t, 5> manufacturer = {}) noexcept;
  // Queues the error reset message (code 0) with what is left in the error register.
  bool clear(std::uint8_t error_register = 0) noexcept { return raise(0x0000, error_register); }
  std::optional<can::Frame> poll(TimeNs now) noexcept;
  std::uint64_t dropped() const noexcept { return dropped_; }

 private:
  std::uint8_t node_;
  TimeNs inhibit_;
  std::optional<TimeNs> last_sent_;
  std::array<Emcy, queue_capacity> queue_{};
  std::size_t head_ = 0, count_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace saw::canopen
