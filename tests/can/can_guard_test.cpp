// The CAN buses' RT paths, receive() and send(), do none of what the project's RT guard counts
// (tests/guard/rt_guard.cpp: allocations, locks, waits, stdio, blocking, page faults), from the
// first cycle: the virtual bus (normal traffic, a lapped reader, a dead producer's slot) and the
// SocketCAN backend (through a SOCK_SEQPACKET pair, as AF_CAN is missing here).
#include <sys/socket.h>

#include <vector>

#include "can_test_support.hpp"
#include "guard_support.hpp"
#include "saw/can/socketcan_bus.hpp"

namespace {

using namespace std::chrono_literals;
using namespace saw::can;
using saw::can::testing::config;
using saw::can::testing::numbered;
using saw::can::testing::RawSegment;
using saw::can::testing::ScopedBusName;
using saw::testing::BodyTask;
using saw::testing::GuardWindow;

// Steps `body` as a 1 ms periodic task's cycle, `cycles` times, inside the guard's window.
saw::testing::GuardCounts step(std::function<void(std::uint64_t)> body, int cycles) {
  GuardWindow window;
  BodyTask task("can", saw::TaskConfig::periodic(1ms, 0), std::move(body));
  saw::Manager m;
  m.add(task);
  m.start_stepped();
  for (int i = 0; i < cycles; ++i) m.step();
  m.stop();
  return window.counts();
}

TEST(CanRtGuard, VirtualBusSendAndReceiveAreRtClean) {
  ScopedBusName bus("guard");
  const auto a = open_bus(config(bus.uri(), true));
  const auto b = open_bus(config(bus.uri(), true));
  std::vector<Frame> frames(8);
  std::vector<Received> in(16);
  std::uint64_t received = 0;
  const auto counts = step(
      [&](std::uint64_t cycle) {
        for (std::uint32_t i = 0; i < frames.size(); ++i)
          frames[i] = numbered(0x100 + i, static_cast<std::uint32_t>(cycle));
        frames[7].flags = CANFD_FDF | CANFD_BRS;
        frames[7].len = 64;
        (void)a->send(frames);
        received += b->receive(in);
        (void)a->receive(in);  // its own frames: passed over
      },
      500);
  EXPECT_EQ(counts.cycles, 500u);
  EXPECT_EQ(received, 500u * 8);
  EXPECT_RT_CLEAN(counts);
}

TEST(CanRtGuard, AVirtualBusReaderWaitingOnADeadProducerThenLappedIsRtClean) {
  ScopedBusName bus("guardlap");
  VirtualBusOptions options;
  options.incomplete_grace = 1;  // skip a dead producer's slot at the second look
  VirtualBus reader(config(bus.uri(), false, 16), bus.name(), options);
  const auto writer = open_bus(config(bus.uri()));
  RawSegment raw(bus.name());
  ASSERT_EQ(raw.header().write_ticket.fetch_add(1), 0u);  // a producer took ticket 0 and died
  raw.slot(0).sequence.store(1);
  const Frame one = numbered(1, 0);
  std::vector<Frame> burst(40, numbered(1, 0));
  std::vector<Received> in(4);
  const auto counts = step(
      [&](std::uint64_t cycle) {
        if (cycle < 100 && cycle % 10 == 0) (void)writer->send(std::span<const Frame>(&one, 1));
        if (cycle >= 100 && cycle % 10 == 0) (void)writer->send(burst);  // more than the ring
        (void)reader.receive(in);
      },
      200);
  EXPECT_EQ(reader.abandoned(), 1u) << "the dead producer's slot was not skipped in the cycle";
  EXPECT_GT(reader.counters().overruns, 1u) << "the reader was never lapped";
  EXPECT_RT_CLEAN(counts);
}

TEST(CanRtGuard, SocketCanSendAndReceiveAreRtClean) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK, 0, sv), 0);
  SocketCanBus a(sv[0], "socketcan:pair0", true);
  SocketCanBus b(sv[1], "socketcan:pair1", true);
  std::vector<Frame> frames(4);
  std::vector<Received> in(16);
  std::uint64_t received = 0;
  const auto counts = step(
      [&](std::uint64_t cycle) {
        for (std::uint32_t i = 0; i < frames.size(); ++i)
          frames[i] = numbered(0x200 + i, static_cast<std::uint32_t>(cycle));
        frames[3].flags = CANFD_FDF;
        frames[3].len = 32;
        (void)a.send(frames);
        received += b.receive(in);
        (void)b.receive(in);  // an empty socket: EAGAIN, at once
      },
      500);
  EXPECT_EQ(received, 500u * 4);
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
