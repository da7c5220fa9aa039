// A simulated drive and a master made of the protocol library's pieces, on an in-memory bus, stepped by hand.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "../ring_bus.hpp"
#include "saw/can/bus.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sim/sim_drive.hpp"

namespace saw::canopen::sim::testing {

inline constexpr TimeNs us = 1'000;
inline constexpr TimeNs ms = 1'000'000;

// The RT tests' in-memory network (vcan's rule: what one port sends, every other port receives).
using MemoryNetwork = saw::canopen::test::RingNetwork;
using MemoryBus = saw::canopen::test::RingPort;

struct Seen {
  can::Frame frame;
  TimeNs time = 0;
};

// The drive steps every 250 µs; the master reads its port after each step, feeds the SDO client,
// the heartbeat consumer and the EMCY log, and keeps every frame it saw.
class Bench {
 public:
  static constexpr TimeNs period = 250 * us;

  explicit Bench(SimDriveConfig config = default_config())
      : node(config.node),
        drive_port(network.attach("drive")),
        master(network.attach("master")),
        drive(config, drive_port),
        sdo(SdoClientConfig{SdoChannel::of_node(config.node)}) {
    heartbeats.watch(node, 100 * ms);
  }
  static SimDriveConfig default_config() {
    SimDriveConfig c;
    c.node = 5;
    return c;
  }

  // One drive period: the master's hook, the drive's step, then the master reads.
  void tick() {
    if (each_tick) each_tick();
    drive_port.now = now;
    drive.step(now);
    read();
    now += period;
  }
  void run_for(TimeNs d) {
    const TimeNs end = now + d;
    while (now < end) tick();
  }
  // Ticks until `done` (true) or `timeout` (false).
  bool run_until(const std::function<bool()>& done, TimeNs timeout) {
    const TimeNs end = now + timeout;
    while (now < end) {
      if (done()) return true;
      tick();
    }
    return done();
  }
  void send(const can::Frame& f) {
    master.now = now;
    master.send(std::span(&f, 1));
  }
  void nmt(NmtCommand c) { send(nmt_frame(c, node)); }

  SdoResult upload(ObjectAddress a, std::vector<std::uint8_t>* bytes = nullptr) {
    EXPECT_TRUE(sdo.upload(a, now));
    return finish_sdo(bytes);
  }
  template <class T>
  T upload_value(ObjectAddress a, DataType type) {
    const SdoResult r = upload(a);
    EXPECT_EQ(r.status, SdoStatus::done) << to_string(a) << ": " << to_string(r.abort);
    T v{};
    EXPECT_EQ(sdo.value(type, v), Codec::ok) << to_string(a);
    return v;
  }
  template <class T>
  SdoResult download(ObjectAddress a, DataType type, T value) {
    EXPECT_TRUE(sdo.download_value(a, type, value, now));
    return finish_sdo(nullptr);
  }
  template <class T>
  void write(ObjectAddress a, DataType type, T value) {
    const SdoResult r = download(a, type, value);
    ASSERT_EQ(r.status, SdoStatus::done) << to_string(a) << ": " << to_string(r.abort);
  }

  std::vector<Emcy> emcys() const {
    std::vector<Emcy> out;
    for (const auto& s : seen)
      if (auto e = parse_emcy(s.frame); e && e->node == node) out.push_back(*e);
    return out;
  }
  std::size_t count(std::uint32_t id) const {
    std::size_t n = 0;
    for (const auto& s : seen) n += s.frame.can_id() == id;
    return n;
  }
  std::vector<HeartbeatEvent> events;  // from the consumer, in order
  std::vector<Seen> seen;              // every frame the master received
  std::function<void()> each_tick;     // the master's cycle, before the drive steps

  std::uint8_t node;
  TimeNs now = 0;
  MemoryNetwork network;
  MemoryBus& drive_port;
  MemoryBus& master;
  SimDrive drive;
  SdoClient sdo;
  HeartbeatConsumer heartbeats;

 private:
  void read() {
    can::Received rx[64];
    for (std::size_t n; (n = master.receive(rx)) > 0;) {
      for (std::size_t i = 0; i < n; ++i) {
        seen.push_back({rx[i].frame, now});
        sdo.on_frame(rx[i].frame, now);
        heartbeats.on_frame(rx[i].frame, now);
      }
    }
    if (auto f = sdo.poll(now)) send(*f);
    while (auto e = heartbeats.poll(now)) events.push_back(*e);
  }
  SdoResult finish_sdo(std::vector<std::uint8_t>* bytes) {
    if (auto f = sdo.poll(now)) send(*f);
    run_until([&] { return !sdo.busy(); }, 2'000 * ms);
    if (bytes != nullptr) bytes->assign(sdo.data().begin(), sdo.data().end());
    return sdo.result();
  }
};

}  // namespace saw::canopen::sim::testing
