// The I/O-thread transport: the cycle posts and takes without waiting; a falcon homes through it.
#include "saw/drivers/falcon/threaded_transport.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "falcon_rig.hpp"

namespace saw::drivers::falcon {
namespace {

using namespace std::chrono_literals;

TEST(FalconThreadedTransport, ReportsArriveFromTheIoThreadEachOnce) {
  ThreadedTransport t(std::make_unique<SimTransport>(), 0);
  Packet in{};
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::disconnected) << "not open";
  t.open();
  int ok = 0, none = 0;
  for (int i = 0; i < 200; ++i) {
    const ExchangeResult r = t.exchange(encode_command({}), in);
    if (r.status == ExchangeStatus::ok) {
      ++ok;
      DeviceReport d{};
      EXPECT_EQ(decode_report(in, d), FrameError::none);
    } else {
      EXPECT_EQ(r.status, ExchangeStatus::no_answer);
      ++none;
    }
    std::this_thread::sleep_for(1ms);
  }
  std::printf("threaded sim: %d reports, %d cycles without a new one\n", ok, none);
  EXPECT_GT(ok, 150);
  // Without new commands no new reports: each report is handed out once.
  std::this_thread::sleep_for(5ms);
  (void)t.exchange(encode_command({}), in);
  std::this_thread::sleep_for(5ms);
  (void)t.exchange(encode_command({}), in);
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::no_answer);
  t.close();
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::disconnected);
}

TEST(FalconThreadedTransport, AFalconHomesAndIsPushedThroughTheIoThread) {
  auto inner = std::make_unique<SimTransport>();
  SimFalconFirmware& sim = inner->firmware();
  FalconConfig c;
  c.max_missed = 50;  // a shared 2-core machine: the I/O thread may be late now and then
  FalconDevice device("falcon", TaskConfig::periodic(1ms, 0), c,
                      std::make_unique<ThreadedTransport>(std::move(inner), 0));
  device.state_table().finalize();
  device.startup();
  TimeNs now = 1'000'000'000;
  for (int i = 0; i < 3000 && !device.operating_state().is_homed; ++i) {
    detail::Access::step(device, now += 1'000'000);
    std::this_thread::sleep_for(1ms);
  }
  EXPECT_TRUE(device.operating_state().is_homed);
  EXPECT_EQ(device.operating_state().state, OperatingStateValue::enabled);
  device.cleanup();  // stops the thread: the firmware may be read now
  EXPECT_TRUE(sim.motor_torque().isZero()) << "closing leaves the motors unpowered";
  EXPECT_EQ(sim.led(), SimLed::off) << "and the LEDs off";
  EXPECT_FALSE(sim.homing_mode()) << "and the homing given up with the last null packet";
  std::printf("threaded: %llu exchanges, %llu without a new report\n",
              static_cast<unsigned long long>(device.summary().exchanges),
              static_cast<unsigned long long>(device.summary().no_answer));
}

}  // namespace
}  // namespace saw::drivers::falcon
