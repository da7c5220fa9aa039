#include "saw/teleop/collaborative_control_force.hpp"

#include <cmath>

#include "saw/eigen.hpp"

namespace saw::teleop {
namespace {

bool finite(double x) { return std::isfinite(x); }
double seconds(const TaskConfig& t) { return static_cast<double>(t.period.count()) * 1e-9; }

}  // namespace

CollaborativeControlForce::CollaborativeControlForce(std::string name, TaskConfig task, TeleopConfig config)
    : Task(std::move(name), task),
      config_(config),
      slave_offset_(seconds(task) > 0 ? seconds(task) : 0.001, config.offset_limits) {
  auto& st = state_table();
  columns_.operating_state = st.add_column("operating_state", &state_);
  columns_.master_force = st.add_column("master_force", &master_force_);
  columns_.slave_force = st.add_column("slave_force", &slave_force_);
  columns_.master_error = st.add_column("master_error", &master_error_);
  columns_.slave_error = st.add_column("slave_error", &slave_error_);
  columns_.slave_offset = st.add_column("slave_offset", &slave_offset_value_);
  columns_.tracking_error = st.add_column("tracking_error", &tracking_error_);
  columns_.ratcheting = st.add_column("ratcheting", &ratcheting_);
  columns_.clutched = st.add_column("clutched", &clutched_);

  auto& p = provide("teleop");
  p.add_command_read("operating_state", columns_.operating_state);
  p.add_command_read("master_force", columns_.master_force);
  p.add_command_read("slave_force", columns_.slave_force);
  p.add_command_read("tracking_error", columns_.tracking_error);
  p.add_command_write<StateCommand>("state_command",
                                    [this](const StateCommand& c) { handle_state_command(c); });
  p.add_command_write<double>("set_scale", [this](const double& s) {
    Scale next = config_.scale;
    next.scale = s;
    if (!next.valid()) return void(++rejected_);
    if (!rescale_pending_) previous_scale_ = config_.scale;
    config_.scale = next;
    rescale_pending_ = true;  // re-express the offset so the error (and force) do not jump
  });
  p.add_command_write<Gains>("set_gains", [this](const Gains& g) {
    if (!finite(g.master) || !finite(g.slave) || g.master < 0 || g.slave < 0) return void(++rejected_);
    config_.gains = g;
  });
  p.add_command_write<ForceLimits>("set_force_limits", [this](const ForceLimits& l) {
    if (!finite(l.master) || !finite(l.slave) || l.master < 0 || l.slave < 0) return void(++rejected_);
    config_.limits = l;
  });
  p.add_command_write<Prediction>("set_prediction", [this](const Prediction& pr) {
    const auto bad = [](double h) { return !finite(h) || h < 0 || h > 1.0; };
    if (bad(pr.master_horizon) || bad(pr.slave_horizon)) return void(++rejected_);
    config_.prediction = pr;
  });
  p.add_command_write<Vec3>("set_slave_offset", [this](const Vec3& o) {
    if (!finite(o[0]) || !finite(o[1]) || !finite(o[2])) return void(++rejected_);
    config_.slave_offset = o;
    config_.align = true;
    slave_offset_.set_target(to_eigen(o));
  });
  state_event_ = &p.add_event_write<OperatingState>("operating_state");

  for (auto [iface, cp, cv, cf] : {std::tuple{"master", &master_cp_, &master_cv_, &master_cf_},
                                   std::tuple{"slave", &slave_cp_, &slave_cv_, &slave_cf_}}) {
    auto& r = require(iface);
    r.add_function("measured_cp", *cp);
    r.add_function("measured_cv", *cv);
    // A master may be read-only (a da Vinci master through the dVRK's research API): then the
    // operator feels no force, and the law still drives the slave.
    r.add_function("servo_cf", *cf, std::string_view(iface) == "master" ? Need::optional : Need::required);
  }
  required("master")->add_event_handler_write<ButtonEvent>(
      "clutch", [this](const ButtonEvent& b) { clutched_ = b.pressed; }, Need::optional);
  state_.state = config_.start_enabled ? OperatingStateValue::enabled : OperatingStateValue::disabled;
}

void CollaborativeControlForce::set_operating_state(OperatingStateValue s) noexcept {
  if (state_.state == s) return;
  state_.state = s;
  (void)(*state_event_)(state_);
}

void CollaborativeControlForce::handle_state_command(StateCommand c) noexcept {
  switch (c) {
    case StateCommand::enable:
      fault_ = FaultReason::none;
      snap_pending_ = true;
      set_operating_state(OperatingStateValue::enabled);
      break;
    case StateCommand::disable:
      set_operating_state(OperatingStateValue::disabled);
      break;
    case StateCommand::pause:
      if (state_.state == OperatingStateValue::enabled) set_operating_state(OperatingStateValue::paused);
      break;
    case StateCommand::resume:
      if (state_.state == OperatingStateValue::paused) {
        snap_pending_ = true;
        set_operating_state(OperatingStateValue::enabled);
      }
      break;
    case StateCommand::home:
      break;  // nothing to home: the devices home themselves
  }
}

bool CollaborativeControlForce::read_inputs(Input& master, Input& slave) noexcept {
  const auto stale_ns = static_cast<TimeNs>(config_.stale_timeout * 1e9);
  for (auto [in, last, cp, cv, missing, stale] :
       {std::tuple{&master, &last_master_, &master_cp_, &master_cv_, FaultReason::master_missing,
                   FaultReason::master_stale},
        std::tuple{&slave, &last_slave_, &slave_cp_, &slave_cv_, FaultReason::slave_missing,
                   FaultReason::slave_stale}}) {
    Pose pose;
    Twist twist;
    RowStamp stamp;
    if ((*cp)(pose, stamp) == Status::ok && (*cv)(twist) == Status::ok) {
      last->input = {to_eigen(pose.position), to_eigen(twist.linear)};
      last->time = stamp.time;
      last->valid = true;
    } else if (!last->valid) {
      fault_ = missing;
      return false;
    }
    // A read that fails once (a writer pre-empted mid-row, a full retry budget) keeps the last
    // value; only an input older than stale_timeout is a fault.
    if (now() - last->time > stale_ns) {
      fault_ = stale;
      return false;
    }
    *in = last->input;
  }
  return true;
}

Eigen::Vector3d CollaborativeControlForce::predict(const Input& in, double horizon) const noexcept {
  if (!config_.prediction.enabled || horizon <= 0) return in.position;
  // Eq. 7, x(t) = x(t−1) + δt·ẋ(t−1), stepped over the horizon with the last known velocity.
  const double dt = seconds(config());
  const auto steps = static_cast<int>(std::lround(horizon / dt));
  Eigen::Vector3d x = in.position;
  for (int i = 0; i < steps; ++i) x += dt * in.velocity;
  return x;
}

void CollaborativeControlForce::send_forces(const Eigen::Vector3d& f_master,
                                            const Eigen::Vector3d& f_slave) noexcept {
  Wrench w;
  w.force = to_vec3(f_master);
  if (master_cf_.is_bound() && master_cf_(w) != Status::ok) ++refused_sends_;
  w.force = to_vec3(f_slave);
  if (slave_cf_(w) != Status::ok) ++refused_sends_;
  master_force_ = to_vec3(f_master);
  slave_force_ = to_vec3(f_slave);
}

void CollaborativeControlForce::snap_offsets(const Input& master, const Input& slave) noexcept {
  slave_offset_.reset(
      cancelling_slave_offset(predict(master, config_.prediction.master_horizon), master_offset_,
                              predict(slave, config_.prediction.slave_horizon), config_.scale));
}

void CollaborativeControlForce::run() {
  Input master, slave;
  const bool inputs_ok = read_inputs(master, slave);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  if (start_time_ < 0) start_time_ = now();
  if (!inputs_ok) {
    // A stopped or silent device: zero force on both sides, and stay faulted until re-enabled.
    // At start-up, inputs may simply not be published yet: wait up to startup_timeout for them.
    const double grace = config_.startup_timeout > 0 ? config_.startup_timeout : config_.stale_timeout;
    const bool starting = !inputs_seen_ && now() - start_time_ <= static_cast<TimeNs>(grace * 1e9);
    if (state_.state == OperatingStateValue::enabled && !starting)
      set_operating_state(OperatingStateValue::fault);
    send_forces(zero, zero);
    return;
  }
  inputs_seen_ = true;
  if (state_.state != OperatingStateValue::enabled || clutched_) {
    // Forces off; keep the offset cancelling so that enabling or releasing the clutch cannot jump.
    snap_offsets(master, slave);
    snap_pending_ = rescale_pending_ = false;
    ratcheting_ = false;
    send_forces(zero, zero);
    return;
  }
  const Eigen::Vector3d p_m = predict(master, config_.prediction.master_horizon);
  const Eigen::Vector3d p_s = predict(slave, config_.prediction.slave_horizon);
  if (snap_pending_) {
    snap_offsets(master, slave);
    if (config_.align) slave_offset_.set_target(to_eigen(config_.slave_offset));
    snap_pending_ = false;
  }
  if (rescale_pending_) {
    // e_s = d_s − S⁻¹·d_m must not jump: shift o_s by (S'⁻¹ − S⁻¹)·d_m, target included.
    const Eigen::Vector3d d_m = p_m + master_offset_;
    const Eigen::Vector3d shift =
        (config_.scale.master_to_slave() - previous_scale_.master_to_slave()).cwiseProduct(d_m);
    const Eigen::Vector3d target = slave_offset_.target() + shift;
    const bool was_moving = slave_offset_.moving();
    slave_offset_.reset(slave_offset_.offset() + shift);
    if (was_moving) slave_offset_.set_target(target);
    rescale_pending_ = false;
  }
  const Eigen::Vector3d& o_s = slave_offset_.update();
  const LawOutput law =
      compute_law(p_m, master_offset_, p_s, o_s, config_.scale, config_.gains, config_.limits);
  // Ratchet: at a force limit, slip the offset target so the error returns to the limit; the
  // offset follows the jerk-limited trajectory, the saturated force holds meanwhile.
  ratcheting_ = false;
  if (config_.ratchet) {
    const LawOutput at_target = compute_law(p_m, master_offset_, p_s, slave_offset_.target(), config_.scale,
                                            config_.gains, config_.limits);
    if (at_target.master_saturated || at_target.slave_saturated) {
      slave_offset_.set_target(slave_offset_.target() +
                               ratchet_shift(at_target, config_.scale, config_.gains, config_.limits));
      ratcheting_ = true;
    }
    ratcheting_ = ratcheting_ || slave_offset_.moving();
  }
  master_error_ = to_vec3(law.master_error);
  slave_error_ = to_vec3(law.slave_error);
  slave_offset_value_ = to_vec3(o_s);
  tracking_error_ = law.slave_error.norm();
  tracking_sum_sq_ += tracking_error_ * tracking_error_;
  tracking_max_ = std::max(tracking_max_, tracking_error_);
  ++enabled_cycles_;
  // End-to-end: how old the master sample is when the force computed from it is sent (its row
  // time, from this process or another, to this cycle's time).
  master_age_ = now() - last_master_.time;
  master_age_sum_ += static_cast<double>(master_age_);
  master_age_max_ = std::max(master_age_max_, master_age_);
  if (2 * master_age_ >= config().period.count()) ++master_age_late_;
  send_forces(law.master_force, law.slave_force);
}

}  // namespace saw::teleop
