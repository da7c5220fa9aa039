#include "saw/teleop/laws/passive_bilateral.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace saw::teleop {
namespace {
// The controller's damping needs no cap: its force never exceeds the law's along the motion.
constexpr double unlimited = std::numeric_limits<double>::infinity();
}  // namespace

PassiveBilateralLaw::PassiveBilateralLaw(const Settings& s, const LawContext& ctx)
    : s_(s), dt_(ctx.period), slave_port_(s.passivity ? unlimited : 0.0) {}

void PassiveBilateralLaw::reset(const LawInputs& in) noexcept {
  // Engage without a force step. The ports' energies are not reset: the master's port keeps
  // counting beside the master, and the bookkeeping of both ends must stay one account.
  offset_ = s_.scale * in.master.position - in.slave.position;
  rescaled_from_ = 0;
}

void PassiveBilateralLaw::on_set(std::string_view setting, const Settings& before) noexcept {
  if (setting == "scale" && rescaled_from_ == 0) rescaled_from_ = before.scale;
  slave_port_.set_max_damping(s_.passivity ? unlimited : 0.0);
}

LawCommand PassiveBilateralLaw::step(const LawInputs& in) noexcept {
  if (rescaled_from_ != 0) {  // keep e_s: o' − scale'·p_m = o − scale·p_m
    offset_ += (s_.scale - rescaled_from_) * in.master.position;
    rescaled_from_ = 0;
  }
  LawCommand out;
  out.slave_error = in.slave.position + offset_ - s_.scale * in.master.position;
  out.master_error = -out.slave_error / s_.scale;
  out.slave_offset = offset_;
  const Eigen::Vector3d relative = in.slave.velocity - s_.scale * in.master.velocity;
  const Eigen::Vector3d fs = -s_.gains.slave * out.slave_error - s_.damping * relative;
  const Eigen::Vector3d fm = (s_.gains.master * out.slave_error + s_.damping * relative) / s_.scale;
  out.finite = fs.allFinite() && fm.allFinite() && std::isfinite(fs.norm()) && std::isfinite(fm.norm());
  if (!out.finite) {
    out.bad_side = in.master.position.allFinite() ? FaultSide::slave : FaultSide::master;
    return out;
  }
  out.limiting = fs.norm() > s_.limits.slave || fm.norm() > s_.limits.master;
  out.master_force = saturate(fm, s_.limits.master);
  // The slave's port is here: the force it gets is bounded by what entered at the master.
  // Only grows: a late row tells nothing new (none yet: nothing has entered).
  if (const double* e = in.declared.get<double>(0)) master_energy_in_ = std::max(master_energy_in_, *e);
  const PassivityController::Step s =
      slave_port_.step(saturate(fs, s_.limits.slave), in.slave.velocity, master_energy_in_, dt_);
  out.slave_force = s.force;
  slave_energy_in_ = slave_port_.energy().in;
  slave_energy_out_ = slave_port_.energy().out;
  slave_dissipated_ = slave_port_.dissipated();
  slave_damping_ = s.damping;
  (void)in.outputs.set(0, slave_energy_in_);
  return out;
}

}  // namespace saw::teleop
