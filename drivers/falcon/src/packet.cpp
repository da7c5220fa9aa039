#include "saw/drivers/falcon/packet.hpp"

namespace saw::drivers::falcon {
namespace {

constexpr std::uint8_t max_nibble = nibble_base + 0x0f;  // 'P'

// Little-endian nibbles: the word's lowest nibble first (the firmware's order).
void put_word(Packet& p, std::size_t at, std::int16_t v) noexcept {
  const auto u = static_cast<std::uint16_t>(v);
  for (std::size_t k = 0; k < 4; ++k)
    p[at + k] = static_cast<std::uint8_t>(nibble_base + ((u >> (4 * k)) & 0x0f));
}

std::int16_t get_word(std::span<const std::uint8_t> f, std::size_t at) noexcept {
  std::uint16_t u = 0;
  for (std::size_t k = 0; k < 4; ++k)
    u = static_cast<std::uint16_t>(u | ((f[at + k] - nibble_base) & 0x0f) << (4 * k));
  return static_cast<std::int16_t>(u);
}

bool is_nibble(std::uint8_t b) noexcept { return b >= nibble_base && b <= max_nibble; }

// The checks both directions share: size, framing and the motor/encoder nibbles. Not byte 14:
// "unknown" in libnifalcon, which never looks at it.
FrameError check_frame(std::span<const std::uint8_t> f) noexcept {
  if (f.size() < packet_size) return FrameError::short_frame;
  if (f[0] != packet_start) return FrameError::bad_start;
  if (f[15] != packet_end) return FrameError::bad_end;
  for (std::size_t i = 1; i <= 12; ++i)
    if (!is_nibble(f[i])) return FrameError::bad_nibble;
  return FrameError::none;
}

Packet frame() noexcept {
  Packet p{};
  p.fill(nibble_base);
  p[0] = packet_start;
  p[15] = packet_end;
  return p;
}

}  // namespace

const char* to_string(FrameError e) noexcept {
  switch (e) {
    case FrameError::none:
      return "ok";
    case FrameError::short_frame:
      return "short frame";
    case FrameError::bad_start:
      return "bad start byte";
    case FrameError::bad_end:
      return "bad end byte";
    case FrameError::bad_nibble:
      return "value byte outside 'A'..'P'";
    case FrameError::bad_status:
      return "status byte out of range";
  }
  return "?";
}

Packet encode_command(const MotorCommand& c) noexcept {
  Packet p = frame();
  for (std::size_t i = 0; i < 3; ++i) put_word(p, 1 + 4 * i, c.dac[i]);
  p[13] = static_cast<std::uint8_t>(nibble_base + (c.control & control::mask));
  return p;
}

FrameError decode_report(std::span<const std::uint8_t> f, DeviceReport& out) noexcept {
  if (const FrameError e = check_frame(f); e != FrameError::none) return e;
  if (f[13] < nibble_base || f[13] > nibble_base + 0x7f) return FrameError::bad_status;
  for (std::size_t i = 0; i < 3; ++i) out.encoder[i] = get_word(f, 1 + 4 * i);
  out.status = static_cast<std::uint8_t>(f[13] - nibble_base);
  return FrameError::none;
}

Packet encode_report(const DeviceReport& r) noexcept {
  Packet p = frame();
  for (std::size_t i = 0; i < 3; ++i) put_word(p, 1 + 4 * i, r.encoder[i]);
  p[13] = static_cast<std::uint8_t>(nibble_base + (r.status & 0x7f));
  return p;
}

FrameError decode_command(std::span<const std::uint8_t> f, MotorCommand& out) noexcept {
  if (const FrameError e = check_frame(f); e != FrameError::none) return e;
  if (!is_nibble(f[13])) return FrameError::bad_status;
  for (std::size_t i = 0; i < 3; ++i) out.dac[i] = get_word(f, 1 + 4 * i);
  out.control = static_cast<std::uint8_t>(f[13] - nibble_base);
  return FrameError::none;
}

}  // namespace saw::drivers::falcon
