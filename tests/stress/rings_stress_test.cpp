// The lock-free rings under two real threads: nothing lost, duplicated, reordered or torn.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <thread>
#include <vector>

#include "saw/detail/mailbox.hpp"
#include "saw/detail/spsc_ring.hpp"
#include "saw/log.hpp"

namespace {

constexpr std::uint64_t messages = 300'000;

TEST(RingStress, SpscRingDeliversEverySlotInOrder) {
  saw::detail::SpscRing ring(8, 40);
  std::atomic<std::uint64_t> torn{0};
  std::thread consumer([&] {
    std::uint64_t expected = 0;
    while (expected < messages) {
      const std::byte* s = ring.front();
      if (s == nullptr) continue;
      std::uint64_t words[5];
      std::memcpy(words, s, sizeof words);
      for (int i = 0; i < 5; ++i)
        if (words[i] != expected * 5 + static_cast<std::uint64_t>(i)) torn.fetch_add(1);
      ring.pop();
      ++expected;
    }
  });
  std::uint64_t full = 0;
  for (std::uint64_t k = 0; k < messages;) {
    std::byte* s = ring.try_reserve();
    if (s == nullptr) {
      ++full;
      continue;
    }
    std::uint64_t words[5];
    for (int i = 0; i < 5; ++i) words[i] = k * 5 + static_cast<std::uint64_t>(i);
    std::memcpy(s, words, sizeof words);
    ring.commit();
    ++k;
  }
  consumer.join();
  EXPECT_EQ(torn.load(), 0u);
  EXPECT_EQ(ring.size_approx(), 0u);
  RecordProperty("full_retries", static_cast<int>(full));
}

TEST(RingStress, MailboxCountsEveryRefusedPushAndRunsEveryAcceptedOne) {
  std::uint64_t executed = 0, last = 0;
  bool ordered = true;
  saw::detail::Mailbox mailbox("stress", 16, sizeof(std::uint64_t));
  struct Target {
    std::uint64_t* executed;
    std::uint64_t* last;
    bool* ordered;
  } target{&executed, &last, &ordered};
  mailbox.add_target({[](void* self, const void* arg) {
                        auto* t = static_cast<Target*>(self);
                        std::uint64_t v;
                        std::memcpy(&v, arg, sizeof v);
                        if (v <= *t->last && *t->executed != 0) *t->ordered = false;
                        *t->last = v;
                        ++*t->executed;
                      },
                      &target});
  std::atomic<bool> done{false};
  std::thread consumer([&] {
    while (!done.load(std::memory_order_acquire)) mailbox.drain();
    mailbox.drain();
  });
  std::uint64_t accepted = 0, refused = 0;
  for (std::uint64_t k = 1; k <= messages; ++k) {
    if (mailbox.push(0, &k, sizeof k) == saw::Status::ok)
      ++accepted;
    else
      ++refused;
  }
  done.store(true, std::memory_order_release);
  consumer.join();
  EXPECT_EQ(executed, accepted);
  EXPECT_EQ(mailbox.full_count(), refused);
  EXPECT_EQ(mailbox.executed_count(), accepted);
  EXPECT_TRUE(ordered);
}

TEST(RingStress, LogRingKeepsEachProducersOrderAndCountsDrops) {
  constexpr std::uint64_t per_producer = 100'000;
  std::atomic<bool> done{false};
  std::uint64_t received = 0;
  std::uint64_t last[2] = {0, 0};
  bool ordered = true;
  std::thread consumer([&] {
    saw::LogRecord r;
    for (;;) {
      const bool finished = done.load(std::memory_order_acquire);
      while (saw::log_ring().pop(r)) {
        const auto producer = static_cast<std::size_t>(r.args[0].u);
        if (r.args[1].u <= last[producer]) ordered = false;
        last[producer] = r.args[1].u;
        ++received;
      }
      if (finished) break;
    }
  });
  std::atomic<std::uint64_t> accepted{0};
  auto producer = [&](std::uint64_t id) {
    for (std::uint64_t k = 1; k <= per_producer; ++k)
      if (saw::log(saw::LogLevel::debug, "stress", "{} {}", id, k)) accepted.fetch_add(1);
  };
  const auto dropped_before = saw::log_ring().dropped();
  std::thread a(producer, 0), b(producer, 1);
  a.join();
  b.join();
  done.store(true, std::memory_order_release);
  consumer.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(received, accepted.load());
  EXPECT_EQ(accepted.load() + (saw::log_ring().dropped() - dropped_before), 2 * per_producer);
}

}  // namespace

