// CanopenArm: CiA 402 drives on one CAN bus as one CRTK device (an arm, or a single drive), a periodic task.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/arm_status.hpp"
#include "saw/canopen/bus_link.hpp"
#include "saw/canopen/bus_master.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/canopen/chain_kinematics.hpp"
#include "saw/canopen/node_monitor.hpp"
#include "saw/canopen/sdo_queue.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/device.hpp"

namespace saw::canopen {

// CRTK's joint-space servo commands (crtk_arm.hpp declares them).
namespace joint_space {
using crtk::arm::servo_jf;  // efforts: N·m or N (cst)
using crtk::arm::servo_jp;  // positions (csp)
using crtk::arm::servo_jv;  // velocities (csv)
using crtk::arm::setpoint_js;
}  // namespace joint_space

// One joint: its drive, its units and its limits, in SI (rad or m).
struct JointConfig {
  std::string name;
  std::uint8_t node = 1;
  DriveUnits units;
  double min = 0, max = 0;     // position limits: commands beyond are refused, a position beyond faults
  double max_velocity = 1;     // servo_jv's bound; servo_jp's step bound (per second since the last)
  double max_torque = 0;       // servo_jf's and servo_cf's bound per joint; 0: the rated torque at the joint
  double following_error = 0;  // csp: |target − position| that faults; 0: not checked
  double offset = 0;           // the joint's position when the drive reads 0: joint = drive position + offset
  std::vector<PdoMapping> pdos;           // what the start-up configures; empty: default_pdo_mappings()
  std::vector<SdoWrite> writes;           // the deployment's own SDO writes (AxisConfig::writes)
  std::optional<DriveIdentity> identity;  // from its EDS/DCF: checked at start-up
  // RPDOs whose EDS lists no writable event timer: their deadline is not written (a warning).
  std::vector<std::uint16_t> rpdo_deadline_unwritable;
};

struct CanopenArmConfig {
  // The base's settings: with no fresh servo_* for command_timeout (0: 3 periods), an enabled arm
  // holds its position (csp), zero velocity (csv) or zero torque (cst), and says so;
  // fault_on_command_timeout also makes it a FAULT. max_force: servo_cf above it (N) is refused (0:
  // the joint torques only). start_enabled: enable once started (a simulation; hardware waits
  // for `enable`). enable_timeout is the driver's: 4 transition_timeouts.
  DeviceSettings contract{.start_enabled = false};
  // "virtual:<name>" or "socketcan:<if>": this component is the master of that bus; or the name
  // of a canopen_bus component: a client of its bus task (which sends SYNC and the master's
  // heartbeat; master_node and master_heartbeat_* are then its).
  std::string bus;
  std::string interface_name = "arm";  // the provided CRTK interface
  cia402::Mode mode = cia402::csp;
  std::vector<JointConfig> joints;         // 1..8
  std::optional<ChainSpec> chain;          // measured_cp/cv and servo_cf; one joint per drive
  TimeNs heartbeat_period = 100'000'000;   // 0x1017 of every drive
  TimeNs heartbeat_timeout = 300'000'000;  // lost after this long without one
  // The master's heartbeat (its node-ID and period) and how long each drive's consumer (0x1016)
  // waits for it before it does what 0x6007 says (abort_connection).
  std::uint8_t master_node = 127;
  TimeNs master_heartbeat_period = 100'000'000;
  TimeNs master_heartbeat_timeout = 300'000'000;
  AbortConnection abort_connection = AbortConnection::quick_stop;
  // Each drive's RPDO deadline (rpdo_deadline.hpp): no RPDO for this long and the drive signals
  // EMCY 0x8250 and does what 0x6007 says; the master faults on that EMCY. nullopt: max(5 ms,
  // 3 periods); 0: off. checked() rounds it up to whole ms (at least two periods).
  std::optional<TimeNs> rpdo_deadline;
  TimeNs feedback_timeout = 0;  // no TPDO for this long faults; 0: 10 periods (at least 10 ms)
  StartupConfig startup;
  TimeNs transition_timeout = 1'000'000'000;  // a drive's CiA 402 transition; beyond: enable fails
  // What the start-up does between its steps (tests step their simulated drives here);
  // empty: sleep 1 ms.
  StartupPause startup_pause;
};

// The configuration with its defaults filled in (command and feedback timeouts from the period,
// max_torque from the rated torque), checked with its drives (check(AxisConfig)); throws
// std::invalid_argument saying which joint and what.
CanopenArmConfig checked(CanopenArmConfig config, const TaskConfig& task);

// Provided `<interface_name>` (CRTK, by the device base: saw/device.hpp): measured_js (named
// joints), setpoint_js, operating_state, fault (FaultInfo), command_timeout, watchdog_trips
// reads; servo_jp, servo_jv, servo_jf, state_command (enable, disable, pause, resume, home)
// writes; operating_state and fault events; with a chain also measured_cp, measured_cv and
// servo_cf (τ = Jᵀ·w, cst).
// Provided "canopen": status (CanopenStatus, also the summary column), sdo (a qualified read:
// SdoRequest → SdoReply, waiting up to 1 s: for non-RT callers only).
//
// The base checks every servo command before it becomes a setpoint (finite, the mode, the
// joints' limits); a refused one is counted and replaced by the hold value (the last target in
// csp, zero velocity or torque), never sent. A fault (a drive's statusword or EMCY, a lost
// heartbeat, a reboot, bus-off, stale TPDOs, a joint limit, a following error, an enable that
// does not complete, and with on_command_timeout: fault a stale command) quick-stops every drive
// and sends zero velocity/torque; FaultInfo (and CanopenStatus::reason) says why. `enable`
// resets the drives' faults and walks them back to operation enabled; a cause still present
// faults again at once.
class CanopenArm : public Device {
 public:
  // Opens config.bus; throws std::runtime_error (the bus cannot be opened, or another component
  // of this process is its master already) or std::invalid_argument (the configuration).
  CanopenArm(std::string name, TaskConfig task, CanopenArmConfig config);
  // The same on a bus the caller owns (tests): it must outlive the component.
  CanopenArm(std::string name, TaskConfig task, CanopenArmConfig config, can::Bus& bus);
  ~CanopenArm() override;

