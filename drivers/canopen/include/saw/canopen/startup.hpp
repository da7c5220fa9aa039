// The start-up of the drives on one bus: NMT reset, boot-ups, identity, SDO configuration, NMT start.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/canopen/axis.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/rpdo_deadline.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

// One SDO write of the start-up. An optional write may be refused by a drive that lacks the
// object (disabling a PDO the drive does not have): a refusal with "object does not exist" or
// "sub-index does not exist" is then not an error.
struct StartupWrite {
  SdoWrite write;
  bool optional = false;
};

// What the start-up writes to one drive, in order: its PDOs (configuration_writes() each),
// each enabled RPDO's deadline (0x1400 + n - 1 sub 05h, ms; optional), the producer heartbeat time 0x1017
// (ms), the consumer heartbeat time 0x1016:01 (the master's node-ID and time, ms; when master_timeout is not
// 0), the abort connection option code 0x6007, the deployment's writes (AxisConfig::writes), the mode of
// operation 0x6060.
std::vector<StartupWrite> startup_writes(const AxisConfig& axis);
// What any node gets (a CiA 402 drive's start with it): its PDOs, the RPDO deadline (when
// deadline.time is set: to each enabled RPDO its EDS does not call unwritable, optional), 0x1017
// and, when master_timeout is not 0, 0x1016:01.
std::vector<StartupWrite> node_writes(std::span<const PdoMapping> pdos, TimeNs heartbeat_period,
                                      std::uint8_t master_node, TimeNs master_timeout,
                                      const RpdoDeadline& deadline = {});

// One node as the start-up sees it, whatever its profile: who it is and what it is written.
struct NodeSetup {
  std::string name;  // what errors call it
  std::uint8_t node = 1;
  std::optional<DriveIdentity> identity;  // checked before anything is written; nullopt: not
  std::vector<StartupWrite> writes;
};
// A CiA 402 drive's: check(axis) (throws as it does), and startup_writes(axis).
NodeSetup setup_of(const AxisConfig& axis);
// A write's value as its type encodes it (values are kept as 32 bits; a signed object's is its
// two's complement).
Number startup_value(const SdoWrite& w) noexcept;

struct StartupConfig {
  TimeNs boot_timeout = 2'000'000'000;         // from NMT reset communication to every boot-up
  TimeNs sdo_timeout = 500'000'000;            // each SDO response
  TimeNs operational_timeout = 2'000'000'000;  // from NMT start to an operational heartbeat
};

enum class StartupPhase : std::uint8_t { reset, boot, identify, configure, start, operational, done, failed };
std::string_view to_string(StartupPhase p) noexcept;

// The sequence as a stepped machine: step() reads what the bus has, sends what is due and says
// where things stand, so that a test steps it beside simulated drives and the set-up thread
// loops it with a sleep (run_startup). Set-up code: it may allocate; never in an RT cycle.
// NMT commands address each node alone: another master's drives on the bus are left alone.
class StartupSequence {
 public:
  StartupSequence(can::Bus& bus, std::span<const AxisConfig> axes, StartupConfig config = {});
  StartupSequence(can::Bus& bus, std::vector<NodeSetup> nodes, StartupConfig config = {});
  ~StartupSequence();
  StartupSequence(const StartupSequence&) = delete;
  StartupSequence& operator=(const StartupSequence&) = delete;

  StartupPhase step(TimeNs now);
  StartupPhase phase() const noexcept { return phase_; }
  // Why it failed: the node, the phase, the object and the abort's name.
  const std::string& error() const noexcept { return error_; }
  // The writes each drive acknowledged, in order (for tests and the log).
  const std::vector<std::vector<SdoWrite>>& written() const noexcept { return written_; }

 private:
  struct Node;
  void receive(TimeNs now);
  void fail(const std::string& what);
  void send(const can::Frame& f);
  bool identify(TimeNs now);
  bool configure(TimeNs now);

  can::Bus& bus_;
  StartupConfig config_;
  std::vector<std::unique_ptr<Node>> nodes_;
  StartupPhase phase_ = StartupPhase::reset;
  TimeNs phase_start_ = 0;
  std::string error_;
  std::vector<std::vector<SdoWrite>> written_;
};

// Loops `sequence` until done or failed, calling `pause` between steps; `pause` returns the time
// of the next step (by default: sleep 1 ms, then the monotonic clock). Throws std::runtime_error
// with error() when it fails.
using StartupPause = std::function<TimeNs()>;
void run_startup(StartupSequence& sequence, const StartupPause& pause = {});

}  // namespace saw::canopen
