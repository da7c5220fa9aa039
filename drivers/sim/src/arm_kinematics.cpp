#include "saw/drivers/arm_kinematics.hpp"

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

namespace saw::drivers {

struct ArmKinematics::Kdl {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  KDL::JntArray q{3};
  KDL::Frame frame;
  KDL::Jacobian jacobian{3};
};

namespace {
KDL::Chain make_chain(ArmModel model) {
  using KDL::Frame, KDL::Joint, KDL::Segment, KDL::Vector;
  KDL::Chain c;
  if (model == ArmModel::omni) {
    constexpr double link = 0.133;
    c.addSegment(Segment(Joint(Joint::RotZ), Frame(Vector(0, 0, 0))));     // base yaw
    c.addSegment(Segment(Joint(Joint::RotY), Frame(Vector(link, 0, 0))));  // shoulder pitch
    c.addSegment(Segment(Joint(Joint::RotY), Frame(Vector(link, 0, 0))));  // elbow pitch
  } else {
    c.addSegment(Segment(Joint(Joint::TransX), Frame::Identity()));
    c.addSegment(Segment(Joint(Joint::TransY), Frame::Identity()));
    c.addSegment(Segment(Joint(Joint::TransZ), Frame::Identity()));
  }
  return c;
}
}  // namespace

ArmKinematics::ArmKinematics(ArmModel model) : model_(model), kdl_(std::make_unique<Kdl>()) {
  kdl_->chain = make_chain(model);
  kdl_->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(kdl_->chain);
  kdl_->jac = std::make_unique<KDL::ChainJntToJacSolver>(kdl_->chain);
}

ArmKinematics::~ArmKinematics() = default;

std::array<std::string_view, 3> ArmKinematics::joint_names() const noexcept {
  if (model_ == ArmModel::omni) return {"yaw", "shoulder_pitch", "elbow_pitch"};
  return {"x", "y", "z"};
}

Eigen::Vector3d ArmKinematics::fk(const Eigen::Vector3d& q) noexcept {
  for (unsigned i = 0; i < 3; ++i) kdl_->q(i) = q[i];
  kdl_->fk->JntToCart(kdl_->q, kdl_->frame);
  const auto& p = kdl_->frame.p;
  return {p.x(), p.y(), p.z()};
}

Eigen::Matrix3d ArmKinematics::jacobian(const Eigen::Vector3d& q) noexcept {
  for (unsigned i = 0; i < 3; ++i) kdl_->q(i) = q[i];
  kdl_->jac->JntToJac(kdl_->q, kdl_->jacobian);
  return kdl_->jacobian.data.topRows<3>();
}

}  // namespace saw::drivers
