#include "saw/drivers/arm_kinematics.hpp"

#include <cmath>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "saw/drivers/falcon/delta_kinematics.hpp"

namespace saw::drivers {

constexpr double omni_link = 0.133;  // m, both links

struct ArmKinematics::Kdl {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  KDL::JntArray q{3};
  KDL::Frame frame;
  KDL::Jacobian jacobian{3};
};

struct ArmKinematics::Delta {
  falcon::DeltaKinematics k;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the tip with every arm at encoder count 0
  Eigen::Vector3d last = Eigen::Vector3d::Zero();    // relative to origin
};

namespace {
KDL::Chain omni_chain() {
  using KDL::Frame, KDL::Joint, KDL::Segment, KDL::Vector;
  KDL::Chain c;
  c.addSegment(Segment(Joint(Joint::RotZ), Frame(Vector(0, 0, 0))));          // base yaw
  c.addSegment(Segment(Joint(Joint::RotY), Frame(Vector(omni_link, 0, 0))));  // shoulder pitch
  c.addSegment(Segment(Joint(Joint::RotY), Frame(Vector(omni_link, 0, 0))));  // elbow pitch
  return c;
}
}  // namespace

ArmKinematics::ArmKinematics(ArmModel model) : model_(model) {
  if (model == ArmModel::omni) {
    kdl_ = std::make_unique<Kdl>();
    kdl_->chain = omni_chain();
    kdl_->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(kdl_->chain);
    kdl_->jac = std::make_unique<KDL::ChainJntToJacSolver>(kdl_->chain);
  } else {
    delta_ = std::make_unique<Delta>();
    (void)delta_->k.forward(delta_->k.angles({0, 0, 0}), delta_->origin);  // the default geometry has it
  }
}

ArmKinematics::~ArmKinematics() = default;

std::array<std::string_view, 3> ArmKinematics::joint_names() const noexcept {
  if (model_ == ArmModel::omni) return {"yaw", "shoulder_pitch", "elbow_pitch"};
  return {"arm0", "arm1", "arm2"};  // as the `falcon` component's measured_js
}

Eigen::Vector3d ArmKinematics::fk(const Eigen::Vector3d& q) noexcept {
  if (delta_) {
    Eigen::Vector3d x;
    if (delta_->k.forward(q, x)) delta_->last = x - delta_->origin;
    return delta_->last;
  }
  for (unsigned i = 0; i < 3; ++i) kdl_->q(i) = q[i];
  kdl_->fk->JntToCart(kdl_->q, kdl_->frame);
  const auto& p = kdl_->frame.p;
  return {p.x(), p.y(), p.z()};
}

bool ArmKinematics::ik(const Eigen::Vector3d& x, Eigen::Vector3d& q) noexcept {
  if (delta_) return delta_->k.inverse(x + delta_->origin, q);
  // Omni: yaw points the arm's plane at the tip; in that plane a two-link arm of equal links,
  // pitched about y (positive pitch lowers the tip), r = L·cos q₁ + L·cos(q₁+q₂), z = −(...sin).
  const double r = std::hypot(x.x(), x.y()), z = x.z(), l = omni_link;
  const double c2 = (r * r + z * z - 2 * l * l) / (2 * l * l);
  if (!(std::abs(c2) <= 1)) return false;
  const double q2 = std::acos(c2);
  q = {std::atan2(x.y(), x.x()), std::atan2(-z, r) - std::atan2(l * std::sin(q2), l + l * c2), q2};
  return q.allFinite();
}

Eigen::Matrix3d ArmKinematics::jacobian(const Eigen::Vector3d& q) noexcept {
  if (delta_) {
    Eigen::Vector3d x;
    Eigen::Matrix3d j;
    if (delta_->k.forward(q, x) && delta_->k.jacobian(q, x, j)) return j;
    return Eigen::Matrix3d::Zero();
  }
  for (unsigned i = 0; i < 3; ++i) kdl_->q(i) = q[i];
  kdl_->jac->JntToJac(kdl_->q, kdl_->jacobian);
  return kdl_->jacobian.data.topRows<3>();
}

}  // namespace saw::drivers
