// One simulated CiA 402 servo drive as a CANopen slave: NMT, SDO, heartbeat, EMCY, PDOs, the 402 machine, a
// motor.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "saw/can/bus.hpp"
#include "saw/canopen/cia402_drive.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/sdo_server.hpp"
#include "saw/canopen/sim/fault.hpp"
#include "saw/canopen/sim/motor_model.hpp"
#include "saw/clock.hpp"

namespace saw::canopen::sim {

class PdoChannels;

struct SimDriveConfig {
  std::uint8_t node = 1;
  std::string eds;  // EDS or DCF; empty: the built-in sim_drive.eds
  MotorParameters motor;
  std::optional<std::uint16_t> heartbeat_ms;  // the power-on 0x1017 (ms) instead of the file's
};

// Each only grows.
struct SimDriveCounters {
  std::uint64_t frames_in = 0;         // taken from the bus, everyone's traffic
  std::uint64_t frames_out = 0;        // accepted by the bus
  std::uint64_t not_canopen = 0;       // failed canopen_data_frame() (FD, extended, remote): ignored
  std::uint64_t send_refused = 0;      // the bus did not take them
  std::uint64_t lost_bus_off = 0;      // received or produced while bus-off
  std::uint64_t nmt = 0;               // NMT commands addressed to this node
  std::uint64_t sync = 0;              // SYNCs acted on (operational)
  std::uint64_t sdo_requests = 0;      // SDO requests served (pre-operational, operational)
  std::uint64_t rpdos = 0;             // RPDOs accepted
  std::uint64_t tpdos = 0;             // TPDOs produced
  std::uint64_t emcys = 0;             // EMCYs produced (error and error reset)
  std::uint64_t heartbeats = 0;        // heartbeats produced (boot-up not included)
  std::uint64_t heartbeat_events = 0;  // the watched node (0x1016:01, the master) went silent
  std::uint64_t rpdo_timeouts = 0;     // an RPDO missed its deadline (its event timer, 0x1400+k:05)
  std::uint64_t pdo_length_errors = 0;
};

// The drive's cycle is step(now): it advances the motor to `now`, reads every frame the bus has
// (each one checked with canopen_data_frame() first), acts on them as CiA 301 allows in the
// node's NMT state (stopped: NMT only; pre-operational: SDO too; operational: SYNC and PDOs
// too), runs the CiA 402 state machine on the controlword (0x6040), computes the servo command
// for the mode shown in 0x6061 (CSP, CSV, CST), and sends what is due. Time is only what the
// caller passes: a test steps it deterministically, saw-can-sim from a real-time loop.
//
// Everything lives in the object dictionary, as on a real drive: RPDOs and SDO writes land in
// it; TPDOs, SDO reads and the application read it. So a master may remap PDOs by SDO in
// pre-operational (0x1400.., 0x1600.., 0x1800.., 0x1A00.., with CiA 301's procedure and
// aborts), set 0x1017, write 0x6060 (shown in 0x6061 once the drive's cycle has run), etc.
//
// After construction, step(), inject() and clear() neither allocate nor throw, except that a
// PDO configuration write or an NMT reset rebuilds PDOs (allocation, at configuration time).
class SimDrive {
 public:
  // Throws saw::deploy::ConfigError for an EDS problem, std::invalid_argument for the rest.
  SimDrive(const SimDriveConfig& config, can::Bus& bus);
  ~SimDrive();
  SimDrive(const SimDrive&) = delete;
  SimDrive& operator=(const SimDrive&) = delete;

  // The first step is power-on: the boot-up message goes out and the node is pre-operational.
  void step(TimeNs now) noexcept;

  // Takes effect at the next step. Events (over-current, following error) raise their EMCY and
  // put the drive in fault; lasting faults hold until `fault.duration` ends or clear(). A bus-off
  // is also an abort-connection event for an enabled drive (0x6007: fault, disable, quick stop).
  void inject(const Fault& fault) noexcept;
  void clear(FaultKind kind) noexcept;
  void clear_all() noexcept;
  std::uint8_t active_faults() const noexcept;  // fault_bit() of each lasting fault in force

  std::uint8_t node() const noexcept { return node_; }
  NmtState nmt_state() const noexcept { return nmt_.state(); }
  cia402::State drive_state() const noexcept { return drive_.state(); }
  cia402::Mode mode_display() const noexcept { return drive_.mode_display(); }
  std::uint16_t statusword() const noexcept { return statusword_; }
  std::uint16_t error_code() const noexcept { return error_code_; }
  std::int32_t position_counts() const noexcept { return position_counts_; }  // 0x6064
  double following_error_counts() const noexcept { return following_error_; }
  const MotorModel& motor() const noexcept { return motor_; }
  const LocalDictionary& dictionary() const noexcept { return dictionary_; }
  const SimDriveCounters& counters() const noexcept { return counters_; }
  bool bus_off() const noexcept { return until_[index(FaultKind::bus_off)].has_value(); }

