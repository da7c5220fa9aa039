#include "saw/canopen/emcy.hpp"

#include <algorithm>
#include <span>
#include <utility>

#include "saw/canopen/cob.hpp"

namespace saw::canopen {

std::optional<Emcy> parse_emcy(const can::Frame& f) noexcept {
  if (!canopen_data_frame(f) || f.len != 8) return std::nullopt;
  const std::uint32_t id = f.can_id();
  if (id <= cob::emcy || id > cob::emcy + max_node_id) return std::nullopt;
  Emcy e;
  e.node = static_cast<std::uint8_t>(id - cob::emcy);
  e.code = static_cast<std::uint16_t>(f.data[0] | f.data[1] << 8);
  e.error_register = f.data[2];
  std::copy_n(f.data + 3, 5, e.manufacturer.begin());
  return e;
}

can::Frame emcy_frame(const Emcy& e) noexcept {
  std::uint8_t bytes[8] = {static_cast<std::uint8_t>(e.code), static_cast<std::uint8_t>(e.code >> 8),
                           e.error_register};
  std::copy(e.manufacturer.begin(), e.manufacturer.end(), bytes + 3);
  return can::classic(cob::emcy + e.node, bytes);
}

namespace {

struct Named {
  std::uint16_t code;
  std::string_view name;
};

// CiA 301 table 21: classes by their high byte (xx00), then by their high nibble (x000).
constexpr Named classes[] = {
    {0x0000, "error reset or no error"},
    {0x1000, "generic error"},
    {0x2000, "current"},
    {0x2100, "current, device input side"},
    {0x2200, "current inside the device"},
    {0x2300, "current, device output side"},
    {0x3000, "voltage"},
    {0x3100, "mains voltage"},
    {0x3200, "voltage inside the device"},
    {0x3300, "output voltage"},
    {0x4000, "temperature"},
    {0x4100, "ambient temperature"},
    {0x4200, "device temperature"},
    {0x5000, "device hardware"},
    {0x6000, "device software"},
    {0x6100, "internal software"},
    {0x6200, "user software"},
    {0x6300, "data set"},
    {0x7000, "additional modules"},
    {0x8000, "monitoring"},
    {0x8100, "communication"},
    {0x8200, "protocol error"},
    {0x9000, "external error"},
    {0xF000, "additional functions"},
    {0xFF00, "device specific"},
};

// Specific codes: CiA 301's communication errors and CiA 402's drive errors (IEC 61800-7-201).
constexpr Named codes[] = {
    // CiA 301
    {0x8110, "CAN overrun (objects lost)"},
    {0x8120, "CAN in error passive mode"},
    {0x8130, "life guard error or heartbeat error"},
    {0x8140, "recovered from bus off"},
    {0x8150, "CAN-ID collision"},
    {0x8210, "PDO not processed due to length error"},
    {0x8220, "PDO length exceeded"},
    {0x8230, "DAM MPDO not processed, destination object not available"},
    {0x8240, "unexpected SYNC data length"},
    {0x8250, "RPDO timeout"},
    // CiA 402: current
    {0x2110, "short circuit/earth leakage (input)"},
    {0x2120, "earth leakage (input)"},
    {0x2121, "earth leakage phase L1"},
    {0x2122, "earth leakage phase L2"},
    {0x2123, "earth leakage phase L3"},
    {0x2130, "short circuit (input)"},
    {0x2131, "short circuit phases L1-L2"},
    {0x2132, "short circuit phases L2-L3"},
    {0x2133, "short circuit phases L3-L1"},
    {0x2211, "internal current no. 1"},
    {0x2212, "internal current no. 2"},
    {0x2213, "over-current in ramp function"},
    {0x2214, "over-current in the sequence"},
    {0x2220, "continuous over-current (device internal)"},
    {0x2221, "continuous over-current no. 1 (device internal)"},
    {0x2222, "continuous over-current no. 2 (device internal)"},
    {0x2230, "short circuit/earth leakage (device internal)"},
    {0x2240, "earth leakage (device internal)"},
    {0x2250, "short circuit (device internal)"},
    {0x2310, "continuous over-current (device output side)"},
    {0x2311, "continuous over-current no. 1 (device output side)"},
    {0x2312, "continuous over-current no. 2 (device output side)"},
    {0x2320, "short circuit/earth leakage (motor side)"},
    {0x2330, "earth leakage (motor side)"},
    {0x2331, "earth leakage phase U"},
    {0x2332, "earth leakage phase V"},
    {0x2333, "earth leakage phase W"},
    {0x2340, "short circuit (motor side)"},
    {0x2341, "short circuit phases U-V"},
    {0x2342, "short circuit phases V-W"},
    {0x2343, "short circuit phases W-U"},
    // voltage
    {0x3110, "mains over-voltage"},
    {0x3111, "mains over-voltage phase L1"},
    {0x3112, "mains over-voltage phase L2"},
    {0x3113, "mains over-voltage phase L3"},
    {0x3120, "mains under-voltage"},
    {0x3121, "mains under-voltage phase L1"},
    {0x3122, "mains under-voltage phase L2"},
    {0x3123, "mains under-voltage phase L3"},
    {0x3130, "phase failure"},
    {0x3131, "phase failure L1"},
    {0x3132, "phase failure L2"},
    {0x3133, "phase failure L3"},
    {0x3134, "phase sequence"},
    {0x3140, "mains frequency"},
    {0x3141, "mains frequency too great"},
    {0x3142, "mains frequency too small"},
    {0x3210, "DC link over-voltage"},
    {0x3211, "DC link over-voltage no. 1"},
    {0x3212, "DC link over-voltage no. 2"},
    {0x3220, "DC link under-voltage"},
    {0x3221, "DC link under-voltage no. 1"},
    {0x3222, "DC link under-voltage no. 2"},
    {0x3230, "load error"},
    {0x3310, "output over-voltage"},
    {0x3311, "output over-voltage phase U"},
    {0x3312, "output over-voltage phase V"},
    {0x3313, "output over-voltage phase W"},
    {0x3320, "armature circuit"},
    {0x3321, "armature circuit interrupted"},
    {0x3330, "field circuit"},
    {0x3331, "field circuit interrupted"},
    // temperature
    {0x4110, "excess ambient temperature"},
    {0x4120, "too low ambient temperature"},
    {0x4130, "temperature of the supply air"},
    {0x4140, "temperature of the air outlet"},
    {0x4210, "excess temperature of the device"},
    {0x4220, "too low temperature of the device"},
    {0x4300, "drive temperature"},
    {0x4310, "excess temperature of the drive"},
    {0x4320, "too low temperature of the drive"},
    {0x4400, "supply temperature"},
    {0x4410, "excess temperature of the supply"},
    {0x4420, "too low temperature of the supply"},
    // device hardware
    {0x5100, "supply"},
    {0x5110, "supply low voltage"},
    {0x5111, "supply low voltage U1 (±15 V)"},
    {0x5112, "supply low voltage U2 (+24 V)"},
    {0x5113, "supply low voltage U3 (+5 V)"},
    {0x5120, "supply intermediate circuit"},
    {0x5200, "control"},
    {0x5210, "measurement circuit"},
    {0x5220, "computing circuit"},
    {0x5300, "operating unit"},
    {0x5400, "power section"},
    {0x5410, "output stages"},
    {0x5420, "chopper"},
    {0x5430, "input stages"},
    {0x5440, "contacts"},
    {0x5450, "fuses"},
    {0x5451, "fuse S1 (L1)"},
    {0x5452, "fuse S2 (L2)"},
    {0x5453, "fuse S3 (L3)"},
    {0x5500, "data storage"},
    {0x5510, "working memory"},
    {0x5520, "program memory"},
    {0x5530, "non-volatile data memory"},
    // device software
    {0x6010, "software reset (watchdog)"},
    {0x6310, "loss of parameters"},
    {0x6320, "parameter error"},
    // additional modules
    {0x7100, "power"},
    {0x7110, "brake chopper"},
    {0x7111, "failure of the brake chopper"},
    {0x7112, "over-current of the brake chopper"},
    {0x7113, "protective circuit of the brake chopper"},
    {0x7120, "motor"},
    {0x7121, "motor blocked"},
    {0x7122, "motor error or commutation malfunction"},
    {0x7123, "motor tilted"},
    {0x7200, "measurement circuit"},
    {0x7300, "sensor"},
    {0x7301, "tacho fault"},
    {0x7302, "tacho wrong polarity"},
    {0x7303, "resolver 1 fault"},
    {0x7304, "resolver 2 fault"},
    {0x7305, "incremental sensor 1 fault"},
    {0x7306, "incremental sensor 2 fault"},
    {0x7307, "incremental sensor 3 fault"},
    {0x7310, "speed"},
    {0x7320, "position"},
    {0x7400, "computation circuit"},
    {0x7500, "communication"},
    {0x7510, "serial interface no. 1"},
    {0x7520, "serial interface no. 2"},
    {0x7600, "data storage (external)"},
    // monitoring
    {0x8300, "torque control"},
    {0x8311, "excess torque"},
    {0x8312, "difficult start up"},
    {0x8313, "standstill torque"},
    {0x8321, "insufficient torque"},
    {0x8331, "torque fault"},
    {0x8400, "velocity speed controller"},
    {0x8500, "position controller"},
    {0x8600, "positioning controller"},
    {0x8611, "following error"},
    {0x8612, "reference limit"},
    {0x8700, "sync controller"},
    {0x8800, "winding controller"},
    {0x8900, "process data monitoring"},
    {0x8A00, "control"},
    // additional functions
    {0xF001, "deceleration"},
    {0xF002, "sub-synchronous run"},
    {0xF003, "stroke operation"},
    {0xF004, "control"},
};

std::string_view find(std::span<const Named> table, std::uint16_t code) noexcept {
  for (const auto& n : table)
    if (n.code == code) return n.name;
  return {};
}

}  // namespace

std::string_view emcy_class_name(std::uint16_t code) noexcept {
  if (code == 0) return "error reset or no error";
  if (const auto by_byte = find(classes, static_cast<std::uint16_t>(code & 0xFF00)); !by_byte.empty())
    return by_byte;
  if (const auto by_nibble = find(classes, static_cast<std::uint16_t>(code & 0xF000)); !by_nibble.empty())
    return by_nibble;
  return "unknown error class";
}

std::string_view emcy_name(std::uint16_t code) noexcept {
  if (const auto exact = find(codes, code); !exact.empty()) return exact;
  return emcy_class_name(code);
}

EmcySeverity emcy_severity(const Emcy& e) noexcept {
  if (e.is_reset()) return EmcySeverity::reset;
  if (e.code == emcy_code::rpdo_timeout) return EmcySeverity::fault;  // whatever its register says
  if (e.error_register == 0 || e.code == 0x8110 || e.code == 0x8120) return EmcySeverity::warning;
  return EmcySeverity::fault;
}

const char* to_string(EmcySeverity s) noexcept {
  switch (s) {
    case EmcySeverity::reset:
      return "reset";
    case EmcySeverity::warning:
      return "warning";
    case EmcySeverity::fault:
      return "fault";
  }
  return "?";
}

std::string describe_error_register(std::uint8_t reg) {
  static constexpr std::pair<std::uint8_t, std::string_view> bits[] = {
      {error_register::generic, "generic"},
      {error_register::current, "current"},
      {error_register::voltage, "voltage"},
      {error_register::temperature, "temperature"},
      {error_register::communication, "communication"},
      {error_register::device_profile, "device profile specific"},
      {0x40, "reserved"},
      {error_register::manufacturer, "manufacturer specific"},
  };
  std::string out;
  for (const auto& [bit, name] : bits) {
    if ((reg & bit) == 0) continue;
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out.empty() ? "none" : out;
}

bool EmcyProducer::raise(std::uint16_t code, std::uint8_t error_register,
                         std::array<std::uint8_t, 5> manufacturer) noexcept {
  if (count_ == queue_.size()) {
    ++dropped_;
    return false;
  }
  queue_[(head_ + count_) % queue_.size()] = Emcy{node_, code, error_register, manufacturer};
  ++count_;
  return true;
}

std::optional<can::Frame> EmcyProducer::poll(TimeNs now) noexcept {
  if (count_ == 0 || (last_sent_ && now - *last_sent_ < inhibit_)) return std::nullopt;
  const Emcy e = queue_[head_];
  head_ = (head_ + 1) % queue_.size();
  --count_;
  last_sent_ = now;
  return emcy_frame(e);
}

}  // namespace saw::canopen