  const CanopenArmConfig& arm_config() const noexcept { return config_; }
  std::size_t joints() const noexcept { return n_; }
  BusMaster& master() noexcept { return *master_; }
  // On a shared bus: this component's port of the bus task; else nullptr.
  BusPort* port() noexcept { return link_.port; }
  FaultReason fault_reason() const noexcept { return reason_; }
  const CanopenStatus& status() const noexcept { return status_; }
  const JointState& measured_js() const noexcept { return measured().js; }
  const JointState& setpoint_js() const noexcept { return setpoint_js_; }

 protected:
  // The start-up sequence (StartupSequence), blocking; throws std::runtime_error saying which
  // drive did not answer or refused what.
  void open() override;
  Outcome read() override;
  Outcome write(const Setpoint& s) override;
  Outcome enable() override;
  void enter_safe_state(SafeReason why) override;
  bool admit(Setpoint& s) override;
  bool accepts(ServoMode m) const noexcept override;

 private:
  CanopenArm(std::string name, TaskConfig task, Checked<CanopenArmConfig> config, can::Bus* bus);
  void provide_interfaces();
  // The cycle.
  void read_feedback() noexcept;
  Outcome check_health() noexcept;
  Outcome check_axis(std::size_t i) noexcept;
  void send_setpoints(const Setpoint& s) noexcept;
  void publish() noexcept;
  Outcome failure(FaultReason reason, FaultCode code, std::size_t axis, std::uint32_t detail = 0,
                  TimeNs age = 0) noexcept;
  Outcome check_emcy(std::size_t i, bool drive_fault) noexcept;
  Outcome check_enabling(std::size_t i) noexcept;
  Outcome reconfigure_rebooted() noexcept;
  std::uint16_t error_code(std::size_t i) const noexcept;
  bool says() const noexcept;  // a new fault (not one already raised) is worth a log line
  void target_all(cia402::Target t) noexcept;

  CanopenArmConfig config_;
  std::size_t n_ = 0;
  BusLink link_;
  can::Bus& bus_;
  std::unique_ptr<BusMaster> master_;
  std::unique_ptr<ChainKinematics> kinematics_;

  using Joints = std::array<double, JointState::max_joints>;
  Joints q_{}, qd_{}, tau_{};  // measured
  Joints target_{};            // what was sent this cycle (csp: position, csv: velocity, cst: torque)
  FaultReason reason_ = FaultReason::none;
  bool enable_sent_ = false;     // this enable's fault resets and targets are out
  bool operation_sent_ = false;  // ... and, every drive showing its mode, operation enabled
  TimeNs mode_wait_ = -1;        // since when every drive is switched on, waiting for 0x6061
  TimeNs start_time_ = -1;
  std::array<std::uint64_t, JointState::max_joints> emcy_seen_{};
  // An EMCY waits for the drive's next statusword: fault (an error) or not (a warning).
  std::array<bool, JointState::max_joints> emcy_pending_{};
  std::array<int, JointState::max_joints> emcy_tpdos_{};
  std::unique_ptr<NodeMonitor> monitor_;  // reboots, NMT state, re-configuration

  // State-table sources.
  JointState setpoint_js_{};
  CanopenStatus status_{};
};

}  // namespace saw::canopen
