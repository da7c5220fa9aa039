// Lifecycle, real threads, the state table's API, the pacer, the histogram and the RT log.
#include <gtest/gtest.h>

#include <sstream>

#include "core_fixtures.hpp"
#include "saw/detail/pacer.hpp"
#include "saw/log.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using namespace saw::testing;
using namespace std::chrono_literals;

class Counted : public saw::Task {
 public:
  Counted() : Task("counted", one_ms()) {}
  void startup() override { ++startups; }
  void cleanup() override { ++cleanups; }
  int startups = 0, cleanups = 0;
};

TEST(Lifecycle, ConstructedReadyActiveFinished) {
  Counted t;
  saw::Manager m;
  m.add(t);
  EXPECT_EQ(t.lifecycle(), saw::Lifecycle::constructed);
  m.start_stepped();
  EXPECT_EQ(t.lifecycle(), saw::Lifecycle::active);
  EXPECT_EQ(t.startups, 1);
  EXPECT_THROW(t.provide("late"), std::logic_error);
  EXPECT_THROW(t.provided("task")->add_command_void("late", [] {}), std::logic_error);
  m.stop();
  m.stop();  // idempotent
  EXPECT_EQ(t.lifecycle(), saw::Lifecycle::finished);
  EXPECT_EQ(t.cleanups, 1);
}

TEST(Lifecycle, RealThreadsExchangeCommandsAndEvents) {
  TaskServer server("server", one_ms());
  class Emitter : public Client {
   public:
    using Client::Client;
    void run() override { (void)push(1); }
  } client;
  saw::Manager m;
  m.add(server);
  m.add(client);
  m.connect("client", "r", "server", "p");
  m.start();
  Vec v;
  // Bounded, not asserted: the assertions below decide.
  (void)wait_for([&] { return client.position(v) == saw::Status::ok && v.x >= 50; }, 10s, 2ms);
  m.stop();
  EXPECT_GE(v.x, 50);
  EXPECT_GT(server.statistics().cycles, 0u);
  EXPECT_GT(server.executed.size(), 10u);
}

TEST(StateTable, HistoryTimeLookupsAndOverwrittenRows) {
  struct Big {
    double d[80];
  };
  double x = 0;
  Big big{};
  saw::StateTable t(8);
  const auto cx = t.add_column("x", &x);
  const auto cb = t.add_column("big", &big);
  t.finalize();
  EXPECT_THROW(t.add_column("late", &x), std::logic_error);
  double out = -1;
  EXPECT_EQ(t.read_latest(cx, out), saw::Status::no_data);
  for (int i = 0; i < 20; ++i) {
    x = i;
    big.d[79] = i;
    t.advance(i * 10);
  }
  std::array<double, 16> h{};
  EXPECT_EQ(t.read_history(cx, std::span<double>(h)), 7u) << "capacity - 1 rows are kept readable";
  EXPECT_EQ(h[0], 13);
  EXPECT_EQ(h[6], 19);
  ASSERT_EQ(t.read_at_or_before(cx, 175, out), saw::Status::ok);
  EXPECT_EQ(out, 17);
  ASSERT_EQ(t.read_at_or_before(cx, 180, out), saw::Status::ok);
  EXPECT_EQ(out, 18);
  EXPECT_EQ(t.read_at_or_before(cx, 20, out), saw::Status::overwritten);
  EXPECT_EQ(t.read_tick(cx, 3, out), saw::Status::overwritten);
  Big b{};
  ASSERT_EQ(t.read_latest(cb, b), saw::Status::ok);
  EXPECT_EQ(b.d[79], 19);
}

TEST(Pacer, OverrunsSkipWholePeriodsAndKeepPhase) {
  saw::detail::Pacer p(1000, 100);
  EXPECT_EQ(p.finish_cycle(1050), 0u);
  EXPECT_EQ(p.next_wakeup(), 1100);
  EXPECT_EQ(p.finish_cycle(1100 + 350), 3u);  // ended 3.5 periods late
  EXPECT_EQ(p.next_wakeup(), 1500);
  EXPECT_EQ((p.next_wakeup() - 1000) % 100, 0);
  EXPECT_EQ(p.overruns(), 1u);
  EXPECT_EQ(p.missed_periods(), 3u);
  EXPECT_EQ(p.finish_cycle(1510), 0u);
  EXPECT_EQ(p.next_wakeup(), 1600);
}

