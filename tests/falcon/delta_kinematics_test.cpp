// The Falcon's delta kinematics: forward/inverse consistency, the Jacobian against finite
// differences, encoders and DAC scaling.
#include "saw/drivers/falcon/delta_kinematics.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cstdio>

namespace saw::drivers::falcon {
namespace {

// A grid of arm angles around the homed encoder zero (35°), ±20°.
std::vector<Eigen::Vector3d> angle_grid() {
  std::vector<Eigen::Vector3d> out;
  for (double a : {-0.3, 0.0, 0.35})
    for (double b : {-0.2, 0.1, 0.3})
      for (double c : {-0.35, 0.0, 0.2}) out.emplace_back(0.61 + a, 0.61 + b, 0.61 + c);
  return out;
}

TEST(FalconDeltaKinematics, HomePoseIsOnTheAxisBelowTheMotors) {
  DeltaKinematics k;
  Eigen::Vector3d x;
  ASSERT_TRUE(k.forward(k.angles({0, 0, 0}), x));
  std::printf("tip at encoders 0: %.4f %.4f %.4f m\n", x.x(), x.y(), x.z());
  EXPECT_NEAR(x.x(), 0, 1e-9);
  EXPECT_NEAR(x.y(), 0, 1e-9);
  EXPECT_GT(x.z(), 0.08);
  EXPECT_LT(x.z(), 0.16);
}

TEST(FalconDeltaKinematics, ForwardAndInverseAgree) {
  DeltaKinematics k;
  for (const Eigen::Vector3d& theta : angle_grid()) {
    Eigen::Vector3d x, back;
    ASSERT_TRUE(k.forward(theta, x)) << theta.transpose();
    ASSERT_TRUE(k.inverse(x, back)) << x.transpose();
    EXPECT_LT((back - theta).norm(), 1e-9) << theta.transpose();
    Eigen::Vector3d x2;
    ASSERT_TRUE(k.forward(back, x2));
    EXPECT_LT((x2 - x).norm(), 1e-12);
  }
}

TEST(FalconDeltaKinematics, JacobianMatchesFiniteDifferences) {
  DeltaKinematics k;
  const double h = 1e-6;
  for (const Eigen::Vector3d& theta : angle_grid()) {
    Eigen::Vector3d x;
    ASSERT_TRUE(k.forward(theta, x));
    Eigen::Matrix3d j;
    ASSERT_TRUE(k.jacobian(theta, x, j));
    Eigen::Matrix3d fd;
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d tp = theta, tm = theta, xp, xm;
      tp[c] += h, tm[c] -= h;
      ASSERT_TRUE(k.forward(tp, xp) && k.forward(tm, xm));
      fd.col(c) = (xp - xm) / (2 * h);
    }
    EXPECT_LT((fd - j).norm(), 1e-6 * (1 + j.norm())) << "\n" << j << "\n" << fd;
  }
}

TEST(FalconDeltaKinematics, EncodersRoundTripAndWrapLikeTheFirmware) {
  DeltaKinematics k;
  for (const std::int16_t e : {std::int16_t{0}, std::int16_t{1447}, std::int16_t{-2000}})
    EXPECT_EQ(k.encoder(k.angle(e)), e);
  // One count is 2π/1280 of a motor turn through the capstan.
  EXPECT_NEAR(k.angle(1) - k.angle(0), 2 * 3.141592653589793 / 1280 * 0.01425 / 0.110, 1e-15);
}

TEST(FalconDeltaKinematics, ForceToDacKeepsTheDirectionWhenSaturated) {
  DeltaKinematics k;
  Eigen::Vector3d x;
  const Eigen::Vector3d theta = k.angles({0, 0, 0});
  ASSERT_TRUE(k.forward(theta, x));
  Eigen::Matrix3d j;
  ASSERT_TRUE(k.jacobian(theta, x, j));
  std::array<std::int16_t, 3> d{};
  EXPECT_EQ(k.dac(j, Eigen::Vector3d(0, 0, 1), d), 1.0);
  const Eigen::Vector3d tau = k.torque(d);
  EXPECT_LT((tau - j.transpose() * Eigen::Vector3d(0, 0, 1)).norm(), 1e-3);
  const double s = k.dac(j, Eigen::Vector3d(500, -300, 800), d);
  EXPECT_LT(s, 1.0);
  EXPECT_LE(std::abs(d[0]), 4096);
  EXPECT_EQ(k.dac(j, Eigen::Vector3d(NAN, 0, 0), d), 0.0);
  EXPECT_EQ(d, (std::array<std::int16_t, 3>{}));
}

}  // namespace
}  // namespace saw::drivers::falcon
