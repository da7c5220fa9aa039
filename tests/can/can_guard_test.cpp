// The CAN buses' RT paths, receive() and send(), do none of what the project's RT guard counts
// (tests/guard/rt_guard.cpp: allocations, locks, waits, stdio, blocking, page faults), from the
// first cycle: the virtual bus (normal traffic, a lapped reader, a dead producer's slot) and the
// SocketCAN backend, both through a SOCK_SEQPACKET pair (everywhere) and on a real CAN_RAW socket
// on the interface SAW_TEST_CAN_INTERFACE names (the PREEMPT_RT guest's vcan0; the host has no AF_CAN).
#include <sys/socket.h>

#include <cstdlib>
#include <string>
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

// Steps the SocketCAN send/receive cycle 500 times: `a` sends four frames (one FD), `b` receives
// them, then reads its empty socket again (EAGAIN, at once). Returns the guard's counts; `received`
// is what `b` returned in the cycles.
saw::testing::GuardCounts socketcan_cycles(Bus& a, Bus& b, std::uint64_t& received) {
  std::vector<Frame> frames(4);
  std::vector<Received> in(16);
  return step(
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
}

// The interface SAW_TEST_CAN_INTERFACE names, or empty when it is unset.
std::string test_interface() {
  const char* e = std::getenv("SAW_TEST_CAN_INTERFACE");
  return e != nullptr ? e : "";
}

// The backend's own code on a socket that is not AF_CAN: runs everywhere.
TEST(CanRtGuard, SocketCanSendAndReceiveAreRtCleanOnASocketPair) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK, 0, sv), 0);
  SocketCanBus a(sv[0], "socketcan:pair0", true);
  SocketCanBus b(sv[1], "socketcan:pair1", true);
  std::uint64_t received = 0;
  const auto counts = socketcan_cycles(a, b, received);
  EXPECT_EQ(counts.cycles, 500u);
  EXPECT_EQ(received, 500u * 4);
  EXPECT_RT_CLEAN(counts);
}

// The backend as opened in a deployment (socketcan:<ifname>, CAN FD): two CAN_RAW sockets on one
// interface, the kernel's loopback carrying one's frames to the other. Where the variable is set,
// a failure to open the bus fails the test: it was asked to run on AF_CAN.
TEST(CanRtGuard, SocketCanSendAndReceiveAreRtCleanOnAfCan) {
  const std::string ifname = test_interface();
  if (ifname.empty())
    GTEST_SKIP() << "SAW_TEST_CAN_INTERFACE is not set: no CAN interface to run on (the host kernel has no "
                    "AF_CAN; the PREEMPT_RT guest's guard check runs this on vcan0)";
  const auto a = open_bus(config("socketcan:" + ifname, true));
  const auto b = open_bus(config("socketcan:" + ifname, true));
  std::uint64_t received = 0;
  const auto counts = socketcan_cycles(*a, *b, received);
  // The loopback delivers while the sender's call runs (the NET_RX softirq at its bottom-half
  // enable); a frame still in flight after the last cycle is read here, outside the window.
  const std::size_t late = saw::can::testing::drain(*b).size();
  EXPECT_EQ(counts.cycles, 500u);
  EXPECT_EQ(a->counters().sent, 500u * 4);
  EXPECT_EQ(a->counters().send_refused, 0u);
  EXPECT_EQ(received + late, 500u * 4) << "in the cycles " << received << ", after them " << late;
  EXPECT_LE(late, 4u) << "frames came a cycle or more late";
  EXPECT_EQ(b->state(), BusState::error_active);
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
