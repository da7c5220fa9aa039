// The device conformance suite: one test list every driver runs, each with its own simulator.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "saw/detail/access.hpp"
#include "saw/detail/mailbox.hpp"
#include "saw/device.hpp"

namespace saw::conformance {

// The commands the suite sends, as each driver spells them (servo_cf, servo_jf, ...): `other` is
// a second good command whose output differs from good's (for a device that holds its output).
enum class Command : std::uint8_t { good, not_finite, infinite, over_limit, other };

// A driver and its simulator, stepped deterministically one 1 ms cycle at a time. What the
// suite observes of the hardware comes from the simulator's side (the firmware's motor torque,
// a drive's target torque and state), never from the driver's own bookkeeping.
class Rig {
 public:
  virtual ~Rig() = default;
  virtual Device& device() = 0;
  // One device cycle and its simulator's reaction.
  virtual void cycle(int n = 1) = 0;
  // A command through a mailbox, as from a connected client: handled in the next cycle.
  virtual void send(Command c) = 0;
  // What the hardware puts out now, by the simulator (|force| in N, or the largest |torque|);
  // 0 is the safe output.
  virtual double output() const = 0;
  // The simulator sees the hardware in its safe state (no force; a drive not in operation enabled).
  virtual bool safe() const = 0;
  // Makes the hardware fail as it does in the field (no answer, a drive fault); false: this
  // simulated hardware has nothing that fails (the test says so and skips).
  virtual bool break_hardware() = 0;
  // Makes the next start fail as this hardware's does (a port that does not open, drives that
  // do not answer); false: it cannot.
  virtual bool fail_start() { return false; }
  // Cycles enough for the simulator to see what the device sent last (a drive's PDO).
  virtual void settle() { cycle(2); }
  // The controller dies as a process does (its cycles stop: no PDOs, no SYNC, no heartbeat) and
  // the hardware runs alone for `alone`; false: this simulated hardware watches nothing (skips).
  virtual bool kill_controller(TimeNs alone) {
    (void)alone;
    return false;
  }

  // What the hardware keeps when a command is refused or commands stop, as the device's contract
  // declares: a device that holds (SafeState::hold: an I/O node's outputs, a position-controlled
  // joint) keeps its last applied output, the others take the safe output 0. Disable, pause, a
  // fault and a stop are the safe output 0 for every device.
  bool holds() { return device().contract().safe_state == SafeState::hold; }

  // The manager's part, done by hand.
  void start() {
    device().state_table().finalize();
    device().startup();
  }
  void stop() {
    device().cleanup();
    settle_after_stop();
  }
  virtual void settle_after_stop() {}
  void state_command(StateCommand c) { write("state_command", c); }
  bool enable(int limit = 5000) {
    state_command(StateCommand::enable);
    for (int i = 0; i < limit; ++i) {
      if (device().following()) return true;
      cycle();
    }
    return device().following();
  }
  TimeNs period() const { return 1'000'000; }

 protected:
  // Connects the device's write commands to this rig's mailbox (once the device exists).
  void wire(Device& d, std::initializer_list<const char*> commands) {
    detail::Access::add_inbound(d, &mailbox_);
    for (const char* name : commands) {
      saw::Command* c = d.provided(d.contract().interface_name)->find_command(name);
      if (c == nullptr) throw std::logic_error(std::string("no command ") + name);
      targets_[name] = mailbox_.add_target(
          {[](void* self, const void* arg) { static_cast<saw::Command*>(self)->execute(arg); }, c});
    }
  }
  template <class T>
  void write(const std::string& name, const T& value) {
    if (mailbox_.push(targets_.at(name), &value, sizeof value) != Status::ok)
      throw std::logic_error("mailbox full");
  }

 private:
  detail::Mailbox mailbox_{"conformance client", 64, sizeof(JointState)};
  std::map<std::string, std::uint32_t> targets_;
};

// The suite's command as a value: `good` itself, half of it, NaN, infinity, or twice `limit`.
inline double value_of(Command c, double good, double limit) {
  return c == Command::good         ? good
         : c == Command::other      ? good / 2
         : c == Command::not_finite ? NAN
         : c == Command::infinite   ? INFINITY
                                    : 2 * limit;
}

// A haptic device stepped alone, its simulator behind its own seam (inside the device, or behind
// its transport): one cycle a step, servo_cf along one axis.
class HapticRig : public Rig {
 public:
  void cycle(int n) override {
    for (int i = 0; i < n; ++i, now_ += period()) detail::Access::step(device(), now_);
  }
  void send(Command c) override {
    Wrench w{};
    w.force[axis_] = value_of(c, 1.0, device().contract().max_force);
    write("servo_cf", w);
  }

 protected:
  explicit HapticRig(std::size_t axis) : axis_(axis) {}

 private:
  std::size_t axis_;
  TimeNs now_ = 1'000'000'000;
};

struct Driver {
  std::string name;
  std::function<std::unique_ptr<Rig>()> make;
};
inline void PrintTo(const Driver& d, std::ostream* os) { *os << d.name; }
inline std::string driver_name(const testing::TestParamInfo<Driver>& info) { return info.param.name; }

class DeviceConformance : public testing::TestWithParam<Driver> {};

}  // namespace saw::conformance