 private:
  // The dictionary as the SDO server sees it: injected aborts first, then the dictionary (with
  // its write hook), then what a stored write changes in the drive.
  class SdoView final : public ObjectDictionary {
   public:
    explicit SdoView(SimDrive& drive) noexcept : drive_(drive) {}
    SdoAbort check_download(ObjectAddress address, std::optional<std::size_t> size) noexcept override;
    SdoAbort read(ObjectAddress address, std::span<std::uint8_t> out, std::size_t& size) noexcept override;
    SdoAbort write(ObjectAddress address, std::span<const std::uint8_t> data,
                   bool size_indicated) noexcept override;

   private:
    SimDrive& drive_;
  };

  static constexpr std::size_t index(FaultKind k) noexcept { return static_cast<std::size_t>(k) - 1; }

  // Configuration and resets.
  void boot() noexcept;
  void reset(NmtReset what) noexcept;
  void restore(std::uint16_t first, std::uint16_t last) noexcept;
  void refresh_identifiers() noexcept;
  void refresh_producers() noexcept;
  void end_fault(FaultKind kind) noexcept;
  void abort_connection(std::uint16_t code) noexcept;
  void refresh_consumer() noexcept;
  void watch_consumer() noexcept;
  void watch_rpdos() noexcept;
  SdoAbort check_write(ObjectAddress address, std::span<const std::uint8_t> data) const noexcept;
  void written(ObjectAddress address) noexcept;
  SdoAbort injected_abort(ObjectAddress address) const noexcept;

  // The cycle.
  void receive_all() noexcept;
  void dispatch(const can::Frame& f) noexcept;
  void on_sync() noexcept;
  void update_faults() noexcept;
  void publish_actuals() noexcept;
  void control() noexcept;
  void queue(const can::Frame& f) noexcept;
  void flush() noexcept;
  void produce() noexcept;

  // Errors and EMCY.
  void raise(std::uint16_t code, std::uint8_t register_bits) noexcept;
  void clear_errors() noexcept;
  void push_history(std::uint16_t code) noexcept;

  template <class T>
  T get_or(ObjectAddress a, T fallback) const noexcept {
    T v{};
    return dictionary_.get(a, v) == Codec::ok ? v : fallback;
  }

  std::uint8_t node_;
  can::Bus& bus_;
  LocalDictionary dictionary_;
  LocalDictionary defaults_;  // the power-on values, for the NMT resets
  SdoView view_;
  std::optional<SdoServer> sdo_;
  NmtNode nmt_;
  HeartbeatProducer heartbeat_;
  EmcyProducer emcy_;
  std::unique_ptr<PdoChannels> pdos_;  // behind a pointer: pdo_channels.hpp is private
  cia402::DriveConfig drive_config_;
  cia402::Drive drive_;
  MotorModel motor_;

  TimeNs now_ = 0;
  std::optional<TimeNs> last_step_;
  bool booted_ = false;
  SimDriveCounters counters_;

  // Communication objects' values, kept where the cycle reads them.
  std::uint32_t sync_id_ = 0x080;
  std::uint32_t emcy_id_ = 0;
  bool emcy_enabled_ = true;

  // Motion: the interval's servo command and the CSP reference it comes from.
  ServoCommand command_;
  ServoCommand::Loop loop_ = ServoCommand::Loop::off;
  double counts_per_revolution_ = 4096;
  double gear_ratio_ = 1;
  double reference_ = 0;     // counts, unwrapped: the CSP position reference at reference_time_
  double feed_forward_ = 0;  // counts/s
  TimeNs reference_time_ = 0;
  TimeNs sync_interval_ = 0;  // between the last two SYNCs
  std::optional<TimeNs> last_sync_;
  std::optional<double> last_sync_reference_;
  bool limit_active_ = false;
  double following_error_ = 0;  // counts
  std::optional<TimeNs> following_error_since_;
  std::int8_t requested_mode_ = 0;
  std::uint16_t statusword_ = 0;
  std::int32_t position_counts_ = 0;

  // Errors.
  std::uint16_t error_code_ = 0;
  std::uint8_t error_register_ = 0;
  bool fault_input_ = false;                     // a fault appeared this cycle: the 402 machine's fault input
  bool pdo_length_error_ = false;                // EMCY 0x8210 sent, until an RPDO of the right length
  bool bus_off_fault_ = false;                   // the bus-off faulted the drive (0x6007 = 1)
  std::optional<std::uint16_t> forced_command_;  // 0x6007 = 2, 3: the drive's own command, once

  // The heartbeat consumer (0x1016:01): the node it watches (the master) and for how long.
  std::uint8_t watched_node_ = 0;
  TimeNs consumer_time_ = 0;
  std::optional<TimeNs> watched_seen_;  // its last heartbeat; monitoring starts with the first
  bool consumer_fired_ = false;

  // Faults: events waiting for the next step, lasting ones with their end (max: until cleared).
  std::array<std::optional<Fault>, fault_kind_count> pending_{};
  std::array<std::optional<TimeNs>, fault_kind_count> until_{};
  Fault sdo_abort_{};

  std::array<can::Frame, 32> out_{};
  std::size_t out_count_ = 0;
};

}  // namespace saw::canopen::sim
