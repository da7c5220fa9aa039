// The SocketCAN backend. Where the kernel has AF_CAN (and a vcan), the conformance tests below
// run against it; here (no AF_CAN) they skip for socketcan and run against the virtual bus
// behind the same seam. The receive and send paths themselves run everywhere, through a
// SOCK_SEQPACKET pair that carries struct can_frame / canfd_frame datagrams as CAN_RAW does.
#include "saw/can/socketcan_bus.hpp"

#include <linux/can/error.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "can_test_support.hpp"

namespace {

using namespace saw::can;
using saw::can::testing::config;
using saw::can::testing::drain;
using saw::can::testing::numbered;
using saw::can::testing::same_frame;
using saw::can::testing::ScopedBusName;

// Why SocketCAN cannot be tested here, or empty when it can (on `ifname`).
std::string socketcan_unavailable(const std::string& ifname) {
  const int fd = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0)
    return std::string("socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: ") + std::strerror(errno) +
           (errno == EAFNOSUPPORT ? " (this kernel has no AF_CAN)" : "");
  ::close(fd);
  if (::if_nametoindex(ifname.c_str()) == 0)
    return "no interface " + ifname + " (ip link add " + ifname + " type vcan; ip link set " + ifname +
           " up)";
  return "";
}

std::string test_interface() {
  const char* e = std::getenv("SAW_TEST_CAN_INTERFACE");
  return e != nullptr ? e : "vcan0";
}

TEST(SocketCanBus, OpeningAMissingInterfaceNamesTheBusAndTheReason) {
  std::string message;
  try {
    (void)open_bus(config("socketcan:nonexistent0"));
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty()) << "open_bus did not throw";
  EXPECT_NE(message.find("'socketcan:nonexistent0'"), std::string::npos) << message;
  // Without AF_CAN the socket cannot even be made; with it, the interface is missing.
  const bool said_why = message.find("no AF_CAN") != std::string::npos ||
                        message.find("no such network interface 'nonexistent0'") != std::string::npos;
  EXPECT_TRUE(said_why) << message;
}

TEST(SocketCanBus, AnInterfaceNameTooLongIsRefusedBeforeAnySocket) {
  try {
    (void)open_bus(config("socketcan:an-interface-name-far-too-long"));
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is not a network interface name"), std::string::npos) << e.what();
  }
}

TEST(SocketCanBus, ErrorFramesMoveTheState) {
  Frame e;
  e.id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  e.len = CAN_ERR_DLC;
  e.data[1] = CAN_ERR_CRTL_RX_WARNING;
  EXPECT_EQ(error_frame_state(e, BusState::error_active), BusState::error_warning);
  e.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  EXPECT_EQ(error_frame_state(e, BusState::error_warning), BusState::error_passive);
  e.data[1] = CAN_ERR_CRTL_ACTIVE;
  EXPECT_EQ(error_frame_state(e, BusState::error_passive), BusState::error_active);
  e.id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  EXPECT_EQ(error_frame_state(e, BusState::error_passive), BusState::bus_off);
  e.id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  EXPECT_EQ(error_frame_state(e, BusState::bus_off), BusState::error_active);
  e.id = CAN_ERR_FLAG | CAN_ERR_PROT;  // a bus error says nothing of the state
  EXPECT_EQ(error_frame_state(e, BusState::error_warning), BusState::error_warning);
}

// A SocketCanBus on one end of a SOCK_SEQPACKET pair; the test plays the kernel on the other.
class SocketCanOnAPair : public ::testing::Test {
 protected:
  void open(bool fd_frames) {
    int sv[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK, 0, sv), 0);
    bus_ = std::make_unique<SocketCanBus>(sv[0], "socketcan:test0", fd_frames);
    kernel_ = sv[1];
  }
  void TearDown() override {
    if (kernel_ >= 0) ::close(kernel_);
  }
  void deliver(const void* bytes, std::size_t size) {
    ASSERT_EQ(::send(kernel_, bytes, size, 0), ssize_t(size));
  }
  void deliver_classic(const Frame& f) { deliver(&f, CAN_MTU); }
  void deliver_fd(const Frame& f) { deliver(&f, CANFD_MTU); }
  std::unique_ptr<SocketCanBus> bus_;
  int kernel_ = -1;
};

TEST_F(SocketCanOnAPair, ReceivesDataFramesKeepsErrorFramesAsStateAndDropsMalformedOnes) {
  open(true);
  const Frame a = numbered(0x123, 1);
  Frame fd = numbered(0x456, 2);
  fd.flags = CANFD_BRS;  // as kernels before 5.14 deliver it: no CANFD_FDF, told by its size
  fd.len = 12;
  Frame error;
  error.id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  error.len = CAN_ERR_DLC;
  error.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  Frame bad_length = numbered(0x1, 3);
  bad_length.len = 9;
  Frame classic_with_flags = numbered(0x2, 4);
  classic_with_flags.flags = CANFD_FDF;
  const saw::TimeNs before = saw::monotonic_now();
  deliver_classic(a);
  deliver_classic(error);
  deliver_fd(fd);
  deliver_classic(bad_length);
  deliver_classic(classic_with_flags);
  deliver("short", 5);  // neither CAN_MTU nor CANFD_MTU
  deliver_classic(numbered(0x789, 5));

  std::vector<Received> out(16);
  const std::size_t n = bus_->receive(out);
  ASSERT_EQ(n, 3u);
  EXPECT_TRUE(same_frame(out[0].frame, a));
  EXPECT_TRUE(out[1].frame.fd());
  EXPECT_EQ(out[1].frame.flags, CANFD_FDF | CANFD_BRS);
  EXPECT_EQ(out[1].frame.len, 12);
  EXPECT_EQ(out[2].frame.id, 0x789u);
  // Kernel time stamps (CLOCK_REALTIME on the wire) come back on CLOCK_MONOTONIC.
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_GE(out[i].time, before - 5'000'000);
    EXPECT_LE(out[i].time, saw::monotonic_now() + 5'000'000);
  }
  EXPECT_EQ(bus_->state(), BusState::error_passive);
  const auto c = bus_->counters();
  EXPECT_EQ(c.received, 3u);
  EXPECT_EQ(c.error_frames, 1u);
  EXPECT_EQ(c.malformed, 3u);
  EXPECT_EQ(bus_->receive(out), 0u);
}

