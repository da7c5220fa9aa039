// What the device base costs a cycle, beside a bare task doing the same mailbox and state-table
// work: printed for docs/performance.md (a benchmark, not a timing assertion).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "saw/detail/access.hpp"
#include "saw/detail/mailbox.hpp"
#include "saw/device.hpp"

namespace saw {
namespace {

using Clock = std::chrono::steady_clock;

// The hardware does nothing: what is left is the base.
class NoopDevice : public Device {
 public:
  NoopDevice() : Device("noop", TaskConfig::periodic(std::chrono::milliseconds(1), 0), config()) {}
  static DeviceConfig config() {
    DeviceConfig c;
    c.max_force = 5;
    c.joints = {JointLimits{"a"}, JointLimits{"b"}, JointLimits{"c"}};
    return c;
  }
  std::uint64_t writes = 0;

 protected:
  Outcome read() override { return Outcome::done(); }
  Outcome write(const Setpoint& s) override {
    writes += s.mode == ServoMode::cf;
    return Outcome::done();
  }
  void enter_safe_state(SafeReason) override {}
};

// The same interface shape without the contract: a write command stored, a pose column.
class BareTask : public Task {
 public:
  BareTask() : Task("bare", TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& p = provide("arm");
    crtk::provide(p, crtk::arm::measured_cp, state_table(), &pose_);
    crtk::provide(p, crtk::arm::servo_cf, [this](const Wrench& w) { last_ = w; });
  }
  void run() override { pose_.position[0] = last_.force[0]; }

 private:
  Pose pose_{};
  Wrench last_{};
};

double p(std::vector<double>& v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

template <class C>
std::vector<double> time_cycles(C& c, int n) {
  detail::Mailbox mailbox{"bench", 64, sizeof(Wrench)};
  detail::Access::add_inbound(c, &mailbox);
  Command* cf = c.provided("arm")->find_command("servo_cf");
  const auto target =
      mailbox.add_target({[](void* self, const void* a) { static_cast<Command*>(self)->execute(a); }, cf});
  c.state_table().finalize();
  c.startup();
  std::vector<double> ns;
  TimeNs t = 1'000'000'000;
  for (int i = 0; i < n; ++i, t += 1'000'000) {
    const Wrench w{{0.5, 0, 0}, {}};
    (void)mailbox.push(target, &w, sizeof w);
    const auto t0 = Clock::now();
    detail::Access::step(c, t);
    ns.push_back(
        static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count()));
  }
  return ns;
}

TEST(DeviceCycleCost, PrintsTheBaseBesideABareTask) {
  constexpr int n = 20000;
  BareTask bare;
  NoopDevice device;
  auto b = time_cycles(bare, n);
  auto d = time_cycles(device, n);
  EXPECT_GT(device.writes, static_cast<std::uint64_t>(n / 2)) << "the commands reached the driver";
  std::printf("device cycle cost: bare task (mailbox, command, row)   p50 %5.2f us  p99 %5.2f us\n",
              p(b, 0.5) * 1e-3, p(b, 0.99) * 1e-3);
  std::printf("device cycle cost: device base, no-op hardware         p50 %5.2f us  p99 %5.2f us\n",
              p(d, 0.5) * 1e-3, p(d, 0.99) * 1e-3);
}

}  // namespace
}  // namespace saw
