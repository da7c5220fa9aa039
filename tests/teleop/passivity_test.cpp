// Time-domain passivity: the controller never lets a port give out more than came in at the other,
// passes the law's force untouched when it can, and keeps a delayed bilateral loop stable where
// the same loop without it is not.
#include "saw/teleop/passivity.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "saw/teleop/delay_channel.hpp"

namespace {

using saw::teleop::DelayChannel;
using saw::teleop::LinkConfig;
using saw::teleop::PassivityController;
using V = Eigen::Vector3d;
constexpr double dt = 1e-3;

TEST(PassivityController, APortThatWouldCreateEnergyIsDampedToWhatCameIn) {
  PassivityController pc;
  double remote_in = 0;
  for (int k = 0; k < 1000; ++k) {
    const V v(0.1 * std::sin(k * 0.01), 0, 0);
    const V f = 5.0 * v;  // negative damping: pushes along the motion, creating energy
    remote_in += 1e-5;    // a trickle comes in at the other port
    const auto s = pc.step(f, v, remote_in, dt);
    EXPECT_LE(pc.energy().out, remote_in + 1e-15) << "never more out than in, step " << k;
    EXPECT_GE(s.damping, 0);
  }
  EXPECT_GT(pc.dissipated(), 0);
}

TEST(PassivityController, WithEnoughEnergyTheLawsForceIsUntouched) {
  PassivityController pc;
  const V f(1, -2, 0.5), v(0.05, 0.01, 0);
  const auto s = pc.step(f, v, 1.0, dt);
  EXPECT_EQ(s.force, f);
  EXPECT_EQ(s.damping, 0);
  EXPECT_NEAR(pc.energy().out, f.dot(v) * dt, 1e-15);
  // A port absorbing energy (force against the motion) is never touched and counts it as input.
  const auto a = pc.step(-f, v, 0, dt);
  EXPECT_EQ(a.force, -f);
  EXPECT_NEAR(pc.energy().in, f.dot(v) * dt, 1e-15);
}

TEST(PassivityController, DampingIsCappedAndAtRestNothingIsDivided) {
  PassivityController pc(2.0);
  const auto s = pc.step(V(10, 0, 0), V(1, 0, 0), 0, dt);
  EXPECT_DOUBLE_EQ(s.damping, 2.0);
  EXPECT_LT(pc.margin(), 0) << "the cap kept it from restoring the bound: the margin says so";
  const auto r = pc.step(V(3, 0, 0), V::Zero(), 0, dt);
  EXPECT_TRUE(r.force.allFinite());
  EXPECT_EQ(r.force, V(3, 0, 0)) << "no motion, no power, nothing to dissipate";
}

// A 1-DOF bilateral loop: an operator's hand (a spring-damper to a moving target) on the master,
// the slave against a stiff wall, each pulled toward the other's delayed position with its own
// gain (the paper's bilateral law), over a link with delay and loss in each direction.
struct Loop {
  double delay_s = 0, loss = 0, gain = 300;
  bool passivity = false;

  struct Result {
    double max_position = 0, max_force = 0, final_energy = 0;
    bool stable() const { return max_position < 0.1 && max_force < 30; }
  };

  Result run(double seconds) const {
    const auto ns = static_cast<saw::TimeNs>(delay_s * 1e9);
    struct Msg {
      double x = 0, e_in = 0;
    };
    DelayChannel<Msg> to_slave(LinkConfig{ns, 0, loss, 11}, 1'000'000),
        to_master(LinkConfig{ns, 0, loss, 12}, 1'000'000);
    PassivityController pc_m, pc_s;
    const double m = 0.1, b_dev = 0.5, k_h = 200, b_h = 2, k_w = 2000, wall = 0.01;
    double xm = 0, vm = 0, xs = 0, vs = 0;
    Msg at_master, at_slave;  // last received
    Result r;
    const int n = static_cast<int>(seconds / dt);
    for (int k = 0; k < n; ++k) {
      const saw::TimeNs t = k * 1'000'000LL;
      to_slave.send(t, {xm, pc_m.energy().in});
      to_master.send(t, {xs, pc_s.energy().in});
      (void)to_slave.receive(t, at_slave);
      (void)to_master.receive(t, at_master);
      V fm(gain * (at_master.x - xm), 0, 0), fs(gain * (at_slave.x - xs), 0, 0);
      if (passivity) {
        fm = pc_m.step(fm, V(vm, 0, 0), at_master.e_in, dt).force;
        fs = pc_s.step(fs, V(vs, 0, 0), at_slave.e_in, dt).force;
      }
      const double target = 0.02 * std::min(1.0, k * dt);  // the hand reaches 2 cm in, into the wall
      for (int i = 0; i < 10; ++i) {
        const double h = dt / 10;
        const double f_hand = k_h * (target - xm) - b_h * vm;
        const double f_wall = xs > wall ? -k_w * (xs - wall) : 0.0;
        vm += h * (fm.x() + f_hand - b_dev * vm) / m;
        vs += h * (fs.x() + f_wall - b_dev * vs) / m;
        xm += h * vm;
        xs += h * vs;
      }
      if (!std::isfinite(xm) || !std::isfinite(xs)) return {1e9, 1e9, 1e9};
      if (k * dt > 2.0) {  // after the reach: what the loop does while the hand holds still
        r.max_position = std::max({r.max_position, std::abs(xm), std::abs(xs)});
        r.max_force = std::max({r.max_force, std::abs(fm.x()), std::abs(fs.x())});
      }
    }
    return r;
  }
};

TEST(BilateralLoop, WithoutPassivityTheDelayedLoopGoesUnstable) {
  EXPECT_TRUE((Loop{0.0, 0, 300, false}.run(6).stable())) << "no delay: stable";
  EXPECT_FALSE((Loop{0.05, 0, 300, false}.run(6).stable())) << "50 ms: the delayed bilateral law oscillates";
}

TEST(BilateralLoop, WithPassivityItIsStableAtEveryDelayWithLoss) {
  for (double delay : {0.0, 0.01, 0.05, 0.1})
    for (double loss : {0.0, 0.1}) {
      const auto r = Loop{delay, loss, 300, true}.run(6);
      EXPECT_TRUE(r.stable()) << "delay " << delay << " s, loss " << loss << ": max position "
                              << r.max_position << " m, max force " << r.max_force << " N";
    }
}

}  // namespace