TEST_F(SocketCanOnAPair, ReceiveFillsAtMostTheCallersSpanAndKeepsTheRestForLater) {
  open(false);
  for (std::uint32_t i = 0; i < 150; ++i) deliver_classic(numbered(0x100, i));  // more than one batch
  std::vector<Received> out(100);
  ASSERT_EQ(bus_->receive(out), 100u);
  for (std::uint32_t i = 0; i < 100; ++i) ASSERT_EQ(saw::can::testing::sequence_of(out[i].frame), i);
  ASSERT_EQ(bus_->receive(out), 50u);
  EXPECT_EQ(saw::can::testing::sequence_of(out[49].frame), 149u);
}

TEST_F(SocketCanOnAPair, SendsClassicFramesAsCanMtuAndFdFramesAsCanfdMtuAndRefusesTheRest) {
  open(true);
  Frame fd = numbered(0x10, 1);
  fd.flags = CANFD_FDF;
  fd.len = 64;
  Frame bad = numbered(0x10, 2);
  bad.len = 13;
  const Frame frames[] = {numbered(0x10, 0), fd, bad, numbered(0x10, 3)};
  EXPECT_EQ(bus_->send(frames), 2u);
  EXPECT_EQ(bus_->counters().sent, 2u);
  EXPECT_EQ(bus_->counters().send_refused, 2u);
  Frame got;
  ASSERT_EQ(::recv(kernel_, &got, sizeof got, 0), ssize_t(CAN_MTU));
  EXPECT_TRUE(same_frame(got, frames[0]));
  ASSERT_EQ(::recv(kernel_, &got, sizeof got, 0), ssize_t(CANFD_MTU));
  EXPECT_TRUE(same_frame(got, fd));
}

TEST_F(SocketCanOnAPair, AClassicBusRefusesFdFramesAndAFullQueueRefusesWithoutBlocking) {
  open(false);
  Frame fd = numbered(0x10, 1);
  fd.flags = CANFD_FDF;
  EXPECT_EQ(bus_->send(std::span<const Frame>(&fd, 1)), 0u);
  // Nobody reads the other end: the socket's queue fills, send() returns what fit.
  std::vector<Frame> many(4096, numbered(0x20, 0));
  for (int i = 0; i < 64; ++i) (void)bus_->send(many);
  const auto c = bus_->counters();
  EXPECT_GT(c.sent, 0u);
  EXPECT_GT(c.send_refused, 1u);
  EXPECT_EQ(bus_->state(), BusState::error_active);
}

// The round trip every Bus must pass, on both backends: two attachments to one bus.
class BusConformance : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (GetParam() == "socketcan") {
      const std::string ifname = test_interface();
      if (const auto why = socketcan_unavailable(ifname); !why.empty()) GTEST_SKIP() << why;
      uri_ = "socketcan:" + ifname;
    } else {
      name_ = std::make_unique<ScopedBusName>("conf");
      uri_ = name_->uri();
    }
  }
  std::unique_ptr<ScopedBusName> name_;
  std::string uri_;
};

TEST_P(BusConformance, FramesGoFromOneAttachmentToTheOtherIntactAndNotBack) {
  const auto a = open_bus(config(uri_));
  const auto b = open_bus(config(uri_));
  Frame ext = numbered(0, 7);
  ext.id = 0x1FFFFFFF | CAN_EFF_FLAG;
  Frame rtr;
  rtr.id = 0x7FF | CAN_RTR_FLAG;
  rtr.len = 8;
  const Frame frames[] = {numbered(0x001, 1), ext, rtr, Frame{}};
  ASSERT_EQ(a->send(frames), 4u);
  std::vector<Received> got;
  for (int i = 0; i < 1000 && got.size() < 4; ++i) {
    const auto more = drain(*b);
    got.insert(got.end(), more.begin(), more.end());
    if (got.size() < 4) usleep(1000);
  }
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_TRUE(same_frame(got[i].frame, frames[i])) << i;
  EXPECT_TRUE(drain(*a).empty()) << "a sender does not receive its own frames";
}

TEST_P(BusConformance, FdFramesAndFiltersBehaveAsOnSocketCan) {
  BusConfig fd_config = config(uri_, true);
  const auto a = open_bus(fd_config);
  fd_config.filters = {{0x100, 0x7F0}};
  const auto b = open_bus(fd_config);
  Frame fd = numbered(0x105, 1);
  fd.flags = CANFD_FDF | CANFD_BRS;
  fd.len = 48;
  const Frame frames[] = {fd, numbered(0x200, 2), numbered(0x10F, 3)};
  ASSERT_EQ(a->send(frames), 3u);
  std::vector<Received> got;
  for (int i = 0; i < 1000 && got.size() < 2; ++i) {
    const auto more = drain(*b);
    got.insert(got.end(), more.begin(), more.end());
    if (got.size() < 2) usleep(1000);
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_TRUE(same_frame(got[0].frame, fd));
  EXPECT_EQ(got[1].frame.id, 0x10Fu);
}

INSTANTIATE_TEST_SUITE_P(Backends, BusConformance, ::testing::Values("virtual", "socketcan"),
                         [](const auto& param_info) { return param_info.param; });

}  // namespace
