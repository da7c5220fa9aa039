// NMT commands and node states, boot-up and heartbeat (producer and consumer), EMCY, SYNC.
#include "saw/canopen/nmt.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/sync.hpp"

namespace {

using namespace saw::canopen;
using saw::TimeNs;
using saw::can::Frame;
using Kind = HeartbeatEvent::Kind;

constexpr TimeNs ms = 1'000'000;

Frame frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  std::vector<std::uint8_t> v(bytes);
  return saw::can::classic(id, v);
}

TEST(CanopenNmt, CommandsAreTwoByteFramesOnIdentifierZero) {
  const Frame f = nmt_frame(NmtCommand::start, 3);
  EXPECT_EQ(f.id, 0u);
  ASSERT_EQ(f.len, 2);
  EXPECT_EQ(f.data[0], 0x01);
  EXPECT_EQ(f.data[1], 3);
  EXPECT_EQ(nmt_frame(NmtCommand::stop, 0).data[0], 0x02);
  EXPECT_EQ(nmt_frame(NmtCommand::enter_pre_operational, 0).data[0], 0x80);
  EXPECT_EQ(nmt_frame(NmtCommand::reset_node, 0).data[0], 0x81);
  EXPECT_EQ(nmt_frame(NmtCommand::reset_communication, 0).data[0], 0x82);
  const auto r = parse_nmt(nmt_frame(NmtCommand::reset_node, 0));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->command, NmtCommand::reset_node);
  EXPECT_TRUE(r->addresses(42)) << "node 0 addresses every node";
  EXPECT_FALSE(parse_nmt(frame(0, {0x03, 1})));      // unknown command
  EXPECT_FALSE(parse_nmt(frame(0, {0x01, 128})));    // no such node
  EXPECT_FALSE(parse_nmt(frame(0, {0x01})));         // short
  EXPECT_FALSE(parse_nmt(frame(0, {0x01, 1, 0})));   // long
  EXPECT_FALSE(parse_nmt(frame(0x001, {0x01, 1})));  // another identifier
  EXPECT_EQ(to_string(NmtState::pre_operational), "pre-operational");
}

TEST(CanopenNmt, NodeBootsIntoPreOperationalAndFollowsCommands) {
  NmtNode n(7);
  EXPECT_EQ(n.state(), NmtState::initialising);
  EXPECT_EQ(n.on_frame(nmt_frame(NmtCommand::start, 7)), NmtReset::none);
  EXPECT_EQ(n.state(), NmtState::initialising) << "no commands before boot-up";
  n.boot();
  const auto boot = n.poll();
  ASSERT_TRUE(boot);
  EXPECT_EQ(boot->id, 0x707u);
  ASSERT_EQ(boot->len, 1);
  EXPECT_EQ(boot->data[0], 0x00);
  EXPECT_FALSE(n.poll());
  EXPECT_EQ(n.state(), NmtState::pre_operational);

  n.on_frame(nmt_frame(NmtCommand::start, 8));
  EXPECT_EQ(n.state(), NmtState::pre_operational) << "addressed to another node";
  n.on_frame(nmt_frame(NmtCommand::start, 7));
  EXPECT_EQ(n.state(), NmtState::operational);
  n.on_frame(nmt_frame(NmtCommand::stop, 0));
  EXPECT_EQ(n.state(), NmtState::stopped);
  n.on_frame(nmt_frame(NmtCommand::enter_pre_operational, 7));
  EXPECT_EQ(n.state(), NmtState::pre_operational);
  n.on_frame(nmt_frame(NmtCommand::start, 0));
  EXPECT_EQ(n.on_frame(nmt_frame(NmtCommand::reset_communication, 7)), NmtReset::communication);
  EXPECT_EQ(n.state(), NmtState::initialising);
  n.boot();
  EXPECT_TRUE(n.poll());
  EXPECT_EQ(n.on_frame(nmt_frame(NmtCommand::reset_node, 0)), NmtReset::application);
}

TEST(CanopenHeartbeat, FramesAreCheckedWhenParsed) {
  const auto hb = parse_heartbeat(heartbeat_frame(12, NmtState::operational));
  ASSERT_TRUE(hb);
  EXPECT_EQ(hb->node, 12);
  EXPECT_EQ(hb->state, NmtState::operational);
  EXPECT_TRUE(parse_heartbeat(boot_up_frame(1))->boot_up());
  EXPECT_FALSE(parse_heartbeat(frame(0x700, {0x05})));        // node 0
  EXPECT_FALSE(parse_heartbeat(frame(0x705, {0x85})));        // node-guarding toggle bit
  EXPECT_FALSE(parse_heartbeat(frame(0x705, {0x06})));        // no such state
  EXPECT_FALSE(parse_heartbeat(frame(0x705, {0x05, 0x00})));  // two bytes
  Frame rtr = heartbeat_frame(5, NmtState::operational);
  rtr.id |= CAN_RTR_FLAG;
  EXPECT_FALSE(parse_heartbeat(rtr));
}

