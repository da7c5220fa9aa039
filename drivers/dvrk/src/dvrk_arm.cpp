#include "saw/drivers/dvrk/dvrk_arm.hpp"

#include <cmath>
#include <stdexcept>

#include "saw/crtk_arm.hpp"

namespace saw::drivers::dvrk {
namespace {

constexpr std::string_view source = "dvrk";
constexpr int max_not_sent = 10;  // the import's queue full this many cycles in a row: FAULT
constexpr TimeNs resend_state_after = 1'000'000'000;  // an enable or home with no effect: again
// A move the arm has not shown busy within this long is over (or was too short to be seen): the
// dVRK says busy as its trajectory starts, within a few of its 1 ms cycles and the import's hops.
constexpr TimeNs move_start_window = 500'000'000;

DvrkArmConfig checked(DvrkArmConfig c) {
  const bool psm = follows_poses(c.kind);
  if (psm && c.safe_command == SafeCommand::zero_wrench)
    throw std::invalid_argument(
        "a PSM's or ECM's safe command is hold or servo_cp_measured (a zero wrench drops it)");
  if (!psm && c.safe_command == SafeCommand::servo_cp_measured)
    throw std::invalid_argument("an MTM's safe command is zero_wrench or hold");
  if (!(c.stale_timeout > 0)) throw std::invalid_argument("stale_timeout must be positive");
  if (c.joints.size() > JointState::max_joints) throw std::invalid_argument("at most 8 joints");
  if (c.servo_jp && c.joints.empty()) throw std::invalid_argument("servo_jp needs the arm's joints");
  return c;
}

// The contract the base runs for it: an MTM takes wrenches (safe at zero force), a PSM poses
// (safe where it holds).
DeviceConfig contract_of(const DvrkArmConfig& c) {
  DeviceConfig d;
  d.settings() = c.contract;
  const bool psm = follows_poses(c.kind);
  d.safe_state = psm ? SafeState::hold : SafeState::zero_force;
  d.servo_cf = !psm;
  d.servo_cp = psm;
  d.joints = c.joints;
  d.servo_jp = c.servo_jp;
  return d;
}

bool finite(const Pose& p) noexcept {
  for (double v : p.position)
    if (!std::isfinite(v)) return false;
  for (double v : p.orientation)
    if (!std::isfinite(v)) return false;
  return Pose::valid(p);
}

bool finite(const Wrench& w) noexcept {
  for (std::size_t k = 0; k < 3; ++k)
    if (!std::isfinite(w.force[k]) || !std::isfinite(w.torque[k])) return false;
  return true;
}

}  // namespace

DvrkArm::DvrkArm(std::string name, TaskConfig task, DvrkArmConfig config)
    : DvrkArm(std::move(name), task, Checked<DvrkArmConfig>{checked(std::move(config))}) {}

DvrkArm::DvrkArm(std::string name, TaskConfig task, Checked<DvrkArmConfig> config)
    : Device(std::move(name), task, contract_of(config.value)), arm_config_(std::move(config.value)) {
  namespace arm = crtk::arm;
  const bool psm = follows_poses(arm_config_.kind);
  auto& r = require(std::string(source));
  crtk::require(r, arm::measured_cp, read_cp_);
  crtk::require(r, arm::measured_cv, read_cv_, Need::optional);
  crtk::require(r, arm::operating_state, read_state_);
  crtk::require(r, arm::state_command, write_state_);
  if (!psm) crtk::require(r, arm::servo_cf, write_cf_);
  if (psm || arm_config_.safe_command == SafeCommand::servo_cp_measured)
    crtk::require(r, arm::servo_cp, write_cp_);
  r.add_function("errors", read_errors_, Need::optional);
  r.add_function("hold", hold_,
                 arm_config_.safe_command == SafeCommand::hold ? Need::required : Need::optional);
  // The console's pedals (the import's events), as this device's buttons.
  crtk::require(
      r, arm::clutch, [this](const ButtonEvent& b) { button(Button::clutch, b.pressed); }, Need::optional);
  crtk::require(
      r, arm::operator_present, [this](const ButtonEvent& b) { button(Button::operator_present, b.pressed); },
      Need::optional);
  auto& a = *provided(std::string(arm::interface_name));
  // What the arm measures, passed on checked; with joints, measured_js and servo_jp.
  crtk::require(r, arm::measured_cf, read_cf_, Need::optional);
  crtk::provide(a, arm::measured_cf, state_table(), &cf_);
  if (!arm_config_.joints.empty()) crtk::require(r, arm::measured_js, read_js_, Need::optional);
  if (arm_config_.servo_jp) crtk::require(r, arm::servo_jp, write_jp_);
  // Moves the dVRK plans itself, and an MTM's free: what the import allows.
  crtk::require(r, arm::move_cp, move_cp_, Need::optional);
  crtk::require(r, arm::move_jp, move_jp_, Need::optional);
  crtk::provide(a, arm::move_cp, [this](const Pose& x) { on_move_cp(x); });
  crtk::provide(a, arm::move_jp, [this](const JointState& j) { on_move_jp(j); });
  if (!psm) {
    r.add_function("free", free_, Need::optional);
    a.add_command_void("free", [this] { on_free(); });
  }
  // The gripper (MTM) or the jaw (PSM), passed on checked; an ECM has neither.
  if (arm_config_.kind == ArmKind::psm) {
    crtk::require(r, arm::jaw_measured_js, read_jaw_, Need::optional);
    crtk::require(r, arm::jaw_servo_jp, write_jaw_, Need::optional);
    crtk::provide(a, arm::jaw_measured_js, state_table(), &jaw_);
    crtk::provide(a, arm::jaw_servo_jp, [this](const JointState& j) { on_jaw(j); });
  } else if (arm_config_.kind == ArmKind::mtm) {
    crtk::require(r, arm::gripper_measured_js, read_jaw_, Need::optional);
    crtk::provide(a, arm::gripper_measured_js, state_table(), &jaw_);
  }
  provide("dvrk").add_command_read("summary",
                                   state_table().add_column("summary", &summary_, ColumnUse::summary));
}

void DvrkArm::open() {
  // Connected by the deployment to the arm's import; a missing one is a failed start, said.
  if (!read_cp_.is_bound() || !read_state_.is_bound() || !write_state_.is_bound())
    throw std::runtime_error(
        "its 'dvrk' interface is not connected to the arm's import (saw-gateway --import)");
}

Outcome DvrkArm::read() {
  Pose cp;
  RowStamp stamp;
  const Status s = read_cp_(cp, stamp);
  if (s == Status::ok) {
    if (finite(cp)) {
      measured().cp = cp;
      cp_time_ = stamp.time;
    } else {
      ++summary_.bad_poses;  // refused, never used: the last good pose stands
    }
  }
  Twist cv;
  if (read_cv_.is_bound() && read_cv_(cv) == Status::ok) {
    bool ok = true;
    for (std::size_t k = 0; k < 3; ++k)
      ok = ok && std::isfinite(cv.linear[k]) && std::isfinite(cv.angular[k]);
    if (ok) measured().cv = cv;
  }
  Wrench cf;
  if (read_cf_.is_bound() && read_cf_(cf) == Status::ok && finite(cf)) cf_ = cf;
  read_joints();
  JointState jaw;
  if (read_jaw_.is_bound() && read_jaw_(jaw) == Status::ok && jaw.size >= 1 && std::isfinite(jaw.position[0]))
    jaw_ = jaw;
  OperatingState arm;
  if (read_state_(arm) == Status::ok) {
    summary_.arm = arm;
    have_state_ = true;
  }
  // The arm's trajectory after a move of ours is this device's busy (not a homing by the console).
  // The move is over once the arm is idle after it was busy, or was never busy for a while (a
  // move too short to be seen; the arm's busy lags the command): a later busy is not ours.
  if (moved_) {
    if (summary_.arm.is_busy)
      move_seen_busy_ = true;
    else if (move_seen_busy_ || now() - moved_at_ > move_start_window)
      moved_ = false;
  }
  set_moving(moved_ && summary_.arm.is_busy);
  std::uint64_t errors = 0;
  const bool errors_read = read_errors_.is_bound() && read_errors_(errors) == Status::ok;
  // The arm's errors before it was driven (the dVRK latches its last ones) are not this run's.
  if (!following()) {
    if (errors_read) errors_before_ = errors;
    return Outcome::done();  // enable() and home() judge what they need
  }
  if (s == Status::disconnected)
    return Outcome::failed(FaultCode::device_lost, "the arm's import is gone (its gateway stopped)", source);
  const TimeNs age = cp_time_ < 0 ? arm_config_.stale_timeout + 1 : now() - cp_time_;
  if (age > arm_config_.stale_timeout)
    return Outcome::failed(FaultCode::input_stale, "stale: the dVRK stopped publishing", "measured_cp", 0,
                           age);
  if (summary_.arm.state == OperatingStateValue::fault)
    return Outcome::failed(FaultCode::device_fault, "the dVRK arm is in FAULT", source);
  if (summary_.arm.state != OperatingStateValue::enabled)
    return Outcome::failed(FaultCode::device_disabled, "the dVRK arm left ENABLED", source);
  if (!summary_.arm.is_homed)
    return Outcome::failed(FaultCode::device_fault, "the dVRK arm is no longer homed", source);
  if (errors_read && errors > errors_before_)
    return Outcome::failed(FaultCode::device_error,
                           "the dVRK arm reported an error (its words: the gateway's log)", source);
  return Outcome::done();
}

Outcome DvrkArm::send_state(StateCommand c, bool& sent, const char* why) noexcept {
  // Sent, and the arm idle and not there a while later: the command was lost (the import's
  // reliable writer had matched a reader that was gone: the dVRK restarted). Sent again; the
  // dVRK takes a repeated enable or home as the first.
  const TimeNs t = now();
  if (sent && !summary_.arm.is_busy && t - state_sent_at_ > resend_state_after) sent = false;
  if (sent) return Outcome::pending();
  const Status s = write_state_(c);
  if (s == Status::disconnected) return Outcome::failed(FaultCode::device_lost, why, source);
  sent = s == Status::ok;  // a full queue: tried again next cycle
  if (sent) {
    state_sent_at_ = t;
    ++summary_.state_commands;
  }
  return Outcome::pending();
}

Outcome DvrkArm::enable() {
  // Nothing known of the arm yet: wait (enable_timeout says when that is too long).
  if (!have_state_ || cp_time_ < 0) return Outcome::pending();
  const OperatingState& arm = summary_.arm;
  // The dVRK takes an `enable` in FAULT but does nothing with it until a `disable`: an operator's
  // decision, at the arm's console (ours never powers an arm off).
  if (arm.state == OperatingStateValue::fault)
    return Outcome::failed(FaultCode::device_fault,
                           "the dVRK arm is in FAULT: clear it at its console (disable, then enable)",
                           source);
  if (arm.state != OperatingStateValue::enabled)
    return send_state(StateCommand::enable, enable_sent_, "the enable did not reach the arm's import");
  if (arm.is_busy) return Outcome::pending();  // powering, or homing from the dVRK's console
  enable_sent_ = false;
  if (!arm.is_homed) {
    if (!arm_config_.home)
      return Outcome::failed(FaultCode::device_disabled,
                             "not homed: home it from the dVRK console, or set home: true (it moves)",
                             source);
    start_homing();  // home() sends `home`, now that it is ENABLED
  }
  return Outcome::done();
}

Outcome DvrkArm::home() {
  const OperatingState& arm = summary_.arm;
  // The dVRK homes only an ENABLED arm.
  if (arm.state != OperatingStateValue::enabled)
    return Outcome::failed(FaultCode::device_disabled, "the dVRK arm is not ENABLED: enable it before homing",
                           source);
  // Homed and idle: done (an operator's `home` to a homed arm sends nothing: it would move it).
  if (arm.is_homed && !arm.is_busy) {
    home_sent_ = false;
    return Outcome::done();
  }
  return send_state(StateCommand::home, home_sent_, "the home did not reach the arm's import");
}

void DvrkArm::on_jaw(const JointState& j) noexcept {
  if (j.size < 1 || !std::isfinite(j.position[0]) || j.position[0] < arm_config_.jaw_min ||
      j.position[0] > arm_config_.jaw_max) {
    ++summary_.jaw_refused;
    return;
  }
  jaw_goal_ = JointState{};
  jaw_goal_.size = 1;
  jaw_goal_.position[0] = j.position[0];
  jaw_pending_ = true;
}

void DvrkArm::read_joints() noexcept {
  const std::size_t n = arm_config_.joints.size();
  JointState js;
  if (n == 0 || !read_js_.is_bound() || read_js_(js) != Status::ok) return;
  bool ok = js.size == n;
  for (std::size_t i = 0; ok && i < n; ++i)
    ok = std::isfinite(js.position[i]) && std::isfinite(js.velocity[i]) && std::isfinite(js.effort[i]);
  if (!ok) {
    ++summary_.bad_joint_states;  // a cycle whose sample was refused: the last good one stands
    return;
  }
  JointState& m = measured().js;
  for (std::size_t i = 0; i < n; ++i) {
    m.position[i] = js.position[i];
    m.velocity[i] = js.velocity[i];
    m.effort[i] = js.effort[i];
  }
}

void DvrkArm::on_move_cp(const Pose& p) noexcept {
  bool inside = move_cp_.is_bound() && finite(p);
  for (std::size_t k = 0; inside && k < 3; ++k)
    inside = p.position[k] >= contract().workspace_min[k] && p.position[k] <= contract().workspace_max[k];
  if (!inside) {
    ++summary_.moves_refused;
    return;
  }
  request_ = Request{Request::Kind::move_cp, p, {}};
  end_servo();
}

void DvrkArm::on_move_jp(const JointState& j) noexcept {
  const std::size_t n = arm_config_.joints.size();
  bool ok = move_jp_.is_bound() && n > 0 && j.size == n;
  Request r{Request::Kind::move_jp, {}, {}};
  r.joints.size = static_cast<decltype(r.joints.size)>(n);
  for (std::size_t i = 0; ok && i < n; ++i) {
    const JointLimits& l = arm_config_.joints[i];
    ok = std::isfinite(j.position[i]) && j.position[i] >= l.min && j.position[i] <= l.max;
    r.joints.position[i] = j.position[i];
  }
  if (!ok) {
    ++summary_.moves_refused;
    return;
  }
  request_ = r;
  end_servo();
}

void DvrkArm::on_free() noexcept {
  if (!free_.is_bound()) {
    ++summary_.moves_refused;
    return;
  }
  request_ = Request{Request::Kind::free, {}, {}};
  end_servo();
}

// In a cycle without a servo command: the client's move or free, once the arm is driven. The
// dVRK's own busy (a homing from its console) holds it back; a move of ours it replaces.
Outcome DvrkArm::send_request() noexcept {
  using Kind = Request::Kind;
  if (request_.kind == Kind::none) return Outcome::done();
  if (!following()) {
    ++summary_.moves_refused;
    request_ = {};
    return Outcome::done();
  }
  if (summary_.arm.is_busy && !moved_) {
    ++summary_.held_busy;
    return Outcome::done();
  }
  const Kind kind = request_.kind;
  const Status st = kind == Kind::move_cp   ? move_cp_(request_.pose)
                    : kind == Kind::move_jp ? move_jp_(request_.joints)
                                            : free_();
  if (st == Status::disconnected)
    return Outcome::failed(FaultCode::device_lost, "the arm's import is gone (its gateway stopped)", source);
  if (st != Status::ok) {
    ++summary_.not_sent;  // tried again in the next cycle
    return Outcome::done();
  }
  request_ = {};
  ++summary_.moves;
  moved_ = kind != Kind::free;
  moved_at_ = now();
  move_seen_busy_ = false;
  // Our servo commands are replaced: a move is undone by the safe command on a stop (moved_),
  // free is no effort (nothing of ours left to undo).
  commanded_ = false;
  return Outcome::done();
}

// A PSM's servo goals that take no effect: the dVRK drops Cartesian commands, with a warning and
// no state, while the tool is not past the cannula (and a stuck or blocked arm looks the same).
// Judged on the goal sent last cycle against this cycle's measured pose.
Outcome DvrkArm::check_following() noexcept {
  if (!goal_live_ || arm_config_.following_error <= 0) {
    far_since_ = -1;
    return Outcome::done();
  }
  Vec3 d{};
  for (std::size_t k = 0; k < 3; ++k) d[k] = measured().cp.position[k] - goal_sent_[k];
  const double distance = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (distance <= arm_config_.following_error) {
    far_since_ = -1;
    return Outcome::done();
  }
  if (far_since_ < 0) far_since_ = now();
  if (now() - far_since_ < arm_config_.following_time) return Outcome::done();
  far_since_ = -1;
  return Outcome::failed(FaultCode::device_error,
                         "the arm does not follow its servo_cp goals (further than following_error for "
                         "following_time): a tool not past the cannula? the dVRK's warning is in the log",
                         "measured_cp");
}

Outcome DvrkArm::write(const Setpoint& s) {
  if (const Outcome f = check_following(); f.is_failed()) return f;
  goal_live_ = false;
  if (s.mode == ServoMode::none) {
    jaw_pending_ = false;  // a jaw goal goes only with the arm's motion
    // A move replaces our servo commands at the dVRK: a hold before it could reach the arm after
    // it (another topic) and cut it.
    if (request_.kind == Request::Kind::none) (void)send_safe();
    return send_request();
  }
  // A move or free given while servo commands run would pre-empt them, or be pre-empted: refused.
  if (request_.kind != Request::Kind::none) {
    ++summary_.moves_refused;
    request_ = {};
  }
  // The dVRK takes motion while busy (a servo command cancels a move, disturbs a homing): held
  // back here instead.
  if (summary_.arm.is_busy) {
    ++summary_.held_busy;
    return Outcome::done();
  }
  Status st = Status::ok;
  if (s.mode == ServoMode::jp) {
    JointState j;
    j.size = static_cast<decltype(j.size)>(arm_config_.joints.size());
    for (std::size_t i = 0; i < arm_config_.joints.size(); ++i) j.position[i] = s.joints[i];
    st = write_jp_(j);
  } else {
    st = s.mode == ServoMode::cf ? write_cf_(s.wrench) : write_cp_(s.pose);
  }
  if (st == Status::disconnected)
    return Outcome::failed(FaultCode::device_lost, "the arm's import is gone (its gateway stopped)", source);
  if (st != Status::ok) {
    ++summary_.not_sent;
    if (++not_sent_in_a_row_ >= max_not_sent)
      return Outcome::failed(FaultCode::device_error,
                             "the arm's import takes no commands (its queue stays full)", source);
    return Outcome::done();
  }
  not_sent_in_a_row_ = 0;
  if (s.mode == ServoMode::cp) {
    goal_sent_ = s.pose.position;
    goal_live_ = true;
  }
  ++summary_.commands;
  commanded_ = true;
  moved_ = false;  // a servo command pre-empts a move at the dVRK
  if (jaw_pending_ && write_jaw_.is_bound() && write_jaw_(jaw_goal_) == Status::ok) ++summary_.jaw_commands;
  jaw_pending_ = false;
  return Outcome::done();
}

Status DvrkArm::send_safe() noexcept {
  if (!commanded_) return Status::ok;  // nothing of ours to undo: the arm holds what it had
  Status s = Status::ok;
  switch (arm_config_.safe_command) {
    case SafeCommand::zero_wrench:
      s = write_cf_(Wrench{});
      break;
    case SafeCommand::hold:
      s = hold_();
      break;
    case SafeCommand::servo_cp_measured:
      s = write_cp_(measured().cp);
      break;
  }
  if (s == Status::ok) {
    commanded_ = false;
    ++summary_.safe_commands;
  }
  return s;  // not taken (a full queue): tried again in the next write(none)
}

void DvrkArm::enter_safe_state(SafeReason) {
  // A move may still be under way (the arm's busy can lag the command): the safe command stops it.
  if (moved_) commanded_ = true;
  moved_ = false;
  request_ = {};
  (void)send_safe();
  enable_sent_ = home_sent_ = false;
}

bool DvrkArm::accepts(ServoMode m) const noexcept {
  return m == (follows_poses(arm_config_.kind) ? ServoMode::cp : ServoMode::cf) ||
         (m == ServoMode::jp && arm_config_.servo_jp);
}

}  // namespace saw::drivers::dvrk
