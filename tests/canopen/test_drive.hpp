// A minimal in-process CiA 402 drive for the master's tests: a LocalDictionary served by an
// SdoServer, an NmtNode, the drive-side state machine, PDOs built from its own mapping objects,
// heartbeat and EMCY producers, a heartbeat consumer (0x1016:01, with CiA 402's abort connection
// option 0x6007 on expiry), RPDO deadline monitoring (each RPDO's event timer, 0x1400+k:05: EMCY
// 0x8250 and 0x6007 on expiry), and a first-order motion. Stepped by the test; allocation-free
// once operational (so it may run inside a guarded cycle).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "ring_bus.hpp"
#include "saw/canopen/cia402_drive.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sdo_server.hpp"

namespace saw::canopen::test {

struct TestDriveConfig {
  std::uint8_t node = 1;
  double torque_gain = 2000;  // CST: counts/s² per ‰ of rated torque
  double damping = 5;         // CST: 1/s
  std::int32_t initial_position = 0;
  double csp_max_step = 1e12;  // CSP: counts per SYNC the drive can move (a drive that lags)
};

class TestDrive {
 public:
  TestDrive(RingNetwork& network, TestDriveConfig config);

  // One step at `now`: frames in (NMT, SDO, RPDOs, SYNC), then on a SYNC the state machine,
  // the motion and the TPDOs; heartbeat, boot-up, EMCY and SDO responses out.
  void step(TimeNs now) noexcept;

  // A fault condition (the drive goes to fault) with an EMCY of `code`; cleared, it may be reset.
  void raise_fault(std::uint16_t code) noexcept;
  void clear_fault() noexcept;
  // A power cycle: what the master configures back to the defaults (PDOs not valid, no
  // heartbeat, consumer or mode), the state machine to its start, and a boot-up message.
  void reboot() noexcept;
  // An EMCY that is a warning: the drive goes on as it was.
  void warn(std::uint16_t code, std::uint8_t error_register) noexcept {
    (void)emcy_.raise(code, error_register);
  }
  // The drive changes its own NMT state (its error behaviour, a local command): its heartbeat says so.
  void set_nmt(NmtCommand command) noexcept { (void)nmt_.on_frame(nmt_frame(command, config_.node)); }
  // A silent drive sends nothing at all (unplugged); it still listens.
  void set_silent(bool silent) noexcept { silent_ = silent; }
  // Only its heartbeat stops (its PDOs go on).
  void set_heartbeat_silent(bool silent) noexcept { heartbeat_silent_ = silent; }

  std::uint8_t node() const noexcept { return config_.node; }
  NmtState nmt_state() const noexcept { return nmt_.state(); }
  cia402::State state() const noexcept { return drive_.state(); }
  cia402::Mode mode() const noexcept { return drive_.mode_display(); }
  std::uint16_t controlword() const noexcept { return controlword_; }
  double position() const noexcept { return position_; }
  double velocity() const noexcept { return velocity_; }
  std::int32_t target_position() const noexcept;
  std::int16_t target_torque() const noexcept;
  std::int32_t target_velocity() const noexcept;
  std::uint64_t syncs() const noexcept { return syncs_; }
  std::uint64_t heartbeat_events() const noexcept { return heartbeat_events_; }
  std::uint64_t rpdo_timeouts() const noexcept { return rpdo_timeouts_; }
  // Every SDO write the dictionary accepted, in order (for the start-up test).
  struct Write {
    ObjectAddress address;
    std::uint32_t value;
  };
  const std::vector<Write>& writes() const noexcept { return writes_; }
  std::uint64_t rpdo_frames() const noexcept { return rpdo_frames_; }
  LocalDictionary& dictionary() noexcept { return dictionary_; }
  RingPort& port() noexcept { return port_; }

 private:
  void build_pdos();
  void on_sync(TimeNs now) noexcept;
  void watch_master(TimeNs now) noexcept;
  void watch_rpdos(TimeNs now) noexcept;
  void abort_connection(std::uint16_t code) noexcept;
  void send(const can::Frame& f) noexcept;

  TestDriveConfig config_;
  RingPort& port_;
  LocalDictionary dictionary_;
  std::unique_ptr<SdoServer> server_;
  NmtNode nmt_;
  cia402::Drive drive_;
  HeartbeatProducer heartbeat_;
  EmcyProducer emcy_;
  std::vector<PdoUnpacker> rpdos_;
  std::vector<std::vector<ObjectAddress>> rpdo_objects_;
  // RPDO deadline monitoring, per RPDO: its event timer (0: off), its last reception in
  // operational (none: not watched yet), whether this silence was reported.
  std::vector<TimeNs> rpdo_deadlines_;
  std::vector<std::optional<TimeNs>> rpdo_seen_;
  std::vector<bool> rpdo_fired_;
  std::vector<PdoPacker> tpdos_;
  std::vector<std::vector<ObjectAddress>> tpdo_objects_;
  std::vector<Write> writes_;
  std::uint16_t heartbeat_ms_ = 0;
  bool fault_ = false, silent_ = false, heartbeat_silent_ = false;
  std::uint16_t controlword_ = 0;
  double position_ = 0, velocity_ = 0;
  TimeNs last_sync_ = 0;
  std::uint64_t syncs_ = 0, rpdo_frames_ = 0, heartbeat_events_ = 0, rpdo_timeouts_ = 0;
  // The heartbeat consumer, from 0x1016:01.
  std::uint32_t consumer_entry_ = 0;
  std::uint8_t consumer_node_ = 0;
  TimeNs consumer_time_ = 0;
  std::optional<TimeNs> consumer_seen_;
  bool consumer_fired_ = false;
};

}  // namespace saw::canopen::test
