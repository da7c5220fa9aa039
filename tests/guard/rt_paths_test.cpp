// Proves the RT paths (a periodic task serving commands, events, reads and logging; a full
// command mailbox and a refused event) do none of what the guard counts, from the first cycle.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <vector>

#include "guard_support.hpp"
#include "saw/manager.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using namespace std::chrono_literals;

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

class Device : public saw::Task {
 public:
  explicit Device(saw::TaskConfig config) : Task("device", config) {
    auto& p = provide("arm");
    p.add_command_void("ping", [this] { pings_.fetch_add(1, std::memory_order_relaxed); });
    p.add_command_write<Vec3>("servo_cf", [this](const Vec3& f) { force_ = f; });
    p.add_command_read("measured_cp", state_table().add_column("measured_cp", &position_));
    p.add_command_qualified_read<double, double>("scale", [](const double& q, double& r) { r = 0.5 * q; });
    beat_ = &p.add_event_void("beat");
    moved_ = &p.add_event_write<Vec3>("moved");
  }
  void run() override {
    position_.x += 0.001 + force_.x * 1e-6;
    (void)(*beat_)();
    (void)(*moved_)(position_);
    if (++cycles_ % 100 == 0) saw::log(saw::LogLevel::info, "device", "cycle {} x={}", cycles_, position_.x);
  }
  std::atomic<std::uint64_t> pings_{0};

 private:
  Vec3 position_, force_;
  std::uint64_t cycles_ = 0;
  saw::EventVoid* beat_;
  saw::EventWrite<Vec3>* moved_;
};

class Helper : public saw::Component {
 public:
  Helper() : Component("helper") {
    provide("math").add_command_qualified_read<double, double>("square",
                                                               [](const double& q, double& r) { r = q * q; });
  }
};

class Controller : public saw::Task {
 public:
  explicit Controller(saw::TaskConfig config) : Task("controller", config) {
    auto& r = require("arm");
    r.add_function("ping", ping_);
    r.add_function("servo_cf", servo_cf_);
    r.add_function("measured_cp", measured_cp_);
    r.add_function("scale", scale_);
    r.add_event_handler_void("beat", [this] { beats_.fetch_add(1, std::memory_order_relaxed); });
    r.add_event_handler_write<Vec3>("moved", [this](const Vec3& p) { last_moved_ = p; });
    require("device_task").add_function("period_statistics", device_stats_);
    require("math").add_function("square", square_);
  }
  void run() override {
    Vec3 p;
    saw::RowStamp stamp;
    if (measured_cp_(p, stamp) == saw::Status::ok) {
      (void)measured_cp_.at_or_before(stamp.time - 5'000'000, p);
      ok_reads_.fetch_add(1, std::memory_order_relaxed);
    }
    double r = 0;
    (void)scale_(2.0, r);
    (void)square_(r, r);
    saw::TaskStatistics s;
    (void)device_stats_(s);
    (void)ping_();
    (void)servo_cf_(Vec3{1, 2, 3});
    cycles_.fetch_add(1, std::memory_order_relaxed);
  }
  std::atomic<std::uint64_t> cycles_{0}, beats_{0}, ok_reads_{0};

 private:
  saw::FunctionVoid ping_;
  saw::FunctionWrite<Vec3> servo_cf_;
  saw::FunctionRead<Vec3> measured_cp_;
  saw::FunctionQualifiedRead<double, double> scale_;
  saw::FunctionRead<saw::TaskStatistics> device_stats_;
  saw::FunctionQualifiedRead<double, double> square_;
  Vec3 last_moved_;
};

void connect_all(saw::Manager& m) {
  m.connect("controller", "arm", "device", "arm");
  m.connect("controller", "device_task", "device", "task");
  m.connect("controller", "math", "helper", "math");
}

