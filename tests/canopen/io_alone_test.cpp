// A CANopen I/O component alone on its bus (its master, as of a URI), against a scripted node:
// what it puts on the wire in each cycle and at exit.
#include <gtest/gtest.h>

#include <vector>

#include "saw/canopen/canopen_io.hpp"
#include "saw/detail/access.hpp"
#include "shared_rig.hpp"

namespace saw::canopen::test {
namespace {

std::uint32_t id_of(const can::Frame& f) { return f.can_id() & CAN_SFF_MASK; }

struct AloneRig {
  AloneRig() : bus(network.attach("io bus")), spy(network.attach("spy")), node(network, 4) {
    CanopenIoConfig c = gripper_config("(a caller's bus)", 4);
    c.master_heartbeat_period = 20 * ms;
    c.startup_pause = [this] {
      node.step(now);
      now += ms;
      bus.now = now;
      return now;
    };
    io =
        std::make_unique<CanopenIo>("gripper", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c, bus);
    io->state_table().finalize();
  }
  // The frames the component and the node put on the bus in one period each (the spy's view).
  std::vector<std::vector<can::Frame>> cycle(int n) {
    std::vector<std::vector<can::Frame>> periods;
    for (int i = 0; i < n; ++i) {
      bus.now = now;
      detail::Access::step(*io, now);
      node.step(now);
      now += ms;
      periods.push_back(drain());
    }
    return periods;
  }
  std::vector<can::Frame> drain() {
    std::vector<can::Frame> out;
    can::Received r[64];
    for (std::size_t k; (k = spy.receive(r)) > 0;)
      for (std::size_t j = 0; j < k; ++j) out.push_back(r[j].frame);
    return out;
  }

  RingNetwork network;
  RingPort& bus;
  RingPort& spy;
  FakeIoNode node;
  TimeNs now = 0;
  std::unique_ptr<CanopenIo> io;
};

// Its own bus task runs in its cycle: each period its RPDO, then SYNC (which applies it), then the
// master's heartbeat when due; one SYNC per period, no other master frame. At exit: the safe
// output, one SYNC, and NMT pre-operational for its node, once.
TEST(CanopenIoAlone, EachPeriodItsRpdoThenSyncThenItsHeartbeatAndAtExitItsNodePreOperational) {
  AloneRig rig;
  rig.io->startup();
  (void)rig.drain();
  const int n = 200;
  const auto periods = rig.cycle(n);
  EXPECT_EQ(rig.io->operating_state().state, OperatingStateValue::enabled);
  std::size_t syncs = 0, heartbeats = 0, out_of_order = 0, others = 0;
  for (const auto& frames : periods) {
    std::vector<std::uint32_t> master;  // what the component sent, in order
    for (const can::Frame& f : frames)
      if (const std::uint32_t id = id_of(f);
          id == 0x204 || id == 0x080 || id == 0x77F || id == 0x000 || id == 0x604)
        master.push_back(id);
    syncs += static_cast<std::size_t>(std::count(master.begin(), master.end(), 0x080u));
    heartbeats += static_cast<std::size_t>(std::count(master.begin(), master.end(), 0x77Fu));
    const bool ordered = master == std::vector<std::uint32_t>{0x204, 0x080} ||
                         master == std::vector<std::uint32_t>{0x204, 0x080, 0x77F};
    if (!ordered) ++out_of_order;
    for (const std::uint32_t id : master)
      if (id == 0x000 || id == 0x604) ++others;
  }
  EXPECT_EQ(syncs, static_cast<std::size_t>(n)) << "one SYNC per period";
  EXPECT_EQ(out_of_order, 0u) << "a period whose frames were not RPDO, SYNC[, heartbeat]";
  EXPECT_EQ(others, 0u) << "no NMT or SDO while it cycles";
  EXPECT_GE(heartbeats, static_cast<std::size_t>(n / 20 - 1));
  EXPECT_LE(heartbeats, static_cast<std::size_t>(n / 20 + 1));
  EXPECT_GT(rig.node.input, 0) << "the node applied the RPDOs";

  rig.io->cleanup();
  const auto last = rig.drain();
  std::size_t pre_op = 0, last_syncs = 0;
  bool safe_before_sync = false;
  for (const can::Frame& f : last) {
    if (id_of(f) == 0x000 && f.len == 2 && f.data[0] == 0x80 && f.data[1] == 4) ++pre_op;
    if (id_of(f) == 0x080) ++last_syncs;
    if (id_of(f) == 0x204 && last_syncs == 0)
      safe_before_sync = static_cast<std::int16_t>(f.data[0] | f.data[1] << 8) == 2000;  // 0.02 / 1e-5
  }
  EXPECT_EQ(pre_op, 1u) << "NMT pre-operational for its node, once";
  EXPECT_EQ(last_syncs, 1u) << "one SYNC applies the safe output";
  EXPECT_TRUE(safe_before_sync) << "the safe output before that SYNC";
}

}  // namespace
}  // namespace saw::canopen::test
