// The master's passivity port: it gives the device no more energy than came in at the other port,
// passes the law's force when it can, holds a command only briefly, refuses what is not a number,
// and lets a dead device age through it; and the energies travel the link with the data.
#include "saw/teleop/passivity_port.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "port_chain.hpp"
#include "saw/component.hpp"
#include "saw/teleop/delay_task.hpp"
#include "saw/testing/fake_device.hpp"
#include "saw/testing/stepper.hpp"

namespace {

using saw::Status;
using saw::TimeNs;
using saw::teleop::PassivityPort;
using saw::teleop::PortConfig;
namespace port = saw::teleop::port;
constexpr TimeNs ms = 1'000'000;

// What sits on the far side of a port: a law's forces and the other port's energy.
class FarSide : public saw::Component {
 public:
  FarSide() : Component("far") {
    auto& r = require("arm");
    saw::crtk::require(r, saw::crtk::arm::servo_cf, servo_cf);
    saw::crtk::require(r, saw::crtk::arm::measured_cp, measured_cp);
    saw::crtk::require(r, port::energy, energy);
    saw::crtk::require(r, port::remote_energy, remote_energy);
  }
  saw::FunctionWrite<saw::Wrench> servo_cf;
  saw::FunctionRead<saw::Pose> measured_cp;
  saw::FunctionRead<double> energy;
  saw::FunctionWrite<double> remote_energy;
};

struct PortRig : PortChain<FarSide> {
  using PortChain::PortChain;
  void command(double fx) { ASSERT_EQ(far.servo_cf(saw::Wrench{{fx, 0, 0}, {}}), Status::ok); }
  double energy_in() {
    double e = -1;
    EXPECT_EQ(far.energy(e), Status::ok);
    return e;
  }
};

TEST(PassivityPort, WithNothingInFromTheOtherSideTheDeviceGetsNoEnergy) {
  PortRig rig;
  rig.device.velocity = {0.1, 0, 0};
  rig.step(2);
  for (int i = 0; i < 50; ++i) {
    rig.command(1.0);  // along the motion: the network would give the device energy
    rig.step();
    EXPECT_LE(rig.device.force[0] * 0.1, 1e-12) << "no output beyond what came in, cycle " << i;
  }
  EXPECT_GT(rig.port.controller().dissipated(), 0);
  // Energy arrives from the other port: the law's force passes untouched.
  ASSERT_EQ(rig.far.remote_energy(1.0), Status::ok);
  rig.command(1.0);
  rig.step(2);
  EXPECT_DOUBLE_EQ(rig.device.force[0], 1.0);
}

TEST(PassivityPort, AForceAgainstTheMotionPassesAndIsTheNetworksInput) {
  PortRig rig;
  rig.device.velocity = {0.1, 0, 0};
  rig.step(2);
  for (int i = 0; i < 100; ++i) {
    rig.command(-2.0);
    rig.step();
    EXPECT_DOUBLE_EQ(rig.device.force[0], -2.0);
  }
  rig.step();  // the newest row carries the last cycle's energy
  EXPECT_NEAR(rig.energy_in(), 100 * 2.0 * 0.1 * 1e-3, 1e-3 * 2.0 * 0.1 * 2) << "the operator's work, J";
}

TEST(PassivityPort, ObservingOnlyNeverChangesTheForce) {
  PortConfig c;
  c.passivity = false;
  PortRig rig(c);
  rig.device.velocity = {0.1, 0, 0};
  rig.step(2);
  for (int i = 0; i < 20; ++i) {
    rig.command(1.0);
    rig.step();
    EXPECT_DOUBLE_EQ(rig.device.force[0], 1.0);
  }
  EXPECT_NEAR(rig.port.controller().energy().out, 20 * 0.1 * 1e-3, 1e-4) << "the output is still counted";
  EXPECT_EQ(rig.port.controller().dissipated(), 0);
}

TEST(PassivityPort, ACommandIsAppliedABoundedTimeThenTheDevicesWatchdogDecides) {
  PortRig rig;
  rig.step(2);
  rig.command(-1.0);
  const int before = rig.device.commands;
  rig.step(30);
  EXPECT_GE(rig.device.commands - before, 5);
  EXPECT_LE(rig.device.commands - before, 6) << "held 5 periods, then nothing is written";
}

TEST(PassivityPort, WhatIsNotANumberIsRefusedAndAnOlderEnergyTellsNothing) {
  PortRig rig;
  rig.step(2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(rig.far.servo_cf(saw::Wrench{{nan, 0, 0}, {}}), Status::ok);
  ASSERT_EQ(rig.far.remote_energy(nan), Status::ok);
  ASSERT_EQ(rig.far.remote_energy(-1.0), Status::ok);
  rig.step(2);
  EXPECT_EQ(rig.device.commands, 0) << "a NaN force never reaches the device";
  EXPECT_EQ(rig.port.rejected(), 3u);
  // Energies only grow: a late, smaller value does not take back what arrived.
  ASSERT_EQ(rig.far.remote_energy(2.0), Status::ok);
  ASSERT_EQ(rig.far.remote_energy(1.0), Status::ok);
  rig.device.velocity = {0.1, 0, 0};
  rig.step();
  rig.command(1.0);
  rig.step(2);
  EXPECT_DOUBLE_EQ(rig.device.force[0], 1.0);
}

TEST(PassivityPort, ADeviceThatStopsPublishingAgesThroughThePort) {
  PortRig rig;
  rig.step(10);
  rig.step(20, false);
  saw::Pose p;
  saw::RowStamp stamp;
  ASSERT_EQ(rig.far.measured_cp(p, stamp), Status::ok);
  EXPECT_LE(stamp.time, 9 * ms) << "the row stands for the device's last reading, not the port's cycle";
}

// The delay task between a port and its controller: the port's energy travels with the positions,
// the other port's with the forces, each as late as its link.
TEST(DelayTask, EnergiesTravelWithTheDataTheyBelongTo) {
  saw::teleop::DelayConfig c;
  c.measured = {10 * ms, 0, 0, 1};
  c.commands = {10 * ms, 0, 0, 2};
  PortChain<FarSide> rig(PortConfig{}, c);
  auto& device = rig.device;
  auto& far = rig.far;
  auto& port_task = rig.port;
  auto& stepper = rig.stepper;
  device.velocity = {0.1, 0, 0};
  int first_energy = -1, first_force = -1;
  for (int k = 0; k < 60; ++k) {
    // The far side pushes against the motion (energy in at the port) and sends a remote energy.
    ASSERT_EQ(far.remote_energy(5.0), Status::ok);
    ASSERT_EQ(far.servo_cf(saw::Wrench{{-1.0, 0, 0}, {}}), Status::ok);
    stepper({&device});
    double e = 0;
    ASSERT_EQ(far.energy(e), Status::ok);
    if (e > 0 && first_energy < 0) first_energy = k;
    if (device.commands > 0 && first_force < 0) first_force = k;
  }
  EXPECT_GE(first_force, 10) << "forces take the commands link's delay";
  EXPECT_GE(first_energy - first_force, 10) << "the port's energy then takes the measured link's";
  EXPECT_DOUBLE_EQ(port_task.controller().margin(), 5.0 - port_task.controller().energy().out)
      << "the remote energy arrived with the forces";
}

}  // namespace