TEST(LatencyHistogram, BinsPercentilesAndCyclictestFormat) {
  saw::LatencyHistogram h(10);
  for (int i = 0; i < 98; ++i) h.record(1500);  // bin 1
  h.record(5200);                               // bin 5
  h.record(50'000);                             // overflow
  EXPECT_EQ(h.count(1), 98u);
  EXPECT_EQ(h.overflows(), 1u);
  EXPECT_EQ(h.max(), 50'000);
  EXPECT_EQ(h.percentile(0.5), 2000);
  std::ostringstream os;
  const saw::LatencyHistogram* hs[] = {&h};
  saw::write_cyclictest_histogram(os, hs);
  const auto text = os.str();
  EXPECT_NE(text.find("# Histogram\n000000 000000\n000001 000098\n"), std::string::npos) << text;
  EXPECT_NE(text.find("# Total: 000000100"), std::string::npos) << text;
  EXPECT_NE(text.find("# Max Latencies: 00050"), std::string::npos) << text;
  EXPECT_NE(text.find("# Histogram Overflows: 00001"), std::string::npos) << text;
}

TEST(Log, FormatsArgumentsAndCountsDrops) {
  saw::LogRecord r;
  while (saw::log_ring().pop(r)) {
  }
  ASSERT_TRUE(saw::log(saw::LogLevel::warning, "src", "a {} b {} c {} d {}", -3, 4u, 2.5, "text"));
  ASSERT_TRUE(saw::log_ring().pop(r));
  const auto s = saw::format_log_record(r);
  EXPECT_NE(s.find("warning src: a -3 b 4 c 2.5 d text"), std::string::npos) << s;
  ASSERT_TRUE(saw::log(saw::LogLevel::info, "src", "code {:x}, {:x} and {}", 0x2310u, 0x4u, 7));
  ASSERT_TRUE(saw::log_ring().pop(r));
  const auto hex = saw::format_log_record(r);
  EXPECT_NE(hex.find("info src: code 0x2310, 0x0004 and 7"), std::string::npos) << hex;
  const auto dropped = saw::log_ring().dropped();
  std::size_t accepted = 0;
  for (std::size_t i = 0; i < saw::LogRing::capacity + 10; ++i)
    accepted += saw::log(saw::LogLevel::info, "s", "{}", i);
  EXPECT_EQ(accepted, saw::LogRing::capacity);
  EXPECT_EQ(saw::log_ring().dropped() - dropped, 10u);
  ASSERT_TRUE(saw::log_ring().pop(r));
  EXPECT_EQ(r.args[0].u, 0u) << "first in, first out";
  while (saw::log_ring().pop(r)) {
  }
}

}  // namespace

namespace {

// Periodic tasks wake on a grid aligned to the monotonic clock plus their offset: in every
// process of a host, and in a fixed order within a period (producers before consumers).
TEST(Task, WakeUpsAreOnTheClockAlignedGridPlusTheOffset) {
  class Ticker : public saw::Task {
   public:
    explicit Ticker(std::chrono::nanoseconds offset)
        : Task("ticker" + std::to_string(offset.count()), [&] {
            auto c = saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0);
            c.offset = offset;
            return c;
          }()) {}
    void run() override {}
  } a(std::chrono::nanoseconds(0)), b(std::chrono::microseconds(300));
  saw::Manager m;
  m.add(a);
  m.add(b);
  m.start();
  // Bounded, not asserted: the assertions below decide.
  (void)wait_for([&] { return a.statistics().cycles >= 20 && b.statistics().cycles >= 20; });
  m.stop();
  ASSERT_GE(a.statistics().cycles, 20u);
  ASSERT_GE(b.statistics().cycles, 20u);
  // Scheduled (not actual) wake-up times: exact, whatever the machine does.
  EXPECT_EQ(a.statistics().last_wakeup % 1'000'000, 0);
  EXPECT_EQ(b.statistics().last_wakeup % 1'000'000, 300'000);
}

}  // namespace
