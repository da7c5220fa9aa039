// FalconDevice: a Novint Falcon as a CRTK arm, a periodic task exchanging one packet per cycle.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string_view>

#include "saw/device.hpp"
#include "saw/drivers/falcon/delta_kinematics.hpp"
#include "saw/drivers/falcon/transport.hpp"

namespace saw::drivers::falcon {

struct FalconConfig {
  // The base's settings: max_force (N, a servo_cf whose norm exceeds it is refused); the
  // workspace (m, in measured_cp's frame: outside it, force pushing further out is dropped);
  // home_timeout (homing pending longer: FAULT).
  DeviceSettings contract{.max_force = 8.0,
                          .home_timeout = 5'000'000'000,
                          .workspace_min = {-0.06, -0.06, -0.06},
                          .workspace_max = {0.06, 0.06, 0.06}};
  DeltaGeometry geometry;
  // measured_cp = tip − origin, both in libnifalcon's frame (DeltaGeometry); NaN (the default):
  // the tip at encoder counts 0 (the arms at 35°), (0, 0, 134.6 mm) in that frame.
  Eigen::Vector3d origin = Eigen::Vector3d::Constant(NAN);
  bool home_on_start = true;  // home in the first cycles (the encoders are relative until then)
  // DAC counts driving the arms up onto their index while homing. 0 (the default): no force;
  // the operator homes by hand, pulling the grip all the way out and pushing it in, as
  // libnifalcon does (docs/devices.md). Either way the homing bit is sent in every packet.
  std::int16_t homing_dac = 0;
  // A failed exchange (no answer, USB error, corrupt or short frame, a pose out of the model):
  // this many in a row → FAULT, zero force. An unplug faults at once.
  int max_missed = 10;
  double velocity_filter = 0.3;          // 0..1: weight of the newest finite-difference velocity
  std::uint8_t clutch_buttons = 0x04;    // status:: bits raising the clutch event (centre button)
  std::uint8_t operator_buttons = 0x02;  // ... and operator_present (forward button)
};

// What a run of the hardware comes to (the "summary" column; the contract's counters — refused
// commands, watchdog trips, faults — are the base's "device" column).
struct FalconSummary {
  static constexpr std::string_view type_name = "saw::drivers::falcon::FalconSummary";
  static constexpr std::uint32_t layout_version = 3;  // 3: reopened
  std::uint64_t exchanges = 0;
  std::uint64_t no_answer = 0, usb_errors = 0, bad_frames = 0, out_of_model = 0;
  std::uint64_t saturated = 0;
  std::uint64_t reopened = 0;  // opened again after an unplug (the transport's reconnect)
  std::int32_t last_usb_error = 0;
};

// Provided "arm" (CRTK, by the device base: saw/device.hpp): measured_cp, measured_cv,
// measured_js (arm angles), operating_state, fault, command_timeout, watchdog_trips, servo_force
// (reads); servo_cf, state_command (writes); operating_state, clutch, operator_present, fault
// (events). Provided "falcon": summary, leds (reads).
// The transport is opened in open() (not RT); write() does one bounded exchange per cycle.
class FalconDevice : public Device {
 public:
  FalconDevice(std::string name, TaskConfig task, FalconConfig config,
               std::unique_ptr<FalconTransport> transport);
  ~FalconDevice() override;

  const FalconConfig& device_config() const noexcept { return config_; }
  const FalconSummary& summary() const noexcept { return summary_; }
  FalconTransport& transport() noexcept { return *transport_; }
  Eigen::Vector3d position() const noexcept { return x_ - origin_; }

 protected:
  void open() override;
  void close() noexcept override;
  Outcome read() override { return Outcome::done(); }  // the exchange is write()'s
  Outcome write(const Setpoint& s) override;
  Outcome enable() override;
  Outcome home() override;
  void enter_safe_state(SafeReason) override {}  // the next exchange carries zero force

 private:
  FalconDevice(std::string name, TaskConfig task, Checked<FalconConfig> config,
               std::unique_ptr<FalconTransport> transport);
  MotorCommand command(const Setpoint& s) noexcept;
  Outcome measure(const DeviceReport& r) noexcept;
  Outcome missed(FaultCode code, const char* why, std::int32_t error) noexcept;
  void publish() noexcept;

  FalconConfig config_;
  DeltaKinematics kinematics_;
  std::unique_ptr<FalconTransport> transport_;
  Eigen::Vector3d theta_ = Eigen::Vector3d::Zero(), theta_dot_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero(), origin_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d j_ = Eigen::Matrix3d::Zero();
  bool measured_ = false;
  bool homed_seen_ = false;   // the firmware reported every arm homed while homing
  bool homed_ = false;        // homed, and the firmware has said so in every report since
  bool homing_lost_ = false;  // until the next enable homes it again
  TimeNs last_report_ = 0;    // cycle time of the last report measured (the velocity's interval)
  int consecutive_missed_ = 0;

  // State-table sources.
  Vec3 servo_force_{};
  std::uint8_t leds_ = 0;
  FalconSummary summary_{};
};

}  // namespace saw::drivers::falcon
