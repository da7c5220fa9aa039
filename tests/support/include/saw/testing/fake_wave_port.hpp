// FakeWavePort: a fake device that also serves a wave port's interface, its impedance set by the test.
#pragma once

#include <string>
#include <utility>

#include "saw/teleop/passivity_port.hpp"
#include "saw/testing/fake_device.hpp"

namespace saw::testing {

// What a PassivityPort with scheme wave offers a wave law (port_wave, port_remote_wave,
// port_wave_impedance), with the impedance it answers and whether it answers at all in the test's
// hands: a port restarted with another b, or in the passivity scheme (b = 0), or gone silent,
// without a second process. The waves it is sent are counted, not applied.
class FakeWavePort : public FakeDevice {
 public:
  FakeWavePort(std::string name, double b) : FakeDevice(std::move(name)), impedance(b) {
    auto& p = *provided(crtk::arm::interface_name);
    crtk::provide(p, teleop::port::wave, state_table(), &wave_);
    crtk::provide(p, teleop::port::remote_wave, [this](const Vec3&) { ++waves; });
    p.add_command_read_value<double>(std::string(teleop::port::wave_impedance.name),
                                     [this](double& out) noexcept {
                                       if (answer != Status::ok) return answer;
                                       out = impedance;
                                       return Status::ok;
                                     });
  }
  // Published with the next row (publish()), as a port's outgoing wave is.
  void set_wave(const Vec3& u) { wave_ = u; }

  double impedance;            // N·s/m: what port_wave_impedance answers
  Status answer = Status::ok;  // anything else: what it answers instead
  int waves = 0;               // port_remote_wave calls received

 private:
  Vec3 wave_{};
};

}  // namespace saw::testing
