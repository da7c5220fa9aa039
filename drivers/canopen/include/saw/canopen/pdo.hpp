// PDOs (CiA 301 7.2.2): mappings, their configuration as SDO writes, allocation-free pack and unpack.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "saw/can/frame.hpp"
#include "saw/canopen/od.hpp"

namespace saw::canopen {

// Receive PDOs carry values to the device (the master's setpoints), transmit PDOs from it.
enum class PdoKind : std::uint8_t { rpdo, tpdo };
std::string_view to_string(PdoKind k) noexcept;

// One mapped object: what 0x1600/0x1A00 sub 1..8 hold (index << 16 | sub-index << 8 | bits),
// plus the type its bytes are read as (from the dictionary or EDS; not on the wire).
struct PdoEntry {
  ObjectAddress address;
  std::uint8_t bits = 0;
  DataType type = DataType::unsigned8;

  static PdoEntry of(ObjectAddress a, DataType t) noexcept {
    return {a, static_cast<std::uint8_t>(8 * size_of(t)), t};
  }
  // From a mapping value: the type is `type` if given, else unsigned of the mapped width.
  static PdoEntry from_u32(std::uint32_t v, std::optional<DataType> type = std::nullopt) noexcept;
  std::uint32_t to_u32() const noexcept {
    return static_cast<std::uint32_t>(address.index) << 16 |
           static_cast<std::uint32_t>(address.subindex) << 8 | bits;
  }
  // A dummy entry maps a data type's index (0x0001..0x001F): it fills bits and carries nothing.
  bool dummy() const noexcept { return address.index < 0x20; }
};

// Transmission types (0x1400/0x1800 sub 2).
namespace transmission {
inline constexpr std::uint8_t synchronous_acyclic = 0x00;
inline constexpr std::uint8_t synchronous = 0x01;  // every SYNC; 2..240: every nth SYNC
inline constexpr std::uint8_t event_manufacturer = 0xFE;
inline constexpr std::uint8_t event_profile = 0xFF;
}  // namespace transmission

inline constexpr std::size_t max_pdo_entries = 8;
inline constexpr std::uint32_t pdo_invalid = 0x80000000;  // COB-ID bit 31: the PDO does not exist

struct PdoMapping {
  PdoKind kind = PdoKind::rpdo;
  std::uint16_t number = 1;  // 1..512: RPDO n is 0x1400 + n - 1 / 0x1600 + n - 1
  std::uint32_t cob_id = 0;  // the 11-bit identifier
  bool enabled = true;       // false: configured as not valid (COB-ID bit 31), nothing mapped
  std::uint8_t transmission = transmission::synchronous;
  std::uint16_t inhibit_time = 0;  // TPDO, in 100 µs; 0: left as the device has it
  std::uint16_t event_timer = 0;   // ms; 0: left as the device has it
  std::array<PdoEntry, max_pdo_entries> entries{};
  std::uint8_t count = 0;

  // Set-up: appends an entry; throws std::invalid_argument beyond 8 entries.
  PdoMapping& map(ObjectAddress a, DataType t);
  PdoMapping& map(const PdoEntry& e);

