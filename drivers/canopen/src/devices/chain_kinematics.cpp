#include "saw/canopen/chain_kinematics.hpp"

#include <cmath>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <stdexcept>
#include <string>

namespace saw::canopen {

struct ChainKinematics::Kdl {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  KDL::JntArray q;
  KDL::Frame frame;
  KDL::Jacobian jacobian;

  void load(std::span<const double> values) noexcept {
    for (unsigned i = 0; i < q.rows() && i < values.size(); ++i) q(i) = values[i];
  }
};

namespace {

KDL::Frame frame_of(const Vec3& xyz, const Vec3& rpy) {
  return KDL::Frame(KDL::Rotation::RPY(rpy[0], rpy[1], rpy[2]), KDL::Vector(xyz[0], xyz[1], xyz[2]));
}

}  // namespace

ChainKinematics::ChainKinematics(const ChainSpec& spec) : kdl_(std::make_unique<Kdl>()) {
  if (spec.joints.empty()) throw std::invalid_argument("a kinematic chain needs at least one joint");
  if (spec.joints.size() > JointState::max_joints)
    throw std::invalid_argument("a kinematic chain has at most " + std::to_string(JointState::max_joints) +
                                " joints");
  for (std::size_t i = 0; i < spec.joints.size(); ++i) {
    const ChainJoint& j = spec.joints[i];
    const KDL::Vector axis(j.axis[0], j.axis[1], j.axis[2]);
    const double norm = axis.Norm();
    if (!std::isfinite(norm) || norm < 1e-9)
      throw std::invalid_argument("joint " + std::to_string(i + 1) +
                                  ": the axis must be a non-zero direction");
    // The origin as a fixed segment, then the joint about (or along) its axis at that origin.
    kdl_->chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame_of(j.xyz, j.rpy)));
    const auto type = j.type == ChainJoint::Type::revolute ? KDL::Joint::RotAxis : KDL::Joint::TransAxis;
    kdl_->chain.addSegment(
        KDL::Segment(KDL::Joint(KDL::Vector::Zero(), axis / norm, type), KDL::Frame::Identity()));
  }
  kdl_->chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), frame_of(spec.tip_xyz, spec.tip_rpy)));
  joints_ = spec.joints.size();
  kdl_->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(kdl_->chain);
  kdl_->jac = std::make_unique<KDL::ChainJntToJacSolver>(kdl_->chain);
  kdl_->q.resize(static_cast<unsigned>(joints_));
  kdl_->jacobian.resize(static_cast<unsigned>(joints_));
}

ChainKinematics::~ChainKinematics() = default;

Pose ChainKinematics::fk(std::span<const double> q) noexcept {
  kdl_->load(q);
  kdl_->fk->JntToCart(kdl_->q, kdl_->frame);
  Pose p;
  const KDL::Vector& x = kdl_->frame.p;
  p.position = {x.x(), x.y(), x.z()};
  kdl_->frame.M.GetQuaternion(p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]);
  return p;
}

Twist ChainKinematics::velocity(std::span<const double> q, std::span<const double> qd) noexcept {
  kdl_->load(q);
  kdl_->jac->JntToJac(kdl_->q, kdl_->jacobian);
  Twist t;
  for (unsigned r = 0; r < 6; ++r) {
    double v = 0;
    for (unsigned c = 0; c < joints_ && c < qd.size(); ++c) v += kdl_->jacobian(r, c) * qd[c];
    (r < 3 ? t.linear[r] : t.angular[r - 3]) = v;
  }
  return t;
}

void ChainKinematics::joint_torques(std::span<const double> q, const Wrench& w,
                                    std::span<double> tau) noexcept {
  kdl_->load(q);
  kdl_->jac->JntToJac(kdl_->q, kdl_->jacobian);
  const double wrench[6] = {w.force[0], w.force[1], w.force[2], w.torque[0], w.torque[1], w.torque[2]};
  for (unsigned c = 0; c < joints_ && c < tau.size(); ++c) {
    double t = 0;
    for (unsigned r = 0; r < 6; ++r) t += kdl_->jacobian(r, c) * wrench[r];
    tau[c] = t;
  }
}

}  // namespace saw::canopen
