// canopen_drive and canopen_arm in deployment files: what parses, and the file:line:key of
// every refusal.
#include "saw/canopen/registration.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <string>

#include "saw/can/virtual_bus.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/canopen_io.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/deploy/deployment_spec.hpp"
#include "saw/drivers/sim_registration.hpp"
#include "saw/teleop/registration.hpp"

namespace {

using saw::deploy::ComponentRegistry;
using saw::deploy::ConfigError;
namespace canopen = saw::canopen;

ComponentRegistry& registry() {
  static ComponentRegistry r = [] {
    ComponentRegistry reg;
    canopen::register_components(reg);
    saw::drivers::sim::register_components(reg);
    saw::teleop::register_components(reg);
    return reg;
  }();
  return r;
}

const std::string good = R"(deployment: {name: canopen-test}
components:
  - name: arm
    type: canopen_arm
    task: {period: 1ms}
    params:
      bus: virtual:nowhere
      mode: cst
      chain: [a, b]
      tip: {xyz: [0.1, 0, 0]}
      heartbeat: {period: 20ms, timeout: 60ms}
      joints:
        a: {node: 1, counts_per_revolution: 4096, rated_torque: 0.5, min: -1, max: 1}
        b:
          node: 2
          xyz: [0.2, 0, 0]
          axis: [0, 1, 0]
          counts_per_revolution: 4096
          gear_ratio: 50
          rated_torque: 0.5
          min: -1
          max: 1
  - name: rail
    type: canopen_drive
    task: {period: 2ms}
    params:
      bus: socketcan:can1
      node: 9
      type: prismatic
      lead: 0.01
      counts_per_revolution: 2000
      rated_torque: 1.2
      min: 0
      max: 0.5
      pdo:
        rpdo1: [controlword, target_position]
        tpdo1: [statusword, position_actual, "0x2001:00:u16"]
)";

saw::deploy::DeploymentSpec parse(const std::string& text) {
  return saw::deploy::parse_deployment(text, "cfg.yaml", registry());
}