  std::uint16_t communication_index() const noexcept {
    return static_cast<std::uint16_t>((kind == PdoKind::rpdo ? 0x1400 : 0x1800) + number - 1);
  }
  std::uint16_t mapping_index() const noexcept {
    return static_cast<std::uint16_t>((kind == PdoKind::rpdo ? 0x1600 : 0x1A00) + number - 1);
  }
  std::size_t bits() const noexcept;
  std::size_t bytes() const noexcept { return (bits() + 7) / 8; }
};

// The predefined connection set's identifiers for PDO 1..4 of a node (TPDO1 0x180 + node,
// RPDO1 0x200 + node, ... RPDO4 0x500 + node).
std::uint32_t default_pdo_cob_id(PdoKind kind, std::uint16_t number, std::uint8_t node) noexcept;

// Set-up: throws std::invalid_argument naming what is wrong: a number outside 1..512, an
// identifier that is not 11 bits or is reserved by CiA 301, no entry or more than 64 bits,
// an entry whose width is not its type's, a string type mapped.
void check(const PdoMapping& m);

// Where an object sits among the enabled PDOs of a kind: the PDO's index among those (0: the
// first enabled), and its entry's slot; pdo < 0: not mapped.
struct MappedAt {
  int pdo = -1, slot = -1;
};
MappedAt find_mapped(std::span<const PdoMapping> pdos, PdoKind kind, ObjectAddress object) noexcept;

// One SDO write of a configuration sequence.
struct SdoWrite {
  ObjectAddress address;
  DataType type = DataType::unsigned32;
  std::uint32_t value = 0;
};

// The writes that configure `m` in a device (CiA 301 7.5.2.35's procedure): mark the PDO not
// valid (COB-ID bit 31), clear the entry count, write the entries, set the count, the
// transmission type (and inhibit time, event timer when set), then write the COB-ID without
// bit 31. A disabled mapping is only the first write. Run through an SdoClient before NMT start.
std::vector<SdoWrite> configuration_writes(const PdoMapping& m);

// Where one mapped value sits in a PDO.
struct PdoSlot {
  std::uint8_t offset = 0;  // bit offset from bit 0 of byte 0
  std::uint8_t bits = 0;
  DataType type = DataType::unsigned8;
};

// The RT side of a mapping: its identifier, its length and where each value sits. Built once
// (check() must pass), then copied freely: no allocation, no pointers.
class PdoLayout {
 public:
  explicit PdoLayout(const PdoMapping& m);  // throws as check()
  std::uint32_t cob_id() const noexcept { return cob_id_; }
  std::uint8_t bytes() const noexcept { return bytes_; }
  std::size_t size() const noexcept { return count_; }
  const PdoSlot& slot(std::size_t i) const noexcept { return slots_[i]; }

 private:
  std::uint32_t cob_id_ = 0;
  std::uint8_t bytes_ = 0;
  std::uint8_t count_ = 0;
  std::array<PdoSlot, max_pdo_entries> slots_{};
};

// Builds a PDO frame from its values (RPDOs on the master, TPDOs in the simulated drive).
// set() checks each value against its entry's type; the frame keeps the last accepted value.
class PdoPacker {
 public:
  explicit PdoPacker(const PdoMapping& m) : PdoPacker(PdoLayout(m)) {}
  explicit PdoPacker(const PdoLayout& layout) noexcept;

  Codec set_number(std::size_t slot, const Number& value) noexcept;
  template <class T>
  Codec set(std::size_t slot, T value) noexcept {
    return set_number(slot, to_number(value));
  }
  const can::Frame& frame() const noexcept { return frame_; }
  const PdoLayout& layout() const noexcept { return layout_; }

 private:
  PdoLayout layout_;
  can::Frame frame_;
};

// What a received PDO was found to be.
enum class PdoReceive : std::uint8_t {
  ok,
  other_identifier,  // not this PDO: the caller's dispatch, not an error
  not_data,          // this identifier but remote, extended, FD or malformed
  wrong_length,      // CiA 301: a PDO shorter than its mapping is not processed (EMCY 0x8210);
                     // a longer one is refused too, so a mapping mismatch is never silent
};
std::string_view to_string(PdoReceive r) noexcept;

// Reads values out of received PDOs (TPDOs on the master, RPDOs in the simulated drive). A frame
// is copied only when every check passes; get() reads the last accepted one, checking the
// value (a REAL32 must be finite, the target type must hold it).
class PdoUnpacker {
 public:
  explicit PdoUnpacker(const PdoMapping& m) : PdoUnpacker(PdoLayout(m)) {}
  explicit PdoUnpacker(const PdoLayout& layout) noexcept : layout_(layout) {}

  PdoReceive receive(const can::Frame& f) noexcept;
  Codec get_number(std::size_t slot, Number& out) const noexcept;
  template <class T>
  Codec get(std::size_t slot, T& out) const noexcept {
    Number n;
    const Codec c = get_number(slot, n);
    return c == Codec::ok ? to_value(n, out) : c;
  }
  bool has_data() const noexcept { return received_; }
  const PdoLayout& layout() const noexcept { return layout_; }

 private:
  PdoLayout layout_;
  std::uint64_t word_ = 0;  // the payload, little-endian
  bool received_ = false;
};

}  // namespace saw::canopen
