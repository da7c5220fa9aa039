#include "saw/drivers/instrument_kinematics.hpp"

#include <Eigen/Cholesky>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

namespace saw::drivers {

struct InstrumentKinematics::Kdl {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  KDL::JntArray q{dof};
  KDL::Frame frame;
  KDL::Jacobian jacobian{dof};
};

namespace {

KDL::Chain instrument_chain() {
  using KDL::Frame, KDL::Joint, KDL::Segment, KDL::Vector;
  KDL::Chain c;
  c.addSegment(Segment(Joint(Joint::RotX)));  // outer yaw
  c.addSegment(Segment(Joint(Joint::RotY)));  // outer pitch
  c.addSegment(
      Segment(Joint("insertion", Vector(0, 0, 0), Vector(0, 0, -1), Joint::TransAxis)));  // along the shaft
  c.addSegment(Segment(Joint(Joint::RotZ)));                                              // shaft roll
  c.addSegment(Segment(Joint(Joint::RotX), Frame(Vector(0, 0, -InstrumentKinematics::wrist_pitch_to_yaw))));
  c.addSegment(Segment(Joint(Joint::RotY), Frame(Vector(0, 0, -InstrumentKinematics::wrist_yaw_to_tip))));
  return c;
}

}  // namespace

InstrumentKinematics::InstrumentKinematics() : kdl_(std::make_unique<Kdl>()) {
  kdl_->chain = instrument_chain();
  kdl_->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(kdl_->chain);
  kdl_->jac = std::make_unique<KDL::ChainJntToJacSolver>(kdl_->chain);
}

InstrumentKinematics::~InstrumentKinematics() = default;

std::array<std::string_view, InstrumentKinematics::dof> InstrumentKinematics::joint_names() noexcept {
  return {"outer_yaw", "outer_pitch", "outer_insertion", "outer_roll", "wrist_pitch", "wrist_yaw"};
}

Eigen::Isometry3d InstrumentKinematics::fk(const Joints& q) noexcept {
  for (unsigned i = 0; i < dof; ++i) kdl_->q(i) = q[i];
  kdl_->fk->JntToCart(kdl_->q, kdl_->frame);
  const KDL::Frame& f = kdl_->frame;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.linear()(r, c) = f.M(static_cast<unsigned>(r), static_cast<unsigned>(c));
    t.translation()[r] = f.p(static_cast<unsigned>(r));
  }
  return t;
}

Eigen::Matrix<double, 6, InstrumentKinematics::dof> InstrumentKinematics::jacobian(const Joints& q) noexcept {
  for (unsigned i = 0; i < dof; ++i) kdl_->q(i) = q[i];
  kdl_->jac->JntToJac(kdl_->q, kdl_->jacobian);
  return kdl_->jacobian.data;  // KDL's twist order: linear, then angular
}

bool InstrumentKinematics::ik(const Eigen::Isometry3d& goal, const Joints& min, const Joints& max, Joints& q,
                              int iterations) noexcept {
  constexpr double damping = 1e-4;  // λ²: well-conditioned near singular wrists, exact elsewhere
  for (int k = 0; k <= iterations; ++k) {
    const Eigen::Isometry3d at = fk(q);
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = goal.translation() - at.translation();
    const Eigen::AngleAxisd turn(goal.linear() * at.linear().transpose());
    e.tail<3>() = turn.axis() * turn.angle();
    if (e.head<3>().norm() < 1e-6 && e.tail<3>().norm() < 1e-5) return true;
    if (k == iterations) break;
    const Eigen::Matrix<double, 6, dof> j = jacobian(q);
    const Eigen::Matrix<double, 6, 6> jjt =
        j * j.transpose() + damping * Eigen::Matrix<double, 6, 6>::Identity();
    q = (q + j.transpose() * jjt.ldlt().solve(e)).cwiseMax(min).cwiseMin(max);
  }
  return false;
}

}  // namespace saw::drivers