// Replaces `from` by `to` once in the good file, parses it, and returns the error message.
std::string error_of(const std::string& from, const std::string& to) {
  std::string text = good;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  try {
    (void)parse(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for: " << to;
  return "";
}

#define EXPECT_HAS(text, fragment) EXPECT_NE((text).find(fragment), std::string::npos) << (text)

TEST(CanopenDeployment, GoodFileParses) {
  const auto spec = parse(good);
  ASSERT_EQ(spec.components.size(), 2u);
  EXPECT_EQ(spec.components[0].type, "canopen_arm");
  EXPECT_EQ(spec.components[1].type, "canopen_drive");
}

TEST(CanopenDeployment, ErrorsNameFileLineAndKey) {
  EXPECT_HAS(error_of("mode: cst", "mode: cyclic"),
             "cfg.yaml:8:13: key 'components[0].params.mode': 'cyclic' is not one of: csp, csv, cst");
  EXPECT_HAS(error_of("{node: 1,", "{node: 200,"),
             "cfg.yaml:13:19: key 'components[0].params.joints.a.node': a node-ID is 1..127");
  EXPECT_HAS(error_of("        a: {node: 1, counts_per_revolution: 4096,", "        a: {node: 1,"),
             "key 'components[0].params.joints.a.counts_per_revolution': required parameter is missing");
  EXPECT_HAS(error_of("chain: [a, b]", "chain: [a, c]"),
             "key 'components[0].params.joints.c': the chain names joint 'c'");
  EXPECT_HAS(error_of("bus: virtual:nowhere", "bus: can:0"),
             "cfg.yaml:7:12: key 'components[0].params.bus': 'can:0' is not a bus");
  // A bus named (a canopen_bus component's) is a client's: the master's heartbeat is the bus's.
  EXPECT_HAS(error_of("bus: virtual:nowhere", "bus: can0\n      master_heartbeat: {period: 50ms}"),
             "key 'components[0].params.master_heartbeat': the master's heartbeat is the bus's");
  EXPECT_HAS(error_of("timeout: 60ms", "timeout: 10ms"),
             "key 'components[0].params.heartbeat.timeout': must be above the heartbeat period");
  EXPECT_HAS(error_of("min: -1, max: 1}", "min: 1, max: -1}"),
             "key 'components[0].params.joints.a.max': must be above min");
  EXPECT_HAS(error_of("gear_ratio: 50", "gear_ratoi: 50"),
             "cfg.yaml:19:11: key 'components[0].params.joints.b.gear_ratoi': unknown parameter (misspelt?)");
  EXPECT_HAS(error_of("axis: [0, 1, 0]", "axis: [0, 0, 0]"),
             "key 'components[0].params.joints.b.axis': must be a non-zero direction");
  EXPECT_HAS(error_of("      lead: 0.01\n", ""),
             "key 'components[1].params.lead': a prismatic joint needs its lead");
  EXPECT_HAS(
      error_of("\"0x2001:00:u16\"", "\"0x2001:00\""),
      "cfg.yaml:37:16: key 'components[1].params.pdo.tpdo1': '0x2001:00': the type of 0x2001:00 is not "
      "known here");
  EXPECT_HAS(
      error_of("rpdo1: [controlword, target_position]", "rpdo1: [controlword, target_torque]"),
      "cfg.yaml:27:7: key 'components[1].params': drive 'rail' (node 9): no RPDO maps the mode's target "
      "(0x607A:00)");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      eds: drive.eds"),
             "key 'components[1].params.eds': give either pdo or eds, not both");
  EXPECT_HAS(error_of("task: {period: 2ms}", "task: {period: 2ms}\n    params_x: 1"), "params_x");
  EXPECT_HAS(error_of("rated_torque: 1.2", "rated_torque: -1"),
             "key 'components[1].params.rated_torque': -1.000000 is out of range");
  // The master's heartbeat, what the drives do without it, the deployment's own SDO writes.
  EXPECT_HAS(
      error_of("node: 9", "node: 9\n      master_heartbeat: {period: 100ms, timeout: 50ms}"),
      "key 'components[1].params.master_heartbeat.timeout': must be above the master's heartbeat period");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      master_heartbeat: {node: 0}"),
             "key 'components[1].params.master_heartbeat.node'");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      master_heartbeat: {node: 9}"),
             "drive 'rail' (node 9): the master's node-ID is the drive's");
  EXPECT_HAS(
      error_of("node: 9", "node: 9\n      abort_connection: stop"),
      "key 'components[1].params.abort_connection': 'stop' is not one of: none, fault, disable_voltage, "
      "quick_stop");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      sdo: [\"0x60C2:01:u8=300\"]"),
             "key 'components[1].params.sdo': '0x60C2:01:u8=300': the value does not fit");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      sdo: [\"0x60C2:01:u8\"]"),
             "key 'components[1].params.sdo': '0x60C2:01:u8' is not <object>=<value>");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      sdo: [\"0x60C2:01:u8=1x\"]"),
             "'0x60C2:01:u8=1x': '1x' is not a number");
}

TEST(CanopenDeployment, AnEdsGivesThePdos) {
  std::string text = good;
  const std::string from =
      "      pdo:\n        rpdo1: [controlword, target_position]\n"
      "        tpdo1: [statusword, position_actual, \"0x2001:00:u16\"]\n";
  text.replace(text.find(from), from.size(), "      eds: " SAW_CANOPEN_TEST_DATA "/drive.eds\n");
  const auto spec = parse(text);
  ASSERT_EQ(spec.components.size(), 2u);
}

TEST(CanopenDeployment, TheSimulationDeploymentParses) {
  const auto spec = saw::deploy::load_deployment_spec(SAW_SOURCE_DIR "/config/canopen-sim.yaml", registry());
  ASSERT_EQ(spec.components.size(), 3u);
  EXPECT_EQ(spec.components[1].type, "canopen_arm");
  EXPECT_EQ(spec.connections.size(), 2u);
}

