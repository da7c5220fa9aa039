// The I/O-thread transport: the cycle posts and takes without waiting; a falcon homes through it.
#include "saw/drivers/falcon/threaded_transport.hpp"

#include <gtest/gtest.h>

#include <atomic>
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

// A Falcon on a cable: unplugged, every exchange is `disconnected` and open() finds nothing;
// plugged in again, open() finds a fresh firmware (powered up again: not homed). The test thread
// plugs and unplugs; only the I/O thread opens and exchanges.
class Cable final : public FalconTransport {
 public:
  void open() override {
    if (!plugged.load(std::memory_order_acquire)) throw TransportError("Falcon: no Falcon found (unplugged)");
    sim_ = std::make_unique<SimTransport>();
    sim_->open();
    opens.fetch_add(1, std::memory_order_relaxed);
    silent_ = silent_opens.load(std::memory_order_acquire) > 0;
    if (silent_) silent_opens.fetch_sub(1, std::memory_order_acq_rel);
  }
  ExchangeResult exchange(const Packet& out, Packet& in) noexcept override {
    if (!plugged.load(std::memory_order_acquire) || !sim_) return {ExchangeStatus::disconnected, 0, -4};
    if (silent_) return {ExchangeStatus::no_answer, 0, 0};
    return sim_->exchange(out, in);
  }
  void close() noexcept override { sim_.reset(); }
  std::string describe() const override { return "a Falcon on a cable"; }
  std::atomic<bool> plugged{true};
  std::atomic<int> opens{0};
  std::atomic<int> silent_opens{0};  // the next opens find a device that answers nothing

 private:
  std::unique_ptr<SimTransport> sim_;
  bool silent_ = false;
};

// Steps the rig a cycle a millisecond (the I/O thread runs beside it) until `done`, at most `limit`.
template <class Done>
bool step_until(test::FalconRig& rig, Done done, int limit = 5000) {
  for (int i = 0; i < limit; ++i) {
    if (done()) return true;
    rig.cycle();
    std::this_thread::sleep_for(1ms);
  }
  return done();
}

TEST(FalconThreadedTransport, AFalconPluggedInAgainIsOpenedAgainAndHomedBeforeAnyForce) {
  auto cable = std::make_unique<Cable>();
  Cable& c = *cable;
  FalconConfig config;
  config.max_missed = 50;  // a shared 2-core machine: the I/O thread may be late now and then
  test::FalconRig rig(config, std::make_unique<ThreadedTransport>(std::move(cable), 0, 100'000, 20'000'000));
  ASSERT_TRUE(step_until(rig, [&] { return rig.homed() && rig.state() == OperatingStateValue::enabled; }));

  c.plugged.store(false, std::memory_order_release);
  ASSERT_TRUE(step_until(rig, [&] { return rig.state() == OperatingStateValue::fault; }));
  EXPECT_EQ(rig.device->fault().code, FaultCode::device_lost);
  EXPECT_EQ(rig.device->fault().source_name(), "usb");
  EXPECT_EQ(rig.device->fault().detail, 4u) << "the backend's code (LIBUSB_ERROR_NO_DEVICE)";
  EXPECT_FALSE(rig.homed()) << "a Falcon plugged in again has a fresh firmware";
  // Enabled while still unplugged: refused at once (never ENABLED on nothing, not even busy).
  EXPECT_FALSE(rig.device->transport().connected());
  rig.write("state_command", StateCommand::enable);
  rig.cycle(2);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.device->fault().code, FaultCode::device_lost);
  rig.cycle(60);
  EXPECT_NE(rig.state(), OperatingStateValue::enabled);

  c.plugged.store(true, std::memory_order_release);
  ASSERT_TRUE(step_until(rig, [&] { return rig.device->transport().reopened() == 1; }))
      << "the I/O thread did not open the Falcon again (" << c.opens.load() << " opens)";
  EXPECT_EQ(c.opens.load(), 2);
  EXPECT_TRUE(rig.device->transport().connected());
  // The operator's enable homes it again first: busy, no force, until the firmware says homed.
  rig.write("state_command", StateCommand::enable);
  ASSERT_TRUE(step_until(rig, [&] { return rig.homed() && rig.state() == OperatingStateValue::enabled; }))
      << "state " << static_cast<int>(rig.state()) << ", homed " << rig.homed() << ", homing "
      << rig.device->homing() << ", exchanges " << rig.device->summary().exchanges << ", unanswered "
      << rig.device->summary().no_answer;
  rig.cycle();
  EXPECT_EQ(rig.device->summary().reopened, 1u);
  rig.device->cleanup();
}

// Plugged in again but answering nothing (enumerated, its firmware not running): after a second of
// silence the I/O thread opens it again, as after an unplug, and the next enable homes it.
TEST(FalconThreadedTransport, AFalconBackButSilentIsOpenedAgain) {
  auto cable = std::make_unique<Cable>();
  Cable& c = *cable;
  FalconConfig config;
  config.max_missed = 50;
  test::FalconRig rig(config, std::make_unique<ThreadedTransport>(std::move(cable), 0, 100'000, 20'000'000));
  ASSERT_TRUE(step_until(rig, [&] { return rig.homed() && rig.state() == OperatingStateValue::enabled; }));
  c.silent_opens.store(1, std::memory_order_release);
  c.plugged.store(false, std::memory_order_release);
  ASSERT_TRUE(step_until(rig, [&] { return rig.state() == OperatingStateValue::fault; }));
  c.plugged.store(true, std::memory_order_release);
  ASSERT_TRUE(step_until(rig, [&] { return rig.device->transport().reopened() == 2; }))
      << "opened " << c.opens.load() << " times: the silent Falcon was not opened again";
  EXPECT_EQ(c.opens.load(), 3);
  rig.write("state_command", StateCommand::enable);
  ASSERT_TRUE(step_until(rig, [&] { return rig.homed() && rig.state() == OperatingStateValue::enabled; }))
      << "state " << static_cast<int>(rig.state()) << ", homed " << rig.homed();
  rig.device->cleanup();
}

TEST(FalconThreadedTransport, WithoutReconnectAnUnpluggedFalconStaysClosed) {
  auto cable = std::make_unique<Cable>();
  Cable& c = *cable;
  FalconConfig config;
  config.max_missed = 50;
  test::FalconRig rig(config, std::make_unique<ThreadedTransport>(std::move(cable), 0));
  ASSERT_TRUE(step_until(rig, [&] { return rig.homed(); }));
  c.plugged.store(false, std::memory_order_release);
  ASSERT_TRUE(step_until(rig, [&] { return rig.state() == OperatingStateValue::fault; }));
  c.plugged.store(true, std::memory_order_release);
  rig.cycle(100);
  EXPECT_EQ(c.opens.load(), 1);
  EXPECT_EQ(rig.device->transport().reopened(), 0u);
  rig.device->cleanup();
}

}  // namespace
}  // namespace saw::drivers::falcon
