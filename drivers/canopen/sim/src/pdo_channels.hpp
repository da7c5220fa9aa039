// The simulated drive's PDOs as its dictionary configures them: checked remapping, SYNC and event timing.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "saw/can/frame.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/clock.hpp"

namespace saw::canopen::sim {

// The device end of CiA 301's PDOs. The configuration lives in the dictionary (0x1400.., 0x1600..,
// 0x1800.., 0x1A00..); check_write() is the dictionary's write hook for those objects, so a
// master remaps by SDO exactly as on a real device (and gets the same aborts), and written()
// rebuilds the PDO once the value is stored. Traffic (on_frame, on_sync, poll) neither allocates
// nor throws; rebuilding does both, and happens only on configuration writes and resets.
class PdoChannels {
 public:
  static constexpr std::uint16_t max_pdos = 8;  // per direction: RPDO 1..8, TPDO 1..8

  explicit PdoChannels(LocalDictionary& dictionary) noexcept : dictionary_(dictionary) {}

  static bool is_pdo_parameter(std::uint16_t index) noexcept;
  // Whether `value` (the numeric value being written to a PDO parameter) may be stored: the
  // abort CANopenNode gives where CiA 301 leaves the code open, none if it may.
  SdoAbort check_write(ObjectAddress address, std::uint64_t value) const noexcept;
  // A PDO parameter was stored: its PDO is rebuilt from the dictionary.
  void written(ObjectAddress address) noexcept;
  // Every PDO from the dictionary (start-up and resets); forgets received data.
  void rebuild_all() noexcept;
  // Entering operational: event-driven TPDOs go out once and their timers start.
  void start(TimeNs now) noexcept;

  enum class Receive : std::uint8_t {
    not_rpdo,      // no enabled RPDO has this identifier
    applied,       // event-driven RPDO: its values are in the dictionary
    latched,       // synchronous RPDO: its values go to the dictionary at the next SYNC
    wrong_length,  // CiA 301: not processed (the drive raises EMCY 0x8210)
    refused,       // right identifier but not a classic data frame, or a value out of range
  };
  // A checked frame (canopen_data_frame) in operational.
  Receive on_frame(const can::Frame& f) noexcept;
  // SYNC in operational: latched RPDOs take effect; synchronous TPDOs sample their values now
  // and are sent every `transmission`-th SYNC (1..240), type 0 ones only when they changed.
  void on_sync(TimeNs now) noexcept;
  // The next TPDO to send: after a SYNC, or event-driven (254/255) on a change once the
  // inhibit time (0x1800 sub 3, 100 µs) has passed, or when the event timer (sub 5, ms) runs out.
  std::optional<can::Frame> poll(TimeNs now) noexcept;

  // RPDO deadline monitoring (CiA 301: an RPDO's event timer, 0x1400 + n - 1 sub 05h in ms, is a
  // deadline on the receiving side). Called each step in operational, after that step's frames:
  // the number of an RPDO that came at least once since start() and not within its deadline since,
  // once per silence (a reception re-arms it); 0 when none (call again for the next one).
  std::uint16_t expired_rpdo(TimeNs now) noexcept;

  // PDOs whose configuration could not be built (an EDS with an invalid mapping): not used.
  std::uint64_t invalid_configurations() const noexcept { return invalid_; }
  std::uint64_t refused_values() const noexcept { return refused_values_; }
  bool rpdo_enabled(std::uint16_t number) const noexcept;  // 1-based
  bool tpdo_enabled(std::uint16_t number) const noexcept;

 private:
  struct Rpdo {
    bool enabled = false;
    bool synchronous = true;
    bool pending = false;
    std::optional<PdoUnpacker> unpacker;
    TimeNs deadline = 0;         // its event timer; 0: not watched
    bool fresh = false;          // received since the last expired_rpdo()
    std::optional<TimeNs> seen;  // its last reception, as expired_rpdo() saw it
    bool expired = false;        // this silence was reported
    std::array<ObjectAddress, max_pdo_entries> objects{};
  };
  struct Tpdo {
    bool enabled = false;
    std::uint8_t transmission = 1;
    TimeNs inhibit = 0;
    TimeNs event_timer = 0;
    std::optional<PdoPacker> packer;
    std::array<const Entry*, max_pdo_entries> sources{};
    std::uint8_t syncs = 0;
    bool due = false;
    bool sent = false;
    TimeNs last_sent = 0;
    can::Frame last_frame;
  };

  // The mapping the dictionary holds for PDO `number` (1-based), with the COB-ID and entries;
  // nullopt if the PDO's parameters are not in the dictionary.
  std::optional<PdoMapping> mapping(PdoKind kind, std::uint16_t number) const noexcept;
  SdoAbort check_entry(PdoKind kind, std::uint32_t value) const noexcept;
  void rebuild(PdoKind kind, std::uint16_t number) noexcept;
  void apply(Rpdo& r) noexcept;
  bool pack(Tpdo& t) noexcept;  // true when the packed frame differs from the last one sent
  std::uint32_t u32(ObjectAddress a, std::uint32_t fallback) const noexcept;

  LocalDictionary& dictionary_;
  std::array<Rpdo, max_pdos> rpdos_{};
  std::array<Tpdo, max_pdos> tpdos_{};
  std::uint64_t invalid_ = 0;
  std::uint64_t refused_values_ = 0;
};

// Writes a number into a dictionary entry through its type and limits (the device's own access).
Codec set_number(LocalDictionary& d, ObjectAddress a, const Number& n) noexcept;
// Reads an entry's number; invalid for a missing or non-numeric one.
Codec get_number(const Entry& e, Number& out) noexcept;

}  // namespace saw::canopen::sim