TEST(CanopenHeartbeat, ProducerKeepsItsPeriodWithoutBursts) {
  HeartbeatProducer p(3, 100 * ms);
  p.start(0);
  EXPECT_FALSE(p.poll(99 * ms, NmtState::operational));
  const auto f = p.poll(100 * ms, NmtState::operational);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->id, 0x703u);
  EXPECT_EQ(f->data[0], 0x05);
  EXPECT_FALSE(p.poll(150 * ms, NmtState::operational));
  EXPECT_TRUE(p.poll(200 * ms, NmtState::operational));
  EXPECT_TRUE(p.poll(750 * ms, NmtState::operational));  // stalled: one, not five
  EXPECT_FALSE(p.poll(760 * ms, NmtState::operational));
  EXPECT_TRUE(p.poll(850 * ms, NmtState::operational));
  HeartbeatProducer off(3, 0);
  off.start(0);
  EXPECT_FALSE(off.poll(10'000 * ms, NmtState::operational));
}

TEST(CanopenHeartbeat, ConsumerReportsLostWithHowLateAndBack) {
  HeartbeatConsumer c;
  c.watch(4, 150 * ms);
  EXPECT_THROW(c.watch(0, 150 * ms), std::invalid_argument);
  EXPECT_THROW(c.watch(4, 0), std::invalid_argument);
  EXPECT_FALSE(c.poll(1000 * ms)) << "monitoring starts with the first heartbeat";

  c.on_frame(heartbeat_frame(4, NmtState::pre_operational), 1000 * ms);
  auto e = c.poll(1000 * ms);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->kind, Kind::appeared);
  c.on_frame(heartbeat_frame(9, NmtState::pre_operational), 1000 * ms);  // not watched
  EXPECT_FALSE(c.poll(1000 * ms));

  c.on_frame(heartbeat_frame(4, NmtState::operational), 1100 * ms);
  e = c.poll(1100 * ms);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->kind, Kind::state_changed);
  EXPECT_EQ(e->previous, NmtState::pre_operational);
  EXPECT_EQ(e->state, NmtState::operational);

  EXPECT_FALSE(c.poll(1250 * ms)) << "exactly at the consumer time is still in time";
  e = c.poll(1262 * ms);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->kind, Kind::lost);
  EXPECT_EQ(e->node, 4);
  EXPECT_EQ(e->late_by, 12 * ms);
  EXPECT_EQ(e->silent_for, 162 * ms);
  EXPECT_EQ(e->state, NmtState::operational);
  EXPECT_TRUE(c.node(4).lost);
  EXPECT_FALSE(c.poll(2000 * ms)) << "lost is said once";

  c.on_frame(heartbeat_frame(4, NmtState::operational), 2100 * ms);
  e = c.poll(2100 * ms);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->kind, Kind::back);
  EXPECT_EQ(e->silent_for, 1000 * ms);
  EXPECT_FALSE(c.node(4).lost);
  EXPECT_EQ(c.node(4).losses, 1u);

  c.on_frame(boot_up_frame(4), 2150 * ms);
  e = c.poll(2150 * ms);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->kind, Kind::boot_up) << "a restarted node has lost its configuration";
}

TEST(CanopenHeartbeat, ConsumerQueueIsBoundedAndCountsWhatItDrops) {
  HeartbeatConsumer c;
  c.watch(1, 100 * ms);
  for (int i = 0; i < 100; ++i)
    c.on_frame(heartbeat_frame(1, i % 2 ? NmtState::operational : NmtState::stopped), i * ms);
  int events = 0;
  while (c.poll(100 * ms)) ++events;
  EXPECT_EQ(events, static_cast<int>(HeartbeatConsumer::event_capacity));
  EXPECT_EQ(c.dropped_events(), 100u - HeartbeatConsumer::event_capacity);
}

