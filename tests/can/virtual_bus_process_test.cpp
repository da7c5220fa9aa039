// The virtual bus across processes: forked producers and readers, each with its own attachment
// and its own mapping, as separate programs on one machine use it.
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <thread>
#include <vector>

#include "can_test_support.hpp"

namespace {

using namespace saw::can;
using saw::can::testing::config;
using saw::can::testing::numbered;
using saw::can::testing::ScopedBusName;
using saw::can::testing::sequence_of;

// Exit codes of a reader child.
enum ReaderExit {
  ok = 0,
  foreign_frame = 3,
  out_of_order = 4,
  timed_out = 5,
  bad_accounting = 6,
  open_failed = 7,
  no_loss = 8
};

struct Plan {
  std::string name;
  int producers = 3;
  std::uint32_t per_producer = 3000;
  bool exact = true;  // the ring holds everything: every reader must see every frame
  bool slow_readers = false;
};

// A reader: attaches, says so on `ready`, then checks what arrives. Exact: each producer's frames
// exactly once, in its order. Not exact: in order without repeats, and every ticket accounted
// for (read, or counted lost or malformed).
int run_reader(const Plan& plan, int ready) {
  std::unique_ptr<VirtualBus> bus;
  VirtualBusOptions options;
  options.incomplete_grace = 10'000'000'000;  // a producer preempted mid-write is waited for
  try {
    bus = std::make_unique<VirtualBus>(config("virtual:" + plan.name), plan.name, options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "reader: %s\n", e.what());
    return open_failed;
  }
  const char byte = 1;
  if (::write(ready, &byte, 1) != 1) return open_failed;
  const std::uint64_t total = static_cast<std::uint64_t>(plan.producers) * plan.per_producer;
  std::vector<std::int64_t> last(static_cast<std::size_t>(plan.producers), -1);
  std::vector<Received> out(32);
  const auto deadline = saw::monotonic_now() + 60'000'000'000;
  std::uint64_t polls = 0;
  for (;;) {
    const auto c = bus->counters();
    if (c.received + c.overruns + c.malformed >= total) break;
    if (saw::monotonic_now() > deadline) {
      std::fprintf(stderr, "reader: timed out: received %llu, lost %llu, malformed %llu of %llu\n",
                   static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.overruns),
                   static_cast<unsigned long long>(c.malformed), static_cast<unsigned long long>(total));
      return timed_out;
    }
    const std::size_t n = bus->receive(out);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t p = out[i].frame.id - 1;
      if (p >= static_cast<std::uint32_t>(plan.producers) || out[i].frame.len != 4) return foreign_frame;
      const std::int64_t s = sequence_of(out[i].frame);
      const bool in_order = plan.exact ? s == last[p] + 1 : s > last[p];
      if (!in_order) {
        std::fprintf(stderr, "reader: producer %u: %lld after %lld\n", p, static_cast<long long>(s),
                     static_cast<long long>(last[p]));
        return out_of_order;
      }
      last[p] = s;
    }
    if (n == 0) std::this_thread::yield();
    if (plan.slow_readers && ++polls % 64 == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  const auto c = bus->counters();
  if (plan.exact && (c.received != total || c.overruns != 0 || c.malformed != 0)) return bad_accounting;
  if (c.received + c.overruns + c.malformed != total) return bad_accounting;
  if (!plan.exact && c.overruns == 0) return no_loss;  // the small ring proved nothing
  return ok;
}

int run_producer(const Plan& plan, int index) {
  try {
    VirtualBus bus(config("virtual:" + plan.name), plan.name);
    for (std::uint32_t i = 0; i < plan.per_producer; ++i) {
      const Frame f = numbered(static_cast<std::uint32_t>(index) + 1, i);
      if (bus.send(std::span<const Frame>(&f, 1)) != 1) return 1;
      if (i % 256 == 0) std::this_thread::yield();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "producer: %s\n", e.what());
    return 2;
  }
  return 0;
}

int exit_code(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
}

// Readers first (each reports when attached), then the producers, all at once.
void run_plan(const Plan& plan, int readers) {
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  std::vector<pid_t> reader_pids, producer_pids;
  for (int r = 0; r < readers; ++r) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::close(ready[0]);
      ::_exit(run_reader(plan, ready[1]));
    }
    reader_pids.push_back(pid);
  }
  ::close(ready[1]);
  for (int r = 0; r < readers; ++r) {
    pollfd p{ready[0], POLLIN, 0};
    ASSERT_EQ(::poll(&p, 1, 20'000), 1) << "a reader did not attach";
    char byte;
    ASSERT_EQ(::read(ready[0], &byte, 1), 1) << "a reader failed to attach";
  }
  ::close(ready[0]);
  for (int p = 0; p < plan.producers; ++p) {
    const pid_t pid = ::fork();
    if (pid == 0) ::_exit(run_producer(plan, p));
    producer_pids.push_back(pid);
  }
  for (const pid_t pid : producer_pids) EXPECT_EQ(exit_code(pid), 0) << "a producer failed";
  for (const pid_t pid : reader_pids) EXPECT_EQ(exit_code(pid), 0) << "a reader failed (see ReaderExit)";
}

TEST(VirtualBusProcesses, EveryReaderSeesEveryProducersFramesOnceAndInItsOrder) {
  ScopedBusName bus("mp");
  Plan plan;
  plan.name = bus.name();
  // A ring larger than all the traffic: nothing can be lost, so everything must arrive.
  { VirtualBus creator(config(bus.uri(), false, 16384), bus.name()); }
  run_plan(plan, 2);
}

TEST(VirtualBusProcesses, SlowReadersOfASmallRingLoseFramesButNeverTheirOrderOrCount) {
  ScopedBusName bus("mps");
  Plan plan;
  plan.name = bus.name();
  plan.exact = false;
  plan.slow_readers = true;
  plan.per_producer = 20000;
  { VirtualBus creator(config(bus.uri(), false, 64), bus.name()); }
  run_plan(plan, 2);
}

}  // namespace
