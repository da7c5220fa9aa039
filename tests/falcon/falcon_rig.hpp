// A FalconDevice on the simulated firmware, stepped deterministically, commands through a mailbox.
#pragma once

#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "saw/detail/access.hpp"
#include "saw/detail/mailbox.hpp"
#include "saw/drivers/falcon/falcon_device.hpp"
#include "saw/drivers/falcon/sim_firmware.hpp"

namespace saw::drivers::falcon::test {

inline detail::Invoker execute_of(Command& c) {
  return {[](void* self, const void* arg) { static_cast<Command*>(self)->execute(arg); }, &c};
}

struct FalconRig {
  explicit FalconRig(FalconConfig c = {}, SimFirmwareConfig f = {}) {
    auto transport = std::make_unique<SimTransport>(f);
    sim = &transport->firmware();
    start(c, std::move(transport));
  }
  // On another transport (`sim` stays null).
  FalconRig(FalconConfig c, std::unique_ptr<FalconTransport> transport) { start(c, std::move(transport)); }
  void start(const FalconConfig& c, std::unique_ptr<FalconTransport> transport) {
    device = std::make_unique<FalconDevice>("falcon", TaskConfig::periodic(std::chrono::milliseconds(1), 0),
                                            c, std::move(transport));
    detail::Access::add_inbound(*device, &mailbox);
    for (const char* name : {"servo_cf", "state_command"})
      targets[name] = mailbox.add_target(execute_of(command(name)));
    device->state_table().finalize();
    device->startup();
  }
  void cycle(int n = 1) {
    for (int i = 0; i < n; ++i) {
      detail::Access::step(*device, now);
      now += 1'000'000;
    }
  }
  template <class Done>
  int cycle_until(Done done, int limit = 5000) {
    int n = 0;
    while (!done() && n < limit) cycle(), ++n;
    return n;
  }
  Command& command(const std::string& name, const std::string& iface = "arm") {
    Command* c = device->provided(iface)->find_command(name);
    if (c == nullptr) throw std::logic_error("no command " + name);
    return *c;
  }
  template <class T>
  void write(const std::string& name, const T& value) {
    if (mailbox.push(targets.at(name), &value, sizeof value) != Status::ok)
      throw std::logic_error("mailbox full");
  }
  template <class T>
  T read(const std::string& name, const std::string& iface = "arm") {
    T v{};
    (void)command(name, iface).read(nullptr, &v);
    return v;
  }
  void force(double x, double y, double z) { write("servo_cf", Wrench{{x, y, z}, {0, 0, 0}}); }
  OperatingStateValue state() const { return device->operating_state().state; }
  bool homed() const { return device->operating_state().is_homed; }
  void home() {
    cycle_until([&] { return homed(); });
  }

  SimFalconFirmware* sim = nullptr;
  std::unique_ptr<FalconDevice> device;
  detail::Mailbox mailbox{"test client", 64, sizeof(Wrench)};
  std::map<std::string, std::uint32_t> targets;
  TimeNs now = 1'000'000'000;
};

}  // namespace saw::drivers::falcon::test
