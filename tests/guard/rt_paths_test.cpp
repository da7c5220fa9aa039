// Proves the RT paths (a periodic task serving commands, events, reads and logging) do not
// allocate or lock after start, with malloc and pthread_mutex_lock replaced by counters.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "alloc_guard.hpp"
#include "saw/manager.hpp"

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

TEST(AllocationGuard, PeriodicTasksServeEverythingWithoutAllocatingOrLocking) {
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
  saw::testing::guard_reset();  // start-up may allocate; from here on the RT threads must not
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while ((controller.cycles_.load() < 300 || controller.beats_.load() < 200) &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(5ms);  // polling with a deadline; the assertions below decide
  m.stop();
  const auto counts = saw::testing::guard_counts();
  ASSERT_GE(controller.cycles_.load(), 300u) << "the tasks did not run long enough to prove anything";
  EXPECT_GE(controller.beats_.load(), 200u);
  EXPECT_GE(device.pings_.load(), 200u);
  EXPECT_GE(controller.ok_reads_.load(), 200u);
  EXPECT_EQ(counts.allocations, 0u) << "an RT thread allocated (first size " << counts.first_allocation_size
                                    << ")";
  EXPECT_EQ(counts.locks, 0u) << "an RT thread locked a mutex";
}

TEST(AllocationGuard, SteppedModeServesEverythingWithoutAllocatingOrLocking) {
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
  saw::testing::guard_reset();
  m.step_until(500'000'000);
  const auto counts = saw::testing::guard_counts();
  m.stop();
  EXPECT_EQ(controller.cycles_.load(), 501u);
  EXPECT_EQ(device.pings_.load(), 500u);  // the last ping waits for a cycle that never comes
  EXPECT_EQ(counts.allocations, 0u) << "first size " << counts.first_allocation_size;
  EXPECT_EQ(counts.locks, 0u);
}

// The guard itself must catch what it is there to catch.
class Offender : public saw::Task {
 public:
  Offender() : Task("offender", saw::TaskConfig::periodic(1ms, 0)) {}
  void run() override {
    std::vector<int> v(16, 1);  // allocates
    std::lock_guard lock(mutex_);
    sum_ += v[3];
  }
  int sum_ = 0;
  std::mutex mutex_;
};

TEST(AllocationGuard, DetectsAllocationAndLockInRtPath) {
  Offender o;
  saw::Manager m;
  m.add(o);
  m.start_stepped();
  saw::testing::guard_reset();
  for (int i = 0; i < 5; ++i) m.step();
  const auto counts = saw::testing::guard_counts();
  m.stop();
  EXPECT_EQ(counts.allocations, 5u);
  EXPECT_EQ(counts.first_allocation_size, 16 * sizeof(int));
  EXPECT_EQ(counts.locks, 5u);
}

TEST(AllocationGuard, IgnoresNonRtThreads) {
  saw::testing::guard_reset();
  auto p = std::make_unique<std::vector<int>>(100);
  std::mutex mu;
  { std::lock_guard lock(mu); }
  EXPECT_EQ(saw::testing::guard_counts().allocations, 0u);
  EXPECT_EQ(saw::testing::guard_counts().locks, 0u);
}

}  // namespace
