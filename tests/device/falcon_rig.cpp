// The conformance suite on the Falcon driver (drivers/falcon) and its simulated firmware: what
// the motors get is the firmware's motor torque, decoded from the packets it received.
#include <gtest/gtest.h>

#include <cmath>

#include "conformance.hpp"
#include "saw/drivers/falcon/falcon_device.hpp"
#include "saw/drivers/falcon/sim_firmware.hpp"

namespace saw::conformance {
namespace {

using namespace saw::drivers::falcon;

// The simulated firmware behind a USB port that may not open (no Falcon plugged in).
class PortRefusing : public FalconTransport {
 public:
  explicit PortRefusing(std::unique_ptr<SimTransport> inner) : inner_(std::move(inner)) {}
  void open() override {
    if (refuse_) throw TransportError("no Novint Falcon (0403:cb48) on USB");
    inner_->open();
  }
  ExchangeResult exchange(const Packet& out, Packet& in) noexcept override {
    return inner_->exchange(out, in);
  }
  void close() noexcept override { inner_->close(); }
  std::string describe() const override { return inner_->describe(); }
  bool refuse_ = false;

 private:
  std::unique_ptr<SimTransport> inner_;
};

class FalconRig : public HapticRig {
 public:
  FalconRig() : HapticRig(2) {
    FalconConfig c;
    c.contract.start_enabled = false;
    auto sim = std::make_unique<SimTransport>(SimFirmwareConfig{});
    firmware_ = &sim->firmware();
    auto port = std::make_unique<PortRefusing>(std::move(sim));
    port_ = port.get();
    device_ = std::make_unique<FalconDevice>("falcon", TaskConfig::periodic(std::chrono::milliseconds(1), 0),
                                             c, std::move(port));
    wire(*device_, {"servo_cf", "state_command"});
  }
  Device& device() override { return *device_; }
  double output() const override { return firmware_->motor_torque().norm(); }
  bool safe() const override { return firmware_->motor_torque().isZero(); }
  // Answers stop coming (the device keeps taking commands): the driver must give up.
  bool break_hardware() override {
    firmware_->drop_answers(1'000'000);
    return true;
  }
  bool fail_start() override {
    port_->refuse_ = true;
    return true;
  }

 private:
  std::unique_ptr<FalconDevice> device_;
  SimFalconFirmware* firmware_ = nullptr;
  PortRefusing* port_ = nullptr;
};

INSTANTIATE_TEST_SUITE_P(FalconDevice, DeviceConformance,
                         testing::Values(Driver{"falcon", [] { return std::make_unique<FalconRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
