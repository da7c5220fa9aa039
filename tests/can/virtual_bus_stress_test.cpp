// The virtual bus under ThreadSanitizer: producer and reader threads, each with its own
// attachment to one shared mapping, so that every access to the ring meets at the same address.
#include <thread>
#include <vector>

#include "can_test_support.hpp"

namespace {

using namespace saw::can;
using saw::can::testing::config;
using saw::can::testing::numbered;
using saw::can::testing::ScopedBusName;
using saw::can::testing::sequence_of;

struct Outcome {
  bool in_order = true;
  bool foreign = false;
  BusCounters counters;
  std::uint64_t received = 0;
};

void stress(std::size_t ring, int producers, int readers, std::uint32_t per_producer, bool exact) {
  ScopedBusName bus("stress");
  const std::uint64_t total = static_cast<std::uint64_t>(producers) * per_producer;
  VirtualBusOptions options;
  options.incomplete_grace = 30'000'000'000;  // under TSan a preempted producer is slow, not dead
  std::vector<std::unique_ptr<VirtualBus>> reader_buses, producer_buses;
  for (int r = 0; r < readers; ++r)
    reader_buses.push_back(std::make_unique<VirtualBus>(config(bus.uri(), false, ring), bus.name(), options));
  for (int p = 0; p < producers; ++p)
    producer_buses.push_back(std::make_unique<VirtualBus>(config(bus.uri(), false, ring), bus.name()));
  std::vector<Outcome> outcomes(static_cast<std::size_t>(readers));
  std::vector<std::thread> threads;
  for (int r = 0; r < readers; ++r)
    threads.emplace_back([&, r] {
      auto& o = outcomes[static_cast<std::size_t>(r)];
      auto& b = *reader_buses[static_cast<std::size_t>(r)];
      std::vector<std::int64_t> last(static_cast<std::size_t>(producers), -1);
      std::vector<Received> out(16);
      const auto deadline = saw::monotonic_now() + 120'000'000'000;
      for (;;) {
        const auto c = b.counters();
        if (c.received + c.overruns + c.malformed >= total || saw::monotonic_now() > deadline) break;
        const std::size_t n = b.receive(out);
        for (std::size_t i = 0; i < n; ++i) {
          const std::uint32_t p = out[i].frame.id - 1;
          if (p >= static_cast<std::uint32_t>(producers)) {
            o.foreign = true;
            continue;
          }
          const std::int64_t s = sequence_of(out[i].frame);
          if (exact ? s != last[p] + 1 : s <= last[p]) o.in_order = false;
          last[p] = s;
        }
        o.received += n;
        if (n == 0) std::this_thread::yield();
      }
      o.counters = b.counters();
    });
  for (int p = 0; p < producers; ++p)
    threads.emplace_back([&, p] {
      auto& b = *producer_buses[static_cast<std::size_t>(p)];
      for (std::uint32_t i = 0; i < per_producer; ++i) {
        const Frame f = numbered(static_cast<std::uint32_t>(p) + 1, i);
        (void)b.send(std::span<const Frame>(&f, 1));
        if (i % 128 == 0) std::this_thread::yield();
      }
    });
  for (auto& t : threads) t.join();
  for (const auto& o : outcomes) {
    EXPECT_FALSE(o.foreign);
    EXPECT_TRUE(o.in_order);
    EXPECT_EQ(o.counters.received, o.received);
    EXPECT_EQ(o.counters.received + o.counters.overruns + o.counters.malformed, total);
    if (exact) {
      EXPECT_EQ(o.counters.received, total);
    } else {
      EXPECT_GT(o.counters.overruns, 0u) << "the small ring was never overrun: the test proved nothing";
    }
  }
}

TEST(VirtualBusStress, ThreeProducersThreeReadersALargeRingEveryFrameOnceInOrder) {
  stress(1 << 17, 3, 3, 40'000, true);
}

TEST(VirtualBusStress, ThreeProducersThreeReadersASmallRingLossesCountedOrderKept) {
  stress(32, 3, 3, 100'000, false);
}

}  // namespace
