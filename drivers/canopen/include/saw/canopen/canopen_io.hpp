// CanopenIo: a generic CANopen I/O node (a gripper's controller, analog/digital I/O) as a CRTK device, a
// client of a bus.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/canopen/bus_link.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/canopen/eds.hpp"
#include "saw/canopen/io_node.hpp"
#include "saw/canopen/node_monitor.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/device.hpp"

namespace saw::canopen {

// One value of the node as a joint: commanded through `output` (an RPDO-mapped object), measured
// through `input` (a TPDO-mapped object; none: the commanded value). SI = count × scale + offset.
struct IoChannel {
  std::string name;
  std::optional<PdoEntry> output, input;
  double scale = 1, offset = 0;
  double min = -1e9, max = 1e9;  // servo_jp beyond is refused
  double max_velocity = 1e9;     // servo_jp's step rate
  double safe = 0;               // SI: sent while not enabled, at a fault and at exit
  bool error_value = true;       // write its CiA 401 error mode and value (false: the device's own)
};

// An I/O component's node as the last cycle saw it: a summary column (printed when a run ends).
struct CanopenIoStatus {
  static constexpr std::string_view type_name = "saw::canopen::CanopenIoStatus";
  static constexpr std::uint32_t layout_version = 2;  // 2: warnings
  OperatingStateValue state = OperatingStateValue::disabled;
  std::uint8_t node = 0;
  std::uint8_t nmt_state = 0;  // NmtState, from its heartbeat
  std::uint8_t bus_state = 0;  // can::BusState
  std::uint64_t emcy = 0;      // EMCYs with an error code (warnings and faults)
  std::uint16_t last_emcy = 0;
  std::uint8_t error_register = 0;
  // EMCYs that were warnings (emcy_severity: the component stayed out of FAULT), and the newest
  std::uint64_t warnings = 0;
  std::uint16_t last_warning = 0;
  std::uint8_t last_warning_register = 0;
  std::uint32_t heartbeat_losses = 0, boot_ups = 0;
  std::uint64_t bad_pdos = 0, reconfigurations = 0;
  static constexpr auto fields = std::tuple{&CanopenIoStatus::state,
                                            &CanopenIoStatus::node,
                                            &CanopenIoStatus::nmt_state,
                                            &CanopenIoStatus::bus_state,
                                            &CanopenIoStatus::emcy,
                                            &CanopenIoStatus::last_emcy,
                                            &CanopenIoStatus::error_register,
                                            &CanopenIoStatus::warnings,
                                            &CanopenIoStatus::last_warning,
                                            &CanopenIoStatus::last_warning_register,
                                            &CanopenIoStatus::heartbeat_losses,
                                            &CanopenIoStatus::boot_ups,
                                            &CanopenIoStatus::bad_pdos,
                                            &CanopenIoStatus::reconfigurations};
};

struct CanopenIoConfig {
  std::string bus;  // the name of a canopen_bus component, or a URI (then it runs a bus task of its own)
  std::string interface_name = "io";
  // The base's settings: no servo_jp for command_timeout (0: 3 periods): hold. No max_force.
  DeviceSettings contract{.start_enabled = false};
  IoNodeConfig node;                // master_node and master_timeout: the bus task's
  std::vector<IoChannel> channels;  // 1..8
  TimeNs feedback_timeout = 0;      // no TPDO for this long faults; 0: 10 periods (at least 10 ms)
  // The node's RPDO deadline (rpdo_deadline.hpp): no RPDO for this long and it signals EMCY 0x8250
  // and puts out its error values (a FAULT here). nullopt: max(5 ms, 3 periods); 0: off.
  std::optional<TimeNs> rpdo_deadline;
  // The node's EDS (`eds:`): the types of the CiA 401 error objects; none: the standard types.
  std::optional<Eds> eds;
  StartupConfig startup;
  StartupPause startup_pause;  // tests step their simulated node here
  // Its own bus (a URI): the master's heartbeat it sends.
  std::uint8_t master_node = 127;
  TimeNs master_heartbeat_period = 100'000'000;
  TimeNs master_heartbeat_timeout = 300'000'000;
};

// Provided `<interface_name>` (CRTK, by the device base): measured_js (the channels), servo_jp,
// state_command, operating_state, fault. Provided "canopen": status (CanopenIoStatus), sdo (a
// qualified read: SdoRequest → SdoReply for this node, waiting up to 1 s: non-RT callers only). Start-up: NMT
// reset, identity, PDOs, the RPDO deadline (unless its EDS lists no writable 0x1400:05), 0x1017, 0x1016, each
// channel's CiA 401 error behaviour (a 0x6411:n output: 0x6443:n = 1 and 0x6444:n = its safe value in counts;
// a 0x6200:n output: 0x6206:n = 0xFF and 0x6207:n; any other output: a warning at construction, it has no
// standard error value; with `eds` each object typed as the EDS says, one it does not list not written, with
// a warning; none for a channel whose error_value is false; a safe value the type cannot hold is refused at
// construction), the deployment's writes, NMT start (StartupSequence; a re-configuration after a reboot
// writes the same). Each cycle: the TPDOs into measured_js; a FAULT (this component's only) on a lost
// heartbeat, a heartbeat not operational, a boot-up, an EMCY that emcy_severity() calls a fault (logged in
// hex with its name; a warning is logged so and counted in status, no FAULT), TPDOs older than
// feedback_timeout, bus off. `enable` waits for every TPDO. Not enabled, at a fault and at exit the outputs
// are the channels' safe values; at exit also one SYNC and NMT enter pre-operational.
class CanopenIo : public Device {
 public:
  CanopenIo(std::string name, TaskConfig task, CanopenIoConfig config);
  // On a caller's bus (tests), of which it is the master as of a URI (config.bus unused).
  CanopenIo(std::string name, TaskConfig task, CanopenIoConfig config, can::Bus& bus);
  ~CanopenIo() override;
  IoNode& node() noexcept { return *io_; }
  BusPort& port() noexcept { return *link_.port; }
  const JointState& measured_js() const noexcept { return measured().js; }
  const CanopenIoStatus& status() const noexcept { return status_; }

 protected:
  void open() override;
  Outcome read() override;
  Outcome write(const Setpoint& s) override;
  Outcome enable() override;
  void enter_safe_state(SafeReason why) override;
  bool accepts(ServoMode m) const noexcept override { return m == ServoMode::jp; }

 private:
  CanopenIo(std::string name, TaskConfig task, Checked<CanopenIoConfig> config, can::Bus* bus);
  Outcome check_node() noexcept;
  Outcome check_emcy() noexcept;
  Outcome failure(const char* why, FaultCode code, std::uint32_t detail = 0, TimeNs age = 0) noexcept;
  void set_safe_outputs() noexcept;

  CanopenIoConfig config_;
  BusLink link_;
  std::shared_ptr<BusTask> own_task_;  // its own bus: the bus task it runs in its cycle
  std::unique_ptr<IoNode> io_;
  std::array<double, JointState::max_joints> target_{};
  TimeNs start_time_ = -1;
  TimeNs watch_from_ = 0;  // not valid: stale counts from here (a re-configuration's end), or the start
  std::uint64_t emcy_faults_seen_ = 0, emcy_warnings_seen_ = 0;
  std::unique_ptr<NodeMonitor> monitor_;  // reboots, NMT state, re-configuration
  CanopenIoStatus status_{};
};

}  // namespace saw::canopen
