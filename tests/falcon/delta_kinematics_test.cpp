// The Falcon's delta kinematics: forward/inverse consistency, the Jacobian against finite
// differences, encoders and DAC scaling.
#include "saw/drivers/falcon/delta_kinematics.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

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

// Rows of a CSV from tests/falcon/reference (header skipped), each as numbers.
std::vector<std::vector<double>> reference_rows(const std::string& file) {
  std::ifstream in(std::string(SAW_FALCON_REFERENCE_DIR "/") + file);
  EXPECT_TRUE(in) << file;
  std::vector<std::vector<double>> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    if (!row.empty()) rows.push_back(row);
  }
  return rows;
}

std::array<std::int16_t, 3> encoders_of(const std::vector<double>& row) {
  return {static_cast<std::int16_t>(row[0]), static_cast<std::int16_t>(row[1]),
          static_cast<std::int16_t>(row[2])};
}

// Against libnifalcon's geometry (tests/falcon/reference, written from libnifalcon, not from
// this code): 144 encoder triples → tip in metres. Catches the missing offsets d, e, f, s (the
// shin modelled as a bare sphere of radius b put the tip 23–35 mm off). Tolerance 1 µm: both
// solve exactly (the reference to 1e-13 rad), so the rest is rounding.
TEST(FalconDeltaKinematics, ForwardMatchesTheLibnifalconReference) {
  const DeltaKinematics k;
  const auto rows = reference_rows("positions.csv");
  ASSERT_GE(rows.size(), 100u);
  double worst = 0;
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 6u);
    const Eigen::Vector3d expected(row[3], row[4], row[5]);
    Eigen::Vector3d x;
    ASSERT_TRUE(k.forward(k.angles(encoders_of(row)), x)) << expected.transpose();
    worst = std::max(worst, (x - expected).norm());
    EXPECT_LT((x - expected).norm(), 1e-6) << "encoders " << row[0] << " " << row[1] << " " << row[2] << ": "
                                           << x.transpose() << " vs " << expected.transpose();
    Eigen::Vector3d theta;  // and back: the encoder counts the reference started from
    ASSERT_TRUE(k.inverse(expected, theta));
    for (int i = 0; i < 3; ++i) EXPECT_EQ(k.encoder(theta[i]), encoders_of(row)[static_cast<std::size_t>(i)]);
  }
  std::printf("worst |forward − reference| over %zu poses: %.3g m\n", rows.size(), worst);
}

// The Jacobian dx/dθ (m/rad) at 36 reference poses: relative 1e-6 of its norm (the reference's
// analytic Jacobian agrees with its central differences to 5e-10). Catches the same geometry.
TEST(FalconDeltaKinematics, JacobianMatchesTheLibnifalconReference) {
  const DeltaKinematics k;
  const auto rows = reference_rows("jacobians.csv");
  ASSERT_GE(rows.size(), 30u);
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 12u);
    Eigen::Matrix3d expected;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) expected(r, c) = row[static_cast<std::size_t>(3 + 3 * r + c)];
    const Eigen::Vector3d theta = k.angles(encoders_of(row));
    Eigen::Vector3d x;
    ASSERT_TRUE(k.forward(theta, x));
    Eigen::Matrix3d j;
    ASSERT_TRUE(k.jacobian(theta, x, j));
    EXPECT_LT((j - expected).norm(), 1e-6 * expected.norm()) << "\n" << j << "\nvs\n" << expected;
  }
}

// libnifalcon's landmarks (tests/falcon/reference/README.md): encoders 0 → (0, 0, 134.6 mm),
// −516 each → (0, 0, 110 mm).
TEST(FalconDeltaKinematics, ReferenceLandmarks) {
  const DeltaKinematics k;
  Eigen::Vector3d x;
  ASSERT_TRUE(k.forward(k.angles({0, 0, 0}), x));
  EXPECT_NEAR(x.z(), 0.1346, 1e-4);
  ASSERT_TRUE(k.forward(k.angles({-516, -516, -516}), x));
  EXPECT_NEAR(x.z(), 0.110, 1e-4);
  EXPECT_NEAR(x.head<2>().norm(), 0, 1e-9);
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