namespace {

// A ring in "shared memory" (here: this process's heap), with a producer's view of it.
struct ExternalRing {
  static constexpr std::size_t capacity = 16, slot = 32;
  saw::detail::SpscRingControl control;
  alignas(64) std::byte storage[capacity * slot];
  saw::detail::SpscRing producer{&control, storage, capacity, slot};
};

// A reconnect: the mailbox's consumer switches from the dead server's ring to the new one's
// while both producers write. Everything the new producer sends arrives, in order, and nothing
// from the old ring is run after the switch.
TEST(RingStress, AMailboxSwitchesToAnOfferedRingWhileBothProducersRun) {
  constexpr std::uint64_t from_new = 100'000;
  auto old_ring = std::make_unique<ExternalRing>();
  auto new_ring = std::make_unique<ExternalRing>();
  saw::detail::SpscRing new_consumer(&new_ring->control, new_ring->storage, ExternalRing::capacity,
                                     ExternalRing::slot);
  saw::detail::Mailbox mailbox("remote events", &old_ring->control, old_ring->storage, ExternalRing::capacity,
                               ExternalRing::slot);
  std::vector<std::uint64_t> old_seen, new_seen;
  old_seen.reserve(1 << 20);
  new_seen.reserve(from_new);
  std::uint64_t old_after_switch = 0;
  mailbox.add_target({[](void* self, const void* arg) {
                        auto* v = static_cast<std::vector<std::uint64_t>*>(self);
                        std::uint64_t x;
                        std::memcpy(&x, arg, sizeof x);
                        v->push_back(x);
                      },
                      &old_seen});
  mailbox.add_target({[](void* self, const void* arg) {
                        auto* v = static_cast<std::vector<std::uint64_t>*>(self);
                        std::uint64_t x;
                        std::memcpy(&x, arg, sizeof x);
                        v->push_back(x);
                      },
                      &new_seen});
  const auto produce = [](saw::detail::SpscRing& ring, std::uint32_t target, std::uint64_t value) {
    std::byte* s = ring.try_reserve();
    if (s == nullptr) return false;
    std::memcpy(s, &target, sizeof target);
    std::memcpy(s + saw::detail::Mailbox::header_bytes(), &value, sizeof value);
    ring.commit();
    return true;
  };
  std::atomic<bool> old_stop{false};
  std::thread old_producer([&] {
    for (std::uint64_t k = 0; !old_stop.load(std::memory_order_relaxed);)
      if (produce(old_ring->producer, 0, k)) ++k;
  });
  std::thread new_producer([&] {
    for (std::uint64_t k = 0; k < from_new;)
      if (produce(new_ring->producer, 1, k)) ++k;
  });
  std::thread consumer([&] {
    while (new_seen.size() < from_new) {
      const auto before = new_seen.size();
      const auto olds = old_seen.size();
      mailbox.drain();
      if (before != 0 && old_seen.size() != olds) old_after_switch += old_seen.size() - olds;
    }
  });
  while (!mailbox.offer_ring(&new_consumer)) {
  }
  while (mailbox.offer_pending()) {
  }
  old_stop.store(true);
  old_producer.join();
  new_producer.join();
  consumer.join();
  ASSERT_EQ(new_seen.size(), from_new);
  for (std::uint64_t k = 0; k < from_new; ++k) ASSERT_EQ(new_seen[k], k) << "lost or reordered";
  for (std::size_t k = 1; k < old_seen.size(); ++k) ASSERT_GT(old_seen[k], old_seen[k - 1]);
  EXPECT_EQ(old_after_switch, 0u);
  EXPECT_FALSE(mailbox.offer_pending());
}

}  // namespace
