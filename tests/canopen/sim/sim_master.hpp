// A 1 kHz CiA 402 master for the bench: SYNC, then the RPDOs sim_drive.eds maps, the controller on TPDO1's
// statusword.
#pragma once

#include <cstdint>

#include "saw/canopen/cia402_controller.hpp"
#include "saw/canopen/eds.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sim/drive_dictionary.hpp"
#include "saw/canopen/sync.hpp"
#include "sim_bench.hpp"

namespace saw::canopen::sim::testing {

// The mappings come from the EDS through the protocol library, as a real master would read
// them. RPDO2 (controlword, target velocity) and RPDO3 (controlword, target torque) are disabled
// in the file; enable_rpdos() makes them valid by SDO in pre-operational.
class Master {
 public:
  explicit Master(Bench& bench)
      : b_(bench),
        mappings_(eds_pdo_mappings(load_drive_eds(""), bench.node)),
        rpdo1_(enabled(PdoKind::rpdo, 1)),
        rpdo2_(enabled(PdoKind::rpdo, 2)),
        rpdo3_(enabled(PdoKind::rpdo, 3)),
        tpdo1_(enabled(PdoKind::tpdo, 1)),
        tpdo2_(enabled(PdoKind::tpdo, 2)) {}

  // In pre-operational: RPDO2 and RPDO3 made valid, then the mode, then NMT start; from then on
  // the master's cycle runs every millisecond.
  void start(cia402::Mode mode) {
    for (const std::uint16_t n : {std::uint16_t{2}, std::uint16_t{3}})
      b_.write({static_cast<std::uint16_t>(0x1400 + n - 1), 1}, DataType::unsigned32,
               default_pdo_cob_id(PdoKind::rpdo, n, b_.node));
    b_.write(cia402::object::modes_of_operation, DataType::integer8, static_cast<std::int8_t>(mode));
    b_.nmt(NmtCommand::start);
    b_.each_tick = [this] { cycle(); };
  }
  void enable() { controller.set_target(cia402::Target::operation_enabled, b_.now); }
  // Runs until the drive is where the controller was told to take it.
  bool reach(cia402::Target t, TimeNs timeout = 200 * ms) {
    controller.set_target(t, b_.now);
    last.progress = cia402::Progress::working;  // until the controller's next cycle says otherwise
    return b_.run_until([&] { return last.progress == cia402::Progress::reached; }, timeout);
  }

  cia402::Controller controller;
  cia402::ControllerOutput last;
  std::int32_t target_position = 0;
  std::int32_t target_velocity = 0;
  std::int16_t target_torque = 0;
  std::uint16_t statusword = 0;
  std::int32_t position = 0;  // TPDO1
  std::int32_t velocity = 0;  // TPDO2
  std::int16_t torque = 0;    // TPDO1
  std::int8_t mode_display = 0;
  std::function<void()> before_send;  // sets the targets for this cycle

 private:
  PdoMapping enabled(PdoKind kind, std::uint16_t number) const {
    for (PdoMapping m : mappings_) {
      if (m.kind != kind || m.number != number) continue;
      m.enabled = true;
      m.cob_id = default_pdo_cob_id(kind, number, b_.node);
      return m;
    }
    throw std::invalid_argument("no such PDO in sim_drive.eds");
  }

  void cycle() {
    if (b_.now % ms != 0) return;
    for (; seen_ < b_.seen.size(); ++seen_) {
      const can::Frame& f = b_.seen[seen_].frame;
      if (tpdo1_.receive(f) == PdoReceive::ok) {
        (void)tpdo1_.get(0, statusword);
        (void)tpdo1_.get(1, position);
        (void)tpdo1_.get(2, torque);
      } else if (tpdo2_.receive(f) == PdoReceive::ok) {
        (void)tpdo2_.get(1, velocity);
        (void)tpdo2_.get(2, mode_display);
      }
    }
    last = controller.update(statusword, b_.now);
    if (before_send) before_send();
    b_.send(sync_frame());
    (void)rpdo1_.set(0, last.controlword);
    (void)rpdo1_.set(1, target_position);
    (void)rpdo2_.set(0, last.controlword);
    (void)rpdo2_.set(1, target_velocity);
    (void)rpdo3_.set(0, last.controlword);
    (void)rpdo3_.set(1, target_torque);
    b_.send(rpdo1_.frame());
    b_.send(rpdo2_.frame());
    b_.send(rpdo3_.frame());
  }

  Bench& b_;
  std::vector<PdoMapping> mappings_;
  PdoPacker rpdo1_, rpdo2_, rpdo3_;
  PdoUnpacker tpdo1_, tpdo2_;
  std::size_t seen_ = 0;
};

}  // namespace saw::canopen::sim::testing
