#include "saw/teleop/laws/collaborative.hpp"

#include <cmath>

#include "saw/eigen.hpp"

namespace saw::teleop {

Prediction SettingCodec<Prediction>::parse(const deploy::Params& p, const std::string& key, double lo,
                                           double hi, const Prediction& fallback) {
  using namespace std::chrono;
  const deploy::Params c = p.child(key);
  Prediction v;
  v.enabled = c.get_or<bool>("enabled", fallback.enabled);
  const auto ns = [](double s) { return nanoseconds(static_cast<std::int64_t>(std::llround(s * 1e9))); };
  v.master_horizon = deploy::seconds_in_range(c, "master", ns(fallback.master_horizon), lo, hi);
  v.slave_horizon = deploy::seconds_in_range(c, "slave", ns(fallback.slave_horizon), lo, hi);
  return v;
}

std::string SettingCodec<Prediction>::text(const Prediction& v) {
  return std::string("{enabled: ") + (v.enabled ? "true" : "false") +
         ", master: " + setting_number(v.master_horizon) + ", slave: " + setting_number(v.slave_horizon) +
         "}";
}

OffsetLimits SettingCodec<OffsetLimits>::parse(const deploy::Params& p, const std::string& key, double,
                                               double, const OffsetLimits& fallback) {
  const deploy::Params c = p.child(key);
  OffsetLimits v;
  v.velocity = c.get_in_range("velocity", min, max_velocity, fallback.velocity);
  v.acceleration = c.get_in_range("acceleration", min, max_acceleration, fallback.acceleration);
  v.jerk = c.get_in_range("jerk", min, max_jerk, fallback.jerk);
  return v;
}

std::string SettingCodec<OffsetLimits>::text(const OffsetLimits& v) {
  return "{velocity: " + setting_number(v.velocity) + ", acceleration: " + setting_number(v.acceleration) +
         ", jerk: " + setting_number(v.jerk) + "}";
}

bool CollaborativeLaw::unit_mirror(const Vec3& m) noexcept { return Scale{1.0, m}.valid(); }

CollaborativeLaw::CollaborativeLaw(const Settings& s, const LawContext& ctx)
    : s_(s), dt_(ctx.period > 0 ? ctx.period : 0.001), offset_(dt_, s.offset_limits), previous_(frame()) {}

void CollaborativeLaw::on_set(std::string_view setting, const Settings& before) noexcept {
  if (setting == "scale" || setting == "prediction") {
    // Scale and prediction change what the offset is expressed in: the next engaged cycle
    // re-expresses it (once, however many changes were queued) so the error does not jump.
    if (!reexpress_pending_) previous_ = {{before.scale, before.mirror}, before.prediction};
    reexpress_pending_ = true;
  } else if (setting == "slave_offset") {
    s_.align = true;
    offset_.set_target(to_eigen(s_.slave_offset));
  } else if (setting == "offset_limits") {
    offset_.set_limits(s_.offset_limits);
  }
}

Eigen::Vector3d CollaborativeLaw::predict(const SideSample& in, double horizon,
                                          const Prediction& pr) const noexcept {
  if (!pr.enabled || horizon <= 0) return in.position;
  // Eq. 7, x(t) = x(t−1) + δt·ẋ(t−1), stepped over the horizon with the last known velocity.
  const auto steps = static_cast<int>(std::lround(horizon / dt_));
  Eigen::Vector3d x = in.position;
  for (int i = 0; i < steps; ++i) x += dt_ * in.velocity;
  return x;
}

void CollaborativeLaw::snap(const LawInputs& in) noexcept {
  const Prediction& pr = s_.prediction;
  offset_.reset(cancelling_slave_offset(predict(in.master, pr.master_horizon, pr), master_offset_,
                                        predict(in.slave, pr.slave_horizon, pr), frame().scale));
}

void CollaborativeLaw::hold(const LawInputs& in) noexcept {
  // Forces off; keep the offset cancelling so that engaging cannot jump.
  snap(in);
  reexpress_pending_ = false;
}

void CollaborativeLaw::reset(const LawInputs& in) noexcept {
  // A snap expresses the offset in the current settings already: a pending re-expression on
  // top of it would apply the change twice.
  snap(in);
  if (s_.align) offset_.set_target(to_eigen(s_.slave_offset));
  reexpress_pending_ = false;
}

void CollaborativeLaw::reexpress(const LawInputs& in) noexcept {
  // e_s = d_s − S⁻¹·d_m must not jump: shift o_s (target included) by the difference between
  // e_s under the settings before the change and after it, for the same inputs and offset.
  const Eigen::Vector3d o_s = offset_.offset();
  const auto error = [&](const Frame& f) -> Eigen::Vector3d {
    const Prediction& pr = f.prediction;
    const Eigen::Vector3d d_m = predict(in.master, pr.master_horizon, pr) + master_offset_;
    const Eigen::Vector3d d_s = predict(in.slave, pr.slave_horizon, pr) + o_s;
    return d_s - f.scale.master_to_slave().cwiseProduct(d_m);
  };
  const Eigen::Vector3d shift = error(previous_) - error(frame());
  const Eigen::Vector3d target = offset_.target() + shift;
  const bool was_moving = offset_.moving();
  offset_.reset(o_s + shift);
  if (was_moving) offset_.set_target(target);
}

bool CollaborativeLaw::ratchet(const Eigen::Vector3d& p_m, const Eigen::Vector3d& p_s) noexcept {
  // At a force limit, slip the offset target so the error returns to the limit; the offset
  // follows the jerk-limited trajectory, the saturated force holds meanwhile.
  if (!s_.ratchet) return false;
  const Scale scale = frame().scale;
  bool slipping = false;
  const LawOutput at_target =
      compute_law(p_m, master_offset_, p_s, offset_.target(), scale, s_.gains, s_.limits);
  if (at_target.finite && (at_target.master_saturated || at_target.slave_saturated)) {
    offset_.set_target(offset_.target() + ratchet_shift(at_target, scale, s_.gains, s_.limits));
    slipping = true;
  }
  return slipping || offset_.moving();
}

LawCommand CollaborativeLaw::step(const LawInputs& in) noexcept {
  if (reexpress_pending_) {
    reexpress(in);
    reexpress_pending_ = false;
  }
  (void)offset_.update();
  const Prediction& pr = s_.prediction;
  const Eigen::Vector3d p_m = predict(in.master, pr.master_horizon, pr);
  const Eigen::Vector3d p_s = predict(in.slave, pr.slave_horizon, pr);
  const LawOutput law =
      compute_law(p_m, master_offset_, p_s, offset_.offset(), frame().scale, s_.gains, s_.limits);
  LawCommand out;
  out.master_error = law.master_error;
  out.slave_error = law.slave_error;
  if (!law.finite) {
    out.finite = false;
    const bool master_bad = !law.master_error.allFinite() || !std::isfinite(law.master_error.norm());
    out.bad_side = master_bad ? FaultSide::master : FaultSide::slave;
    return out;
  }
  out.limiting = ratchet(p_m, p_s);
  out.master_force = law.master_force;
  out.slave_force = law.slave_force;
  out.slave_offset = offset_.offset();
  return out;
}

}  // namespace saw::teleop
