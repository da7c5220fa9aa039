// The Falcon firmware's 16-byte framed, nibble-coded packets (host → device and device → host).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace saw::drivers::falcon {

// One packet on the wire: '<', 14 payload bytes, '>'. Every payload byte is 'A' + a value;
// the firmware answers each packet it receives with exactly one packet.
inline constexpr std::size_t packet_size = 16;
using Packet = std::array<std::uint8_t, packet_size>;

inline constexpr std::uint8_t packet_start = '<';
inline constexpr std::uint8_t packet_end = '>';
inline constexpr std::uint8_t nibble_base = 'A';  // 0x41: payload byte = 'A' + value

// Bits of the control nibble the host sends (byte 13): libnifalcon's enum (FalconFirmware.h), not
// the stale comment in its FalconFirmwareNovintSDK.h (red 0x2, green 0x4, blue 0x8, homing 0x10).
namespace control {
// Homing mode: set in every packet for the device to stay homed; the homed status bits mean
// something only while it is set.
inline constexpr std::uint8_t homing = 0x01;
inline constexpr std::uint8_t led_green = 0x02;
inline constexpr std::uint8_t led_blue = 0x04;
inline constexpr std::uint8_t led_red = 0x08;
inline constexpr std::uint8_t mask = 0x0f;
}  // namespace control

// Bits of the status byte the device sends (byte 13, 'A' + 7 bits).
namespace status {
inline constexpr std::uint8_t button_right = 0x01;
inline constexpr std::uint8_t button_forward = 0x02;
inline constexpr std::uint8_t button_center = 0x04;
inline constexpr std::uint8_t button_left = 0x08;
inline constexpr std::uint8_t buttons = 0x0f;
inline constexpr std::uint8_t homed_shift = 4;  // bits 4..6: axes 0..2 homed (homing mode on)
inline constexpr std::uint8_t homed_all = 0x70;
}  // namespace status

// Host → device: three motor commands (signed DAC counts) and the LED/homing nibble.
struct MotorCommand {
  std::array<std::int16_t, 3> dac{};
  std::uint8_t control = 0;  // control:: bits
  friend bool operator==(const MotorCommand&, const MotorCommand&) = default;
};

// Device → host: three encoder counts, the grip buttons and the homing status.
struct DeviceReport {
  std::array<std::int16_t, 3> encoder{};
  std::uint8_t status = 0;  // status:: bits
  bool homed(int axis) const noexcept { return (status >> (status::homed_shift + axis)) & 1u; }
  std::uint8_t buttons() const noexcept { return status & status::buttons; }
  friend bool operator==(const DeviceReport&, const DeviceReport&) = default;
};

// Why a frame was refused (the first check that failed).
enum class FrameError : std::uint8_t {
  none,
  short_frame,  // fewer than packet_size bytes
  bad_start,    // byte 0 is not '<'
  bad_end,      // byte 15 is not '>'
  bad_nibble,   // a value byte outside 'A'..'P'
  bad_status,   // the status byte outside 'A' + 0..0x7f
};
const char* to_string(FrameError e) noexcept;

// Host side.
Packet encode_command(const MotorCommand& c) noexcept;
// Returns none and fills `out` only when every byte checks; `out` is untouched otherwise. Byte 14
// is not checked: its meaning is unknown (libnifalcon ignores it), and refusing on it could
// refuse every report of a real Falcon.
FrameError decode_report(std::span<const std::uint8_t> frame, DeviceReport& out) noexcept;

// Device side (the simulated firmware speaks the same format).
Packet encode_report(const DeviceReport& r) noexcept;
FrameError decode_command(std::span<const std::uint8_t> frame, MotorCommand& out) noexcept;

}  // namespace saw::drivers::falcon