TEST(CanopenDeployment, TheSharedBusDeploymentParses) {
  const auto spec =
      saw::deploy::load_deployment_spec(SAW_SOURCE_DIR "/config/canopen-shared-bus.yaml", registry());
  ASSERT_EQ(spec.components.size(), 5u);
  EXPECT_EQ(spec.components[1].type, "canopen_bus");
  EXPECT_EQ(spec.components[2].type, "canopen_arm");
  EXPECT_EQ(spec.components[3].type, "canopen_io");
}

const std::string io_file = R"(deployment: {name: io-test}
components:
  - name: can0
    type: canopen_bus
    task: {period: 1ms}
    params: {bus: virtual:nowhere}
  - name: gripper
    type: canopen_io
    task: {period: 1ms}
    params:
      bus: can0
      node: 10
      channels: [jaw]
      joints:
        jaw: {output: "0x6411:01:i16", input: "0x6401:01:i16", scale: 1.0e-5, min: 0, max: 0.08, safe: 0.02}
)";

std::string io_error_of(const std::string& from, const std::string& to) {
  std::string text = io_file;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  try {
    (void)parse(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for: " << to;
  return "";
}

TEST(CanopenDeployment, AnIoNodeOnASharedBusParsesAndItsErrorsNameFileLineAndKey) {
  const auto spec = parse(io_file);
  ASSERT_EQ(spec.components.size(), 2u);
  EXPECT_HAS(io_error_of("output: \"0x6411:01:i16\", ", ""),
             "cfg.yaml:15:14: key 'components[1].params.joints.jaw.output': required parameter is missing");
  EXPECT_HAS(io_error_of("safe: 0.02", "safe: 0.2"), "key 'components[1].params.joints.jaw.safe'");
  EXPECT_HAS(io_error_of("channels: [jaw]", "channels: [jaw, thumb]"),
             "key 'components[1].params.joints.thumb': channels names 'thumb'");
  EXPECT_HAS(io_error_of("node: 10", "node: 10\n      master_heartbeat: {period: 50ms}"),
             "key 'components[1].params.master_heartbeat': the master's heartbeat is the bus's");
  EXPECT_HAS(io_error_of("node: 10", "node: 10\n      pdo: {rpdo1: [\"0x6411:01:i16\"]}"),
             "no TPDO maps its input 0x6401:01");
  EXPECT_HAS(io_error_of("{bus: virtual:nowhere}", "{bus: can0}"),
             "key 'components[0].params.bus': 'can0' is not a bus: virtual:<name> or socketcan:<interface>");
}

TEST(CanopenDeployment, AChannelsErrorValueKeyIsABooleanNamingFileLineAndKeyOtherwise) {
  std::string off = io_file;
  off.replace(off.find("safe: 0.02}"), 11, "safe: 0.02, error_value: false}");
  EXPECT_EQ(parse(off).components.size(), 2u);
  EXPECT_HAS(io_error_of("safe: 0.02}", "safe: 0.02, error_value: maybe}"),
             "key 'components[1].params.joints.jaw.error_value'");
}

// The error of building io_file on a fresh virtual bus with its client's task given `task`.
std::string client_build_error(const std::string& bus_prefix, const std::string& task) {
  const std::string bus = bus_prefix + std::to_string(::getpid());
  std::string text = io_file;
  text.replace(text.find("virtual:nowhere"), 15, "virtual:" + bus);
  text.replace(text.rfind("period: 1ms"), 11, task);
  std::string error;
  try {
    (void)saw::deploy::build_deployment(parse(text), registry());
  } catch (const ConfigError& e) {
    error = e.what();
  }
  (void)saw::can::remove_virtual_bus(bus);
  return error;
}

// Built, `error_value: false` reaches the component: its node gets no error mode or value write.
TEST(CanopenDeployment, AChannelWithErrorValueFalseGetsNoErrorObjectWrites) {
  const std::string bus = "cfg-errval-" + std::to_string(::getpid());
  for (const bool on : {true, false}) {
    std::string text = io_file;
    text.replace(text.find("virtual:nowhere"), 15, "virtual:" + bus);
    if (!on) text.replace(text.find("safe: 0.02}"), 11, "safe: 0.02, error_value: false}");
    auto d = saw::deploy::build_deployment(parse(text), registry());
    auto* io = d.find<saw::canopen::CanopenIo>("gripper");
    ASSERT_NE(io, nullptr);
    const auto& w = io->node().config().writes;
    const bool written = std::any_of(w.begin(), w.end(), [](const saw::canopen::SdoWrite& x) {
      return x.address == saw::canopen::ObjectAddress{0x6444, 1};
    });
    EXPECT_EQ(written, on) << "error_value: " << on;
  }
  (void)saw::can::remove_virtual_bus(bus);
}

// Built with `eds:`, the I/O node's error objects take the EDS's types (UNSIGNED16 here, not
// CiA 401's UNSIGNED8 and INTEGER32), and a safe value an UNSIGNED16 cannot hold is refused.
TEST(CanopenDeployment, AnIoNodesEdsTypesItsErrorObjects) {
  const std::string bus = "cfg-erreds-" + std::to_string(::getpid());
  std::string text = io_file;
  text.replace(text.find("virtual:nowhere"), 15, "virtual:" + bus);
  text.replace(text.find("node: 10"), 8, "node: 10\n      eds: " SAW_CANOPEN_TEST_DATA "/io_unsigned16.eds");
  {
    auto d = saw::deploy::build_deployment(parse(text), registry());
    auto* io = d.find<saw::canopen::CanopenIo>("gripper");
    ASSERT_NE(io, nullptr);
    const auto& w = io->node().config().writes;
    for (const std::uint16_t index : {std::uint16_t{0x6443}, std::uint16_t{0x6444}}) {
      const auto it = std::find_if(w.begin(), w.end(), [&](const saw::canopen::SdoWrite& x) {
        return x.address == saw::canopen::ObjectAddress{index, 1};
      });
      ASSERT_NE(it, w.end()) << index;
      EXPECT_EQ(it->type, saw::canopen::DataType::unsigned16) << index;
    }
  }
  text.replace(text.find("min: 0, max: 0.08, safe: 0.02"), 29, "min: -0.08, max: 0.08, safe: -0.02");
  std::string error;
  try {
    (void)saw::deploy::build_deployment(parse(text), registry());
  } catch (const std::exception& e) {
    error = e.what();
  }
  EXPECT_HAS(error, "channel 'jaw'");
  EXPECT_HAS(error, "UNSIGNED16");
  (void)saw::can::remove_virtual_bus(bus);
}

// Built, the deployment refuses a client of a canopen_bus at another period than the bus task's,
// at the client's entry, naming both components and both periods.
TEST(CanopenDeployment, AClientOfABusTaskAtAnotherPeriodIsRefused) {
  EXPECT_HAS(client_build_error("cfg-period-", "period: 2ms"),
             "cfg.yaml:7:5: key 'components[1]': 'gripper' (canopen_io): 'gripper' runs every 2 ms, its bus "
             "task 'can0' every 1 ms");
}

// The send phase's offset: after the route phase, with room for the clients, within the period.
TEST(CanopenDeployment, ASyncOffsetOutsideThePeriodOrBeforeTheRoutePhaseIsRefused) {
  for (const char* offset : {"1ms", "1us", "0us"})
    EXPECT_HAS(
        io_error_of("{bus: virtual:nowhere}",
                    std::string("{bus: virtual:nowhere, sync_offset: ") + offset + "}"),
        "cfg.yaml:6:49: key 'components[0].params.sync_offset': must be at least 2 us after the task's "
        "offset (0 us: the route phase; the clients run between) and below the period (1000 us)");
  EXPECT_HAS(
      io_error_of(
          "task: {period: 1ms}\n    params: {bus: virtual:nowhere}",
          "task: {period: 1ms, offset: 400us}\n    params: {bus: virtual:nowhere, sync_offset: 300us}"),
      "key 'components[0].params.sync_offset': must be at least 2 us after the task's offset (400 us");
  const auto spec = parse([] {
    std::string text = io_file;
    text.replace(text.find("{bus: virtual:nowhere}"), 22, "{bus: virtual:nowhere, sync_offset: 800us}");
    return text;
  }());
  EXPECT_EQ(spec.components.size(), 2u);
}

// Built, the deployment refuses a client of a canopen_bus whose offset is not between the bus
// task's two phases, at the client's entry, naming both values.
TEST(CanopenDeployment, AClientOfABusTaskOutsideItsPhasesIsRefused) {
  EXPECT_HAS(
      client_build_error("cfg-offset-", "period: 1ms, offset: 700us"),
      "cfg.yaml:7:5: key 'components[1]': 'gripper' (canopen_io): 'gripper' runs at offset 700 us in the "
      "period, its bus task 'can0' routes the frames received at 0 us and sends SYNC at 500 us");
}

}  // namespace

namespace {

TEST(CanopenDeployment, TheSummaryNamesTheFaultAndItsEmergency) {
  canopen::CanopenStatus s;
  s.state = saw::OperatingStateValue::fault;
  s.reason = canopen::FaultReason::emcy;
  s.faults = 1;
  s.fault.code = saw::FaultCode::device_error;
  s.fault.detail = 0x2310;
  s.fault.set_source("elbow_pitch");
  s.syncs = 1000;
  const auto* format = registry().summary_format(saw::type_info_of<canopen::CanopenStatus>());
  ASSERT_NE(format, nullptr);
  const std::string line = (*format)(&s);
  EXPECT_HAS(line, "FAULT, bus error-active: 1000 SYNC");
  EXPECT_HAS(line, "emergency message (device error) on elbow_pitch, detail 0x2310");
  EXPECT_HAS(line, "continuous over-current (device output side)");
  // What the device base counts (refused commands, watchdog trips) is said once, on its own line.
  saw::DeviceStatus d;
  d.refused.not_finite = 2;
  const auto* device = registry().summary_format(saw::type_info_of<saw::DeviceStatus>());
  ASSERT_NE(device, nullptr);
  EXPECT_HAS((*device)(&d), "2 servo commands refused before the hardware: 2 not finite");
  EXPECT_EQ(line.find("refused, never sent"), std::string::npos) << line;
}

}  // namespace

namespace {

// rpdo_deadline: a duration rounded up to whole ms of at least two periods, or off/0; its errors
// name file:line:key (the rail runs at 2 ms: 4 ms at least).
TEST(CanopenDeployment, AnRpdoDeadlineIsOffOrAtLeastTwoPeriodsNamingFileLineAndKey) {
  for (const char* ok : {"off", "0", "4ms", "3.5ms", "false"}) {
    std::string text = good;
    text.replace(text.find("node: 9"), 7, std::string("node: 9\n      rpdo_deadline: ") + ok);
    EXPECT_NO_THROW((void)parse(text)) << ok;
  }
  EXPECT_HAS(
      error_of("node: 9", "node: 9\n      rpdo_deadline: 3ms"),
      "cfg.yaml:29:22: key 'components[1].params.rpdo_deadline': rpdo_deadline (3 ms in whole ms) must "
      "be at least two periods (4000 us), or 0 (off)");
  EXPECT_HAS(error_of("node: 9", "node: 9\n      rpdo_deadline: 70s"),
             "key 'components[1].params.rpdo_deadline': rpdo_deadline must be 0 (off) or up to 65.535 s");
  EXPECT_HAS(error_of("mode: cst", "mode: cst\n      rpdo_deadline: soon"),
             "key 'components[0].params.rpdo_deadline'");
}

}  // namespace