TEST(RtGuard, PeriodicTasksServeEverythingCleanly) {
  saw::testing::GuardWindow window;
  const auto config = saw::TaskConfig::periodic(1ms, 0);
  Device device(config);
  Controller controller(config);
  Helper helper;
  saw::Manager m;
  m.add(device);
  m.add(controller);
  m.add(helper);
  connect_all(m);
  m.start();
  // Bounded, not asserted: the assertions below decide.
  (void)saw::testing::wait_for(
      [&] { return controller.cycles_.load() >= 300 && controller.beats_.load() >= 200; }, 20s, 5ms);
  m.stop();
  const auto counts = window.counts();
  ASSERT_GE(controller.cycles_.load(), 300u) << "the tasks did not run long enough to prove anything";
  EXPECT_GE(controller.beats_.load(), 200u);
  EXPECT_GE(device.pings_.load(), 200u);
  EXPECT_GE(controller.ok_reads_.load(), 200u);
  // statistics() is the newest state row, which the last cycle's accounting may not be in yet.
  const auto ran = device.statistics().cycles + controller.statistics().cycles;
  EXPECT_GE(counts.cycles, ran) << "the guard did not sample every cycle";
  EXPECT_LE(counts.cycles, ran + 2);
  EXPECT_RT_CLEAN(counts);
}

TEST(RtGuard, SteppedModeServesEverythingCleanly) {
  saw::testing::GuardWindow window;
  const auto config = saw::TaskConfig::periodic(1ms, 0);
  Device device(config);
  Controller controller(config);
  Helper helper;
  saw::Manager m;
  m.add(device);
  m.add(controller);
  m.add(helper);
  connect_all(m);
  m.start_stepped();
  m.step_until(500'000'000);
  m.stop();
  const auto counts = window.counts();
  EXPECT_EQ(controller.cycles_.load(), 501u);
  EXPECT_EQ(device.pings_.load(), 500u);  // the last ping waits for a cycle that never comes
  EXPECT_EQ(counts.cycles, 2 * 501u);
  EXPECT_RT_CLEAN(counts);
}

// A stalled consumer: a 1 ms producer fills the command mailbox and the event mailbox of a task
// that drains them every 100 ms. Refusing is an RT path too: counted, returned, nothing else.
class Sink : public saw::Task {
 public:
  Sink() : Task("sink", saw::TaskConfig::periodic(100ms, 0)) {
    provide("in").add_command_write<Vec3>("push", [this](const Vec3&) { ++pushed_; });
    require("out").add_event_handler_write<Vec3>("sent", [this](const Vec3&) { ++received_; });
  }
  void run() override {}
  std::uint64_t pushed_ = 0, received_ = 0;
};

class Source : public saw::Task {
 public:
  Source() : Task("source", saw::TaskConfig::periodic(1ms, 0)) {
    require("in").add_function("push", push_);
    sent_ = &provide("out").add_event_write<Vec3>("sent");
  }
  void run() override {
    if (push_(Vec3{1, 2, 3}) == saw::Status::queue_full) ++commands_full_;
    if ((*sent_)(Vec3{4, 5, 6}) == saw::Status::queue_full) ++events_full_;
  }
  std::uint64_t commands_full_ = 0, events_full_ = 0;
  saw::EventWrite<Vec3>* sent_;

 private:
  saw::FunctionWrite<Vec3> push_;
};

TEST(RtGuard, AFullCommandMailboxAndARefusedEventAreRtSafe) {
  saw::testing::GuardWindow window;
  Source source;
  Sink sink;
  saw::Manager m;
  m.add(source);
  m.add(sink);
  m.connect("source", "in", "sink", "in");
  m.connect("sink", "out", "source", "out");
  m.start_stepped();
  m.step_until(1'000'000'000);
  m.stop();
  const auto counts = window.counts();
  // Each 100 ms the sink drains 64 (the default capacity): about a third of the pushes are refused.
  EXPECT_GT(source.commands_full_, 300u)
      << "the command mailbox should have been full for a third of the cycles";
  EXPECT_GT(source.events_full_, 300u) << "the event mailbox should have been full for a third of the cycles";
  EXPECT_EQ(source.sent_->dropped(), source.events_full_);
  EXPECT_GT(sink.pushed_, 0u);
  EXPECT_GT(sink.received_, 0u);
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
