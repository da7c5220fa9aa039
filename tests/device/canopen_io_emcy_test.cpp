// canopen_io's EMCYs by severity, each one raised on the simulated I/O node's side: an error reset
// clears, an error register of 0 and CAN error-passive or overrun are warnings (logged once, in
// hex with the standard name, shown in status), the rest faults.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "canopen_io_rig.hpp"
#include "saw/log.hpp"

namespace saw::conformance {
namespace {

std::vector<std::string> drain_log() {
  std::vector<std::string> lines;
  LogRecord r;
  while (log_ring().pop(r)) lines.push_back(format_log_record(r));
  return lines;
}

int count_containing(const std::vector<std::string>& lines, const std::string& text) {
  int n = 0;
  for (const std::string& l : lines) n += l.find(text) != std::string::npos;
  return n;
}

// Enabled and driving the jaw (count 3000), the log emptied.
std::unique_ptr<CanopenIoRig> driving() {
  auto rig = std::make_unique<CanopenIoRig>();
  rig->start();
  EXPECT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  EXPECT_EQ(rig->output(), 3000);
  (void)drain_log();
  return rig;
}

// Enough cycles for the EMCY to reach the component, and the component to send again.
void emcy(CanopenIoRig& rig, std::uint16_t code, std::uint8_t error_register) {
  rig.sim().raise_emcy(code, error_register);
  for (int i = 0; i < 5; ++i) {
    rig.send(Command::good);
    rig.cycle(1);
  }
}

// A starved component (its bus task's SYNC and heartbeat go on, its RPDOs do not): the node's RPDO
// deadline (written at start-up, rpdo_deadline: 5 ms by default) fires EMCY 0x8250 and puts out
// its error value (the safe value); the component's next cycle faults on that EMCY.
TEST(CanopenIoEmcy, AStarvedComponentsNodeTakesItsErrorValueAtItsRpdoDeadlineAndTheComponentFaults) {
  auto rig = driving();
  rig->starve(4);
  EXPECT_EQ(rig->sim().rpdo_timeouts(), 0u) << "within the deadline";
  EXPECT_EQ(rig->output(), 3000);
  rig->starve(4);
  EXPECT_EQ(rig->sim().rpdo_timeouts(), 1u);
  EXPECT_EQ(rig->output(), 0) << "its error value: the safe value";
  EXPECT_EQ(rig->sim().heartbeat_events(), 0u) << "the master's heartbeat went on";
  rig->cycle(3);
  EXPECT_EQ(rig->io().operating_state().state, OperatingStateValue::fault);
  EXPECT_EQ(rig->io().device_status().fault.detail, 0x8250u);
  EXPECT_EQ(count_containing(drain_log(), "EMCY 0x8250 (RPDO timeout)"), 1);
}

TEST(CanopenIoEmcy, AnErrorRegisterOfZeroIsAWarningLoggedOnceAndShown) {
  auto rig = driving();
  emcy(*rig, 0x4210, 0x00);  // temperature, device: the register says there is no error
  EXPECT_EQ(rig->device().operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(rig->device().device_status().faults, 0u);
  EXPECT_EQ(rig->output(), 3000) << "the jaw goes on";
  const canopen::CanopenIoStatus& s = rig->io().status();
  EXPECT_EQ(s.warnings, 1u);
  EXPECT_EQ(s.last_warning, 0x4210);
  EXPECT_EQ(s.last_warning_register, 0x00);
  EXPECT_EQ(s.emcy, 1u);
  const auto lines = drain_log();
  EXPECT_EQ(
      count_containing(
          lines, "node 10: EMCY 0x4210 (excess temperature of the device), error register 0x0000: a warning"),
      1)
      << "logged once, in hex with the standard name";
  rig->cycle(20);
  EXPECT_EQ(count_containing(drain_log(), "EMCY"), 0) << "not again";
}

TEST(CanopenIoEmcy, CanErrorPassiveAndOverrunAreWarnings) {
  auto rig = driving();
  emcy(*rig, 0x8120, 0x11);  // generic, communication
  emcy(*rig, 0x8110, 0x11);
  EXPECT_EQ(rig->device().operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(rig->io().status().warnings, 2u);
  EXPECT_EQ(rig->io().status().last_warning, 0x8110);
  EXPECT_EQ(rig->io().status().last_warning_register, 0x11);
  const auto lines = drain_log();
  EXPECT_EQ(
      count_containing(lines, "EMCY 0x8120 (CAN in error passive mode), error register 0x0011: a warning"),
      1);
  EXPECT_EQ(
      count_containing(lines, "EMCY 0x8110 (CAN overrun (objects lost)), error register 0x0011: a warning"),
      1);
}

TEST(CanopenIoEmcy, AnErrorResetIsNeitherAWarningNorAFault) {
  auto rig = driving();
  emcy(*rig, 0x0000, 0x00);
  EXPECT_EQ(rig->device().operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(rig->io().status().warnings, 0u);
  EXPECT_EQ(rig->io().status().emcy, 0u);
  EXPECT_EQ(rig->io().node().emcys().resets, 1u);
}

// The codes of CiA 301's 0x81xx that mean lost communication, and an error of the device.
TEST(CanopenIoEmcy, LostCommunicationAndDeviceErrorsFaultSayingWhichAndAreSafe) {
  for (const std::uint16_t code :
       std::initializer_list<std::uint16_t>{0x8100, 0x8130, 0x8140, 0x8150, 0x2310, 0x5000}) {
    SCOPED_TRACE(code);
    auto rig = driving();
    emcy(*rig, code, 0x01);
    rig->settle();
    const Device& d = rig->device();
    ASSERT_EQ(d.operating_state().state, OperatingStateValue::fault);
    EXPECT_EQ(d.fault().code, FaultCode::device_error);
    EXPECT_EQ(d.fault().detail, code);
    EXPECT_EQ(d.device_status().reason_text(), "emergency message");
    EXPECT_EQ(rig->io().status().warnings, 0u);
    EXPECT_TRUE(rig->safe()) << "the jaw at its safe value";
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%04X", code);
    const auto lines = drain_log();
    EXPECT_EQ(count_containing(lines, std::string("node 10: EMCY ") + hex + " (" +
                                          std::string(canopen::emcy_name(code)) + "), error register 0x0001"),
              1);
  }
}

TEST(CanopenIoEmcy, SeverityFollowsTheCodeAndTheErrorRegister) {
  using canopen::EmcySeverity;
  const auto of = [](std::uint16_t code, std::uint8_t reg) {
    canopen::Emcy e;
    e.code = code;
    e.error_register = reg;
    return canopen::emcy_severity(e);
  };
  EXPECT_EQ(of(0x0000, 0x00), EmcySeverity::reset);
  EXPECT_EQ(of(0x0000, 0x01), EmcySeverity::reset) << "a reset with errors left: the register says so";
  EXPECT_EQ(of(0x2310, 0x00), EmcySeverity::warning);
  EXPECT_EQ(of(0x8110, 0x11), EmcySeverity::warning);
  EXPECT_EQ(of(0x8120, 0x11), EmcySeverity::warning);
  for (const std::uint16_t code :
       std::initializer_list<std::uint16_t>{0x8100, 0x8130, 0x8140, 0x8150, 0x8210, 0x2310, 0xFF00})
    EXPECT_EQ(of(code, 0x01), EmcySeverity::fault) << std::hex << code;
}

}  // namespace
}  // namespace saw::conformance
