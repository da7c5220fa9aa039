// What the Falcon's exchange and cycle cost on this machine, with the simulated transport:
// printed for docs/devices.md. (A libusb transfer's cost needs a Falcon: not measured here.)
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "falcon_rig.hpp"
#include "saw/drivers/falcon/threaded_transport.hpp"

namespace saw::drivers::falcon {
namespace {

using Clock = std::chrono::steady_clock;

struct Figures {
  double mean_ns, p50_ns, p99_ns, max_ns;
};

// Times `body` `n` times, one sample each.
template <class F>
Figures time_each(int n, F body) {
  std::vector<double> ns(static_cast<std::size_t>(n));
  for (auto& s : ns) {
    const auto t0 = Clock::now();
    body();
    s = static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count());
  }
  double sum = 0;
  for (double s : ns) sum += s;
  std::sort(ns.begin(), ns.end());
  return {sum / n, ns[ns.size() / 2], ns[ns.size() * 99 / 100], ns.back()};
}

void print(const char* what, const Figures& f) {
  std::printf("falcon cycle cost: %-52s p50 %6.2f us  p99 %6.2f us  mean %6.2f us  max %7.1f us\n", what,
              f.p50_ns * 1e-3, f.p99_ns * 1e-3, f.mean_ns * 1e-3, f.max_ns * 1e-3);
}

TEST(FalconCycleCost, PrintsTheCodecExchangeAndCycleCosts) {
  constexpr int n = 20000;
  DeviceReport report{{100, -200, 300}, 0x15};
  const Packet frame = encode_report(report);
  volatile std::uint32_t sink = 0;
  print("codec (encode command + decode report)", time_each(n, [&] {
          const Packet out = encode_command(MotorCommand{{1, 2, 3}, control::led_green});
          DeviceReport r{};
          sink = sink + out[1] + static_cast<std::uint32_t>(decode_report(frame, r));
        }));
  SimTransport sim;
  sim.open();
  Packet in{};
  const Packet cmd = encode_command(MotorCommand{});
  print("simulated exchange (firmware + dynamics, 4 substeps)",
        time_each(n, [&] { (void)sim.exchange(cmd, in); }));
  ThreadedTransport threaded(std::make_unique<SimTransport>(), 0);
  threaded.open();
  print("cycle side of the I/O-thread transport (post + take)",
        time_each(n, [&] { (void)threaded.exchange(cmd, in); }));
  threaded.close();
  test::FalconRig rig;
  rig.home();
  rig.sim->set_hand(true);
  int i = 0;
  print("whole falcon cycle on the simulated transport", time_each(n, [&] {
          rig.force(0.5 * ((++i % 100) < 50 ? 1 : -1), 0, 0);
          rig.cycle();
        }));
  EXPECT_EQ(rig.device->device_status().faults, 0u);
}

}  // namespace
}  // namespace saw::drivers::falcon
