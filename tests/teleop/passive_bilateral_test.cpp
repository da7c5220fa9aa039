// The passive bilateral law: it engages without a force step, pulls each side toward the other,
// never lets the slave's port give out more than entered at the master (received), observes only
// when told, and the task refuses to run it without a port at the master.
#include "saw/teleop/laws/passive_bilateral.hpp"

#include <gtest/gtest.h>

#include "saw/testing/law_io.hpp"
#include "saw/testing/teleop_rig.hpp"

namespace {

using saw::teleop::LawContext;
using saw::teleop::LawInputs;
using saw::teleop::PassiveBilateralLaw;
using V = Eigen::Vector3d;

// The master port's energy in, the slave port's out (the law's declared input and output).
saw::testing::LawIo<double, double> law_port;

LawInputs inputs(V master, V slave, V v_master = V::Zero(), V v_slave = V::Zero(), double energy = 0) {
  LawInputs in;
  law_port.value = energy;
  law_port.attach(in);
  in.master.position = master;
  in.slave.position = slave;
  in.master.velocity = v_master;
  in.slave.velocity = v_slave;
  return in;
}

TEST(PassiveBilateralLaw, EngagesWithoutAForceStepAndPullsEachSideTowardTheOther) {
  PassiveBilateralLaw law({}, LawContext{});
  law.reset(inputs(V(0.1, 0, 0), V(0.3, 0, 0)));
  const auto still = law.step(inputs(V(0.1, 0, 0), V(0.3, 0, 0), V::Zero(), V::Zero(), 1.0));
  EXPECT_LT(still.slave_force.norm(), 1e-12);
  EXPECT_LT(still.master_force.norm(), 1e-12);
  // The master moves 1 mm: the slave is pulled after it, the master back (it feels the slave).
  const auto moved = law.step(inputs(V(0.101, 0, 0), V(0.3, 0, 0), V::Zero(), V::Zero(), 1.0));
  EXPECT_GT(moved.slave_force.x(), 0.5);
  EXPECT_LT(moved.master_force.x(), -0.5);
  EXPECT_NEAR(moved.slave_error.x(), -0.001, 1e-12);
}

TEST(PassiveBilateralLaw, TheSlavesPortGivesOutNoMoreThanEnteredAtTheMaster) {
  PassiveBilateralLaw law({}, LawContext{});
  law.reset(inputs(V::Zero(), V::Zero()));
  double received = 0;
  for (int k = 0; k < 500; ++k) {
    received += 1e-6;  // a trickle from the master's port
    // The master is 5 mm ahead and the slave moves toward it: the law pushes along the motion.
    (void)law.step(inputs(V(0.005, 0, 0), V::Zero(), V::Zero(), V(0.05, 0, 0), received));
    EXPECT_LE(law.slave_energy_out_, received + 1e-15) << k;
    ASSERT_NE(law_port.sent(), nullptr) << k;
    EXPECT_GE(*law_port.sent(), 0);
    EXPECT_EQ(*law_port.sent(), law.slave_energy_in_);
  }
  EXPECT_GT(law.slave_dissipated_, 0);
  EXPECT_DOUBLE_EQ(law.master_energy_in_, received);
}

TEST(PassiveBilateralLaw, WithPassivityOffTheForceIsTheCouplingsAndTheEnergyStillCounted) {
  PassiveBilateralLaw::Settings s;
  s.passivity = false;
  PassiveBilateralLaw law(s, LawContext{});
  law.reset(inputs(V::Zero(), V::Zero()));
  const auto out = law.step(inputs(V(0.001, 0, 0), V::Zero(), V::Zero(), V(0.05, 0, 0), 0.0));
  EXPECT_NEAR(out.slave_force.x(), 600 * 0.001 - 1.5 * 0.05, 1e-12);
  EXPECT_GT(law.slave_energy_out_, 0);
  EXPECT_EQ(law.slave_dissipated_, 0);
}

TEST(PassiveBilateralLaw, TheTaskRefusesToStartItWithoutAPortAtTheMaster) {
  struct Nobody : saw::Component {
    Nobody() : Component("nobody") { require("teleop"); }
  };
  try {
    saw::testing::TeleopRig<Nobody> rig(saw::teleop::TeleopConfig{},
                                        saw::teleop::law_spec<PassiveBilateralLaw>());
    FAIL() << "started without a port";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("passivity_port"), std::string::npos) << e.what();
  }
}

}  // namespace
