// The control law (paper eqs. 1-6) read consistently: errors, saturation, mirroring, ratchet.
#include "saw/teleop/teleop_law.hpp"

#include <gtest/gtest.h>

namespace {

using Eigen::Vector3d;
using namespace saw::teleop;

TEST(TeleopLaw, EachEquationByHand) {
  Scale s{0.5, {1, 1, 1}};  // slave moves half the master
  const Gains k{100, 200};
  const ForceLimits lim{100, 100};  // not limiting here
  const Vector3d p_m(0.10, 0, 0), o_m(0.01, 0, 0), p_s(0.02, 0.01, 0), o_s(0, 0, 0);
  const auto out = compute_law(p_m, o_m, p_s, o_s, s, k, lim);
  // d_m = 0.11; d_s = (0.02, 0.01, 0); e_m = d_m − 2·d_s; e_s = d_s − 0.5·d_m.
  EXPECT_TRUE(out.master_error.isApprox(Vector3d(0.11 - 0.04, -0.02, 0)));
  EXPECT_TRUE(out.slave_error.isApprox(Vector3d(0.02 - 0.055, 0.01, 0)));
  EXPECT_TRUE(out.master_force.isApprox(-100 * out.master_error));
  EXPECT_TRUE(out.slave_force.isApprox(-200 * out.slave_error));
  EXPECT_FALSE(out.master_saturated);
  EXPECT_FALSE(out.slave_saturated);
}

TEST(TeleopLaw, BothErrorsVanishAtTheSameConfiguration) {
  // The literal paper reading (e_s = d_s + sc·d_m) would leave e_s ≠ 0 here.
  for (const Scale& s : {Scale{1, {1, 1, 1}}, Scale{0.3, {-1, 1, -1}}, Scale{2.5, {1, -1, 1}}}) {
    const Vector3d p_m(0.03, -0.02, 0.05), o_m(0.01, 0.0, -0.02), p_s(-0.1, 0.2, 0.0);
    const Vector3d o_s = cancelling_slave_offset(p_m, o_m, p_s, s);
    const auto out = compute_law(p_m, o_m, p_s, o_s, s, {100, 100}, {3, 3});
    EXPECT_LT(out.master_error.norm(), 1e-12);
    EXPECT_LT(out.slave_error.norm(), 1e-12);
    EXPECT_LT(out.master_force.norm(), 1e-9);
  }
}

TEST(TeleopLaw, SaturationLimitsMagnitudeAndKeepsDirection) {
  const Vector3d f(3, 4, 0);  // |f| = 5
  const Vector3d limited = saturate(f, 2.0);
  EXPECT_NEAR(limited.norm(), 2.0, 1e-12);
  EXPECT_TRUE(limited.normalized().isApprox(f.normalized()));
  EXPECT_TRUE(saturate(f, 6.0).isApprox(f));
  const auto out = compute_law(Vector3d(0.1, 0, 0), Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(),
                               Scale{}, {100, 100}, {3, 2});
  EXPECT_NEAR(out.master_force.norm(), 3.0, 1e-12);
  EXPECT_NEAR(out.slave_force.norm(), 2.0, 1e-12);
  EXPECT_TRUE(out.master_saturated && out.slave_saturated);
}

TEST(TeleopLaw, MirroredScaleFlipsTheSlaveGoal) {
  const Scale s{0.5, {-1, 1, 1}};  // devices face each other along x
  const Vector3d o_s = cancelling_slave_offset(Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(), s);
  // The master moves +2 cm in x and +2 cm in y: the slave is pulled toward −1 cm x, +1 cm y.
  const auto out =
      compute_law(Vector3d(0.02, 0.02, 0), Vector3d::Zero(), Vector3d::Zero(), o_s, s, {100, 100}, {10, 10});
  EXPECT_LT(out.slave_force.x(), 0);
  EXPECT_GT(out.slave_force.y(), 0);
  EXPECT_TRUE(out.slave_error.isApprox(Vector3d(0.01, -0.01, 0)));
  EXPECT_TRUE(out.master_force.isApprox(Vector3d(-2, -2, 0)));  // the master is pulled back home
}

TEST(TeleopLaw, RatchetShiftBringsForcesBackToTheLimit) {
  const Scale s{0.5, {1, -1, 1}};
  const Gains k{100, 50};
  const ForceLimits lim{2, 1};
  const Vector3d p_m(0.08, 0.02, 0), p_s(0, 0, 0), o(0, 0, 0);
  const auto before = compute_law(p_m, o, p_s, o, s, k, lim);
  ASSERT_TRUE(before.master_saturated || before.slave_saturated);
  const Vector3d shift = ratchet_shift(before, s, k, lim);
  const auto after = compute_law(p_m, o, p_s, shift, s, k, lim);
  const double fm = k.master * after.master_error.norm(), fs = k.slave * after.slave_error.norm();
  EXPECT_LE(fm, lim.master + 1e-9);
  EXPECT_LE(fs, lim.slave + 1e-9);
  EXPECT_TRUE(std::abs(fm - lim.master) < 1e-9 || std::abs(fs - lim.slave) < 1e-9) << "slipped too far";
  EXPECT_TRUE(after.master_error.normalized().isApprox(before.master_error.normalized()));
  const auto inside = compute_law(Vector3d(0.001, 0, 0), o, p_s, o, s, k, lim);
  EXPECT_EQ(ratchet_shift(inside, s, k, lim), Vector3d::Zero());
}

TEST(TeleopLaw, ScaleValidation) {
  EXPECT_TRUE((Scale{0.5, {1, -1, 1}}.valid()));
  EXPECT_FALSE((Scale{0.0, {1, 1, 1}}.valid()));
  EXPECT_FALSE((Scale{std::nan(""), {1, 1, 1}}.valid()));
  EXPECT_FALSE((Scale{1.0, {1, 0.5, 1}}.valid()));
}

}  // namespace