TEST(CanopenEmcy, DecodesCodeRegisterAndManufacturerBytes) {
  const auto e = parse_emcy(frame(0x085, {0x10, 0x23, 0x03, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE}));
  ASSERT_TRUE(e);
  EXPECT_EQ(e->node, 5);
  EXPECT_EQ(e->code, 0x2310);
  EXPECT_EQ(e->error_register, 0x03);
  EXPECT_EQ(e->manufacturer, (std::array<std::uint8_t, 5>{0xAA, 0xBB, 0xCC, 0xDD, 0xEE}));
  EXPECT_FALSE(e->is_reset());
  EXPECT_EQ(emcy_name(e->code), "continuous over-current (device output side)");
  EXPECT_EQ(emcy_class_name(e->code), "current, device output side");
  EXPECT_EQ(describe_error_register(e->error_register), "generic, current");
  EXPECT_FALSE(parse_emcy(frame(0x080, {0, 0, 0, 0, 0, 0, 0, 0}))) << "0x080 is SYNC";
  EXPECT_FALSE(parse_emcy(frame(0x085, {0x10, 0x23, 0x03}))) << "short";
  EXPECT_FALSE(parse_emcy(frame(0x100, {0, 0, 0, 0, 0, 0, 0, 0})));
  const Emcy back = *parse_emcy(emcy_frame(*e));
  EXPECT_EQ(back.code, e->code);
  EXPECT_EQ(back.manufacturer, e->manufacturer);
}

TEST(CanopenEmcy, NamesStandardCodesAndFallsBackToTheirClass) {
  EXPECT_EQ(emcy_name(0x0000), "error reset or no error");
  EXPECT_EQ(emcy_name(0x3210), "DC link over-voltage");
  EXPECT_EQ(emcy_name(0x4310), "excess temperature of the drive");
  EXPECT_EQ(emcy_name(0x7305), "incremental sensor 1 fault");
  EXPECT_EQ(emcy_name(0x8611), "following error");
  EXPECT_EQ(emcy_name(0x8130), "life guard error or heartbeat error");
  EXPECT_EQ(emcy_name(0x8250), "RPDO timeout");
  EXPECT_EQ(emcy_name(0x2399), "current, device output side") << "unknown code, known class";
  EXPECT_EQ(emcy_name(0x4350), "temperature") << "402's 43xx group: 301 has only the 4xxx class";
  EXPECT_EQ(emcy_name(0x6105), "internal software");
  EXPECT_EQ(emcy_name(0xFF42), "device specific");
  EXPECT_EQ(emcy_name(0x1000), "generic error");
  EXPECT_EQ(emcy_name(0xA123), "unknown error class");
}

TEST(CanopenEmcy, ProducerRespectsTheInhibitTime) {
  EmcyProducer p(2, 10 * ms);
  EXPECT_TRUE(p.raise(0x4310, error_register::temperature));
  EXPECT_TRUE(p.raise(0x2310, error_register::current));
  EXPECT_TRUE(p.clear());
  auto f = p.poll(0);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->id, 0x082u);
  EXPECT_EQ(parse_emcy(*f)->code, 0x4310);
  EXPECT_FALSE(p.poll(9 * ms));
  EXPECT_EQ(parse_emcy(*p.poll(10 * ms))->code, 0x2310);
  EXPECT_TRUE(parse_emcy(*p.poll(20 * ms))->is_reset());
  EXPECT_FALSE(p.poll(100 * ms));
  for (std::size_t i = 0; i < EmcyProducer::queue_capacity; ++i) EXPECT_TRUE(p.raise(0x1000, 1));
  EXPECT_FALSE(p.raise(0x1000, 1));
  EXPECT_EQ(p.dropped(), 1u);
}

TEST(CanopenSync, ProducerCountsAndSkipsMissedPeriods) {
  SyncProducer plain(1 * ms);
  plain.start(0);
  const auto f = plain.poll(0);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->id, 0x080u);
  EXPECT_EQ(f->len, 0);
  EXPECT_FALSE(plain.poll(ms / 2));
  EXPECT_TRUE(plain.poll(1 * ms));

  SyncProducer counted(1 * ms, 3);
  counted.start(0);
  std::vector<int> counters;
  for (TimeNs t = 0; t < 5 * ms; t += ms) counters.push_back(parse_sync(*counted.poll(t))->counter.value());
  EXPECT_EQ(counters, (std::vector<int>{1, 2, 3, 1, 2}));
  EXPECT_TRUE(counted.poll(8 * ms + 1));  // 5, 6 and 7 missed
  EXPECT_EQ(counted.skipped(), 3u);
  EXPECT_FALSE(counted.poll(8 * ms + 2)) << "no burst after an overrun";

  EXPECT_THROW(SyncProducer(0), std::invalid_argument);
  EXPECT_THROW(SyncProducer(ms, 1), std::invalid_argument);
  EXPECT_THROW(SyncProducer(ms, 241), std::invalid_argument);
  EXPECT_FALSE(parse_sync(frame(0x080, {0})));    // counter 0
  EXPECT_FALSE(parse_sync(frame(0x080, {241})));  // counter above 240
  EXPECT_FALSE(parse_sync(frame(0x080, {1, 2})));
  EXPECT_FALSE(parse_sync(frame(0x081, {})));
}

}  // namespace
