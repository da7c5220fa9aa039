#include "saw/teleop/teleoperation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "saw/crtk_arm.hpp"
#include "saw/eigen.hpp"
#include "saw/log.hpp"
#include "saw/teleop/delay_task.hpp"

namespace saw::teleop {
namespace {

double seconds(const TaskConfig& t) { return static_cast<double>(t.period.count()) * 1e-9; }
// A delay a DelayTask reports beyond this is garbage (DelayTask refuses more than 10 s).
constexpr TimeNs max_delay = 10'000'000'000;

}  // namespace

Teleoperation::Teleoperation(std::string name, TaskConfig task, TeleopConfig config, const LawSpec& law)
    : Task(std::move(name), task),
      config_(config),
      law_(law.make(LawContext{seconds(task) > 0 ? seconds(task) : 0.001})),
      inputs_(law_->make_inputs()),
      outputs_(law_->make_outputs()) {
  auto& st = state_table();
  columns_.operating_state = st.add_column("operating_state", &state_);
  columns_.master_force = st.add_column("master_force", &master_force_);
  columns_.slave_force = st.add_column("slave_force", &slave_force_);
  columns_.master_error = st.add_column("master_error", &master_error_);
  columns_.slave_error = st.add_column("slave_error", &slave_error_);
  // The offset the law works with now; the setting `slave_offset` (if the law has one) is its target.
  columns_.slave_offset = st.add_column("current_offset", &slave_offset_value_);
  columns_.tracking_error = st.add_column("tracking_error", &tracking_error_);
  columns_.ratcheting = st.add_column("ratcheting", &ratcheting_);
  columns_.clutched = st.add_column("clutched", &clutched_);
  columns_.operator_present = st.add_column("operator_present", &operator_present_);
  columns_.fault = st.add_column("fault", &fault_);
  columns_.rejected_inputs = st.add_column("rejected_inputs", &rejected_inputs_);
  columns_.offset_errors = st.add_column("offset_errors", &offset_errors_);
  columns_.summary = st.add_column("summary", &summary_, ColumnUse::summary);
  columns_.description = st.add_column("description", &description_);

  auto& p = provide("teleop");
  crtk::provide(p, crtk::operating_state, columns_.operating_state);
  p.add_command_read("master_force", columns_.master_force);
  p.add_command_read("slave_force", columns_.slave_force);
  p.add_command_read("tracking_error", columns_.tracking_error);
  p.add_command_read("fault", columns_.fault);
  p.add_command_read("rejected_inputs", columns_.rejected_inputs);
  p.add_command_read("offset_errors", columns_.offset_errors);
  p.add_command_read("description", columns_.description);
  crtk::provide(p, crtk::state_command, [this](const StateCommand& c) { handle_state_command(c); });
  // Declared once by the law: set_<name> (bounded, refusals counted), and <name> read back.
  law_->provide_settings(p, st, rejected_);
  state_event_ = &crtk::provide(p, crtk::operating_state_event);
  fault_event_ = &p.add_event_write<FaultInfo>("fault");

  master_.side = FaultSide::master;
  slave_.side = FaultSide::slave;
  require_side(master_, "master");
  require_side(slave_, "slave");
  const auto interface_of = [this](const std::string& iface) -> RequiredInterface& {
    RequiredInterface* r = required(iface);
    return r != nullptr ? *r : require(iface);
  };
  inputs_.require(interface_of);
  outputs_.require(interface_of);
  crtk::require(
      *required("master"), crtk::arm::clutch, [this](const ButtonEvent& b) { clutched_ = b.pressed; },
      Need::optional);
  crtk::require(
      *required("master"), crtk::arm::operator_present,
      [this](const ButtonEvent& b) { operator_present_ = b.pressed; },
      config_.needs_operator ? Need::required : Need::optional);
  state_.state = config_.start_enabled ? OperatingStateValue::enabled : OperatingStateValue::disabled;

  ComponentDescription::set(description_.kind, "teleoperation");
  ComponentDescription::set(description_.variant, law_->name());
  ComponentDescription::set(description_.roles[0], "master");
  ComponentDescription::set(description_.roles[1], "slave");
  law_->describe(description_);
}

void Teleoperation::startup() {
  outputs_.connected();
  agreements_.prepare(inputs_, *law_, [this](const detail::InputSlot& in) { return source_words(in); });
  agreements_.check_at_start(std::max(1.0, config_.startup_timeout));
  // Connected by now: say which components play each role (a client need not guess by name).
  ComponentDescription::set(description_.servers[0], required("master")->connected_to());
  ComponentDescription::set(description_.servers[1], required("slave")->connected_to());
}

std::string Teleoperation::source_words(const detail::InputSlot& in) {
  const std::string iface = in.interface_name();
  RequiredInterface* r = required(iface);
  std::string who = "'" + (r != nullptr ? r->connected_to() : std::string()) + "'";
  // Named as the deployment names it: behind a delay task, the component it carries.
  Side* side = in.side() == LawSide::master ? &master_ : in.side() == LawSide::slave ? &slave_ : nullptr;
  ComponentDescription via{};
  if (side != nullptr && side->description.is_bound() && side->description(via) == Status::ok &&
      ComponentDescription::get(via.kind) == "delay" && !ComponentDescription::get(via.servers[0]).empty())
    who = "'" + std::string(ComponentDescription::get(via.servers[0])) + "', through " + who;
  return "its input " + in.command() + " from the " + iface + " (" + who + ")";
}

void Teleoperation::require_side(Side& s, const char* iface) {
  auto& r = require(iface);
  crtk::require(r, crtk::arm::measured_cp, s.cp);
  crtk::require(r, crtk::arm::measured_cv, s.cv);
  // A master may be read-only (a da Vinci master through the dVRK's research API): then the
  // operator feels no force, and the law still drives the slave.
  const bool follows_pose = s.side == FaultSide::slave && config_.slave_servo_cp;
  crtk::require(r, crtk::arm::servo_cf, s.cf,
                s.side == FaultSide::master || follows_pose ? Need::optional : Need::required);
  if (follows_pose) {
    crtk::require(r, crtk::arm::servo_cp, s.goal);
    r.add_function("watchdog_trips", s.trips, Need::optional);
  }
  // A master's gripper drives a slave's jaw (a law that gives slave_jaw).
  if (s.side == FaultSide::master) {
    crtk::require(r, crtk::arm::gripper_measured_js, s.grip, Need::optional);
  } else {
    crtk::require(r, crtk::arm::jaw_measured_js, s.grip, Need::optional);
    crtk::require(r, crtk::arm::jaw_servo_jp, s.jaw, Need::optional);
  }
  crtk::require(r, delayed_arm::source_time, s.source_time, Need::optional);
  crtk::require(r, delayed_arm::delay, s.delay, Need::optional);
  crtk::require(r, crtk::operating_state, s.state, Need::optional);
  r.add_function("description", s.description, Need::optional);
}

void Teleoperation::set_operating_state(OperatingStateValue s) noexcept {
  if (state_.state == s) return;
  state_.state = s;
  if (s != OperatingStateValue::enabled) state_.is_busy = false;  // waits only while enabled
  (void)(*state_event_)(state_);
}

void Teleoperation::raise_fault(FaultInfo why) noexcept {
  if (state_.state == OperatingStateValue::fault) return;
  why.time = now();
  why.since_start_ns = now() - start_time_;
  fault_ = why;
  explain(why);
  summary_.reason = fault_reason_.text;
  // Once per transition: one log line, the event (the gateway publishes it), then the state.
  // A deadline's line carries the window's words when it was a window ("107 of 1000 periods
  // missed"): one line per fault, whose first words say its kind, for people and log scanners.
  if (why.code == FaultCode::deadline_missed) {
    if (fault_reason_.size != 0)
      saw::log(LogLevel::error, name().c_str(), "FAULT: deadline missed: {} ({}), zero force both ways",
               fault_reason_.text.data(), fault_.source.data());
    else
      saw::log(LogLevel::error, name().c_str(), "FAULT: deadline missed: {} periods {}, zero force both ways",
               why.detail, fault_.source.data());
  } else {
    saw::log(LogLevel::error, name().c_str(), "FAULT: {} {}: {} ns old, last read {}",
             to_string(side_of(why)).data(), to_string(why.code).data(), why.age_ns,
             saw::to_string(why.last_read).data());
    // The words outlive the record: fault_reason_ changes only at the next fault, after an enable.
    if (fault_reason_.size != 0)
      saw::log(LogLevel::error, name().c_str(), "FAULT: {}", fault_reason_.text.data());
  }
  (void)(*fault_event_)(fault_);
  set_operating_state(OperatingStateValue::fault);
}

void Teleoperation::explain(const FaultInfo& why) noexcept {
  fault_reason_.clear();
  if (stale_input_ != nullptr) {
    const detail::InputSlot* in = std::exchange(stale_input_, nullptr);
    if (why.code == FaultCode::input_stale || why.code == FaultCode::input_missing) {
      if (const auto* a = agreements_.find(in)) {  // a value the law must agree with stopped coming
        (void)agreements_.describe(*a, fault_reason_);
        fault_reason_.append(" no longer answers (").append(saw::to_string(in->last_status)).append(")");
        return;
      }
      fault_reason_.append("the law's input ")
          .append(in->command())
          .append(" (declared) has had no valid value");
      return;
    }
  }
  if (why.code == FaultCode::deadline_missed) {
    // The FaultInfo says the periods and how late; a window's size only the words can.
    const auto& b = deadline_breach_;
    if (b.kind == DeadlineBreach::Kind::share)
      fault_reason_.append(static_cast<double>(b.missed))
          .append(" of ")
          .append(static_cast<double>(b.periods))
          .append(" periods missed");
    return;
  }
  if (why.code == FaultCode::config_mismatch && disagreed_ != nullptr) {
    const auto& a = *std::exchange(disagreed_, nullptr);
    const std::string_view unit = agreements_.describe(a, fault_reason_);
    fault_reason_.append(" is now ")
        .append(a.seen)
        .append(unit.empty() ? "" : " ")
        .append(unit)
        .append(": not the law's (was its server restarted with another?)");
  }
}

void Teleoperation::handle_state_command(StateCommand c) noexcept {
  switch (c) {
    case StateCommand::enable:
      // Already enabled: nothing to do (re-engaging would drop the force in one step).
      if (state_.state == OperatingStateValue::enabled) break;
      if (fault_.code != FaultCode::none) {
        fault_ = {};
        fault_reason_.clear();
        summary_.reason = fault_reason_.text;
        (void)(*fault_event_)(fault_);
      }
      engage_pending_ = true;
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
        engage_pending_ = true;
        set_operating_state(OperatingStateValue::enabled);
      }
      break;
    case StateCommand::home:
      break;  // nothing to home: the devices home themselves
  }
}

Status Teleoperation::read_time(Side& s, TimeNs row_time, TimeNs& time) noexcept {
  time = row_time;
  if (!s.source_time.is_bound() || !s.delay.is_bound()) return Status::ok;
  // Behind a DelayTask the row is the delay task's, stamped with its own cycle: the age that
  // matters is the source row's, less the delay it was meant to have.
  TimeNs source = 0, delay = 0;
  if (const Status st = s.source_time(source); st != Status::ok) return st;
  if (const Status st = s.delay(delay); st != Status::ok) return st;
  if (delay < 0 || delay > max_delay) return Status::invalid;
  time = std::min(source + delay, row_time);  // never fresher than the row that carries it
  return Status::ok;
}

bool Teleoperation::read_side(Side& s, FaultInfo& why) noexcept {
  Pose pose;
  Twist twist;
  RowStamp stamp;
  TimeNs time = 0;
  Status st = s.cp(pose, stamp);
  if (st == Status::ok) st = s.cv(twist);
  if (st == Status::ok) st = read_time(s, stamp.time, time);
  // A row from the future (more than a period ahead) would never go stale: refused.
  if (st == Status::ok && time > now() + config().period.count()) st = Status::invalid;
  if (st == Status::ok) {
    const Eigen::Vector3d position = to_eigen(pose.position), velocity = to_eigen(twist.linear),
                          angular = to_eigen(twist.angular);
    const Eigen::Quaterniond q = to_eigen(pose.orientation);
    // A quaternion off the unit sphere is no rotation: refused as a value that is not one.
    s.not_finite = !position.allFinite() || !velocity.allFinite() || !angular.allFinite() ||
                   !q.coeffs().allFinite() || !Pose::valid(pose);
    if (s.not_finite) {
      ++rejected_inputs_;
      st = Status::invalid;
    } else {
      s.last.position = position;
      s.orientation = pose.orientation;
      s.last.velocity = velocity;
      s.last.orientation = q;
      s.last.angular_velocity = angular;
      s.time = time;
      s.valid = true;
    }
  } else if (st == Status::invalid) {
    ++rejected_inputs_;
  }
  s.status = st;
  // A device in FAULT (a drive's emergency, a lost node) is not driven, however fresh its
  // position: the teleoperation faults too, and says which side.
  OperatingState device;
  if (s.state.is_bound() && s.state(device) == Status::ok) {
    if (device.state == OperatingStateValue::fault) {
      why = fault_on(s.side, FaultCode::device_fault);
      return false;
    }
    s.busy = device.is_busy;
    // A device only read (a read-only master) need not be enabled to be followed.
    s.enabled = device.state == OperatingStateValue::enabled || !s.cf.is_bound();
    s.paused = device.state == OperatingStateValue::paused && s.cf.is_bound();
  }
  // A read that fails (a writer pre-empted mid-row, a NaN, a peer gone) keeps the last good
  // value; only an input older than stale_timeout is a fault.
  const auto stale_ns = static_cast<TimeNs>(config_.stale_timeout * 1e9);
  const FaultCode failed = s.not_finite ? FaultCode::input_not_finite : FaultCode::input_stale;
  if (!s.valid) {
    why = fault_on(s.side, s.not_finite ? FaultCode::input_not_finite : FaultCode::input_missing, st);
    return false;
  }
  s.last.age = now() - s.time;
  if (s.last.age > stale_ns) {
    why = fault_on(s.side, failed, st, s.last.age);
    return false;
  }
  return true;
}

// A slave whose commands stopped (a stalled cycle here, a late row) holds where it is, not at
// the last goal, and judges the next goal's step from there: the law is engaged afresh from that
// pose, so that the stream resumes without a step the slave would refuse.
bool Teleoperation::slave_held() noexcept {
  std::uint64_t trips = 0;
  if (!slave_.trips.is_bound() || slave_.trips(trips) != Status::ok) return false;
  const bool held = slave_.trips_known && trips != slave_.trips_seen;
  slave_.trips_seen = trips;
  slave_.trips_known = true;
  return held;
}

// Optional, and no reason to fault: NaN when the device has none or its value is not one.
void Teleoperation::read_grip(Side& s) noexcept {
  JointState j;
  s.last.grip = s.grip.is_bound() && s.grip(j) == Status::ok && j.size >= 1 && std::isfinite(j.position[0])
                    ? j.position[0]
                    : std::numeric_limits<double>::quiet_NaN();
}

void Teleoperation::send_forces(const Eigen::Vector3d& f_master, const Eigen::Vector3d& f_slave,
                                const LawCommand* law) noexcept {
  Eigen::Vector3d fm = f_master, fs = f_slave;
  const bool finite = fm.allFinite() && fs.allFinite() && (law == nullptr || law->slave_goal.allFinite());
  if (!finite) {  // the last check before a device
    raise_fault(
        fault_on(fm.allFinite() ? FaultSide::slave : FaultSide::master, FaultCode::output_not_finite));
    fm.setZero();
    fs.setZero();
  }
  Wrench w;
  w.force = to_vec3(fm);
  const bool master_moving = law != nullptr && law->master_moving;
  if (master_.cf.is_bound() && !master_moving && master_.cf(w) != Status::ok) ++refused_sends_;
  master_force_ = to_vec3(fm);
  if (config_.slave_servo_cp) {
    // A slave that follows a pose gets only goals: while the law holds, nothing (its device's
    // command watchdog holds it).
    if (finite && law != nullptr) {
      const Quat q = law->orients_slave ? to_quat(law->slave_goal_orientation) : held_orientation_;
      // The device refuses a pose that is not one (not finite, off the unit sphere): counted.
      if (slave_.goal(Pose{to_vec3(law->slave_goal), q}) != Status::ok) ++refused_sends_;
      if (std::isfinite(law->slave_jaw) && slave_.jaw.is_bound()) {
        JointState j;
        j.size = 1;
        j.position[0] = law->slave_jaw;
        if (slave_.jaw(j) != Status::ok) ++refused_sends_;
      }
    }
    slave_force_ = {};
    return;
  }
  w.force = to_vec3(fs);
  if (slave_.cf(w) != Status::ok) ++refused_sends_;
  slave_force_ = to_vec3(fs);
}

void Teleoperation::note_refusals() noexcept {
  const std::uint64_t n = law_->refusals();
  if (n == offset_errors_) return;
  offset_errors_ = n;
  // Counted in the state table; logged at the 1st, 2nd, 4th, 8th... so a stuck input cannot flood.
  if ((n & (n - 1)) == 0)
    saw::log(LogLevel::warning, name().c_str(),
             "offset trajectory refused (Ruckig result {}), {} times so far", law_->last_refusal(), n);
}

void Teleoperation::account(const LawCommand& law) noexcept {
  master_error_ = to_vec3(law.master_error);
  slave_error_ = to_vec3(law.slave_error);
  slave_offset_value_ = to_vec3(law.slave_offset);
  tracking_error_ = law.slave_error.norm();
  tracking_sum_sq_ += tracking_error_ * tracking_error_;
  tracking_max_ = std::max(tracking_max_, tracking_error_);
  ++enabled_cycles_;
  // End-to-end: how old the master sample is when the force computed from it is sent (its row
  // time, from this process or another, to this cycle's time).
  master_age_ = now() - master_.time;
  master_age_sum_ += static_cast<double>(master_age_);
  master_age_max_ = std::max(master_age_max_, master_age_);
  if (2 * master_age_ >= config().period.count()) ++master_age_late_;
}

// Every cycle, after the declared inputs (in declaration order: a wave port's b after its wave, so
// a port restarted with another b, which shows it with its first wave or before, has none of its
// waves used). A read command's value is a copy (the bridge's mirror): RT-safe. An input without
// a value this cycle holds the law (unconfirmed_); for stale_timeout, it is stale as any input.
bool Teleoperation::check_agreements(FaultInfo& why) noexcept {
  const auto* a = agreements_.check();
  if (a == nullptr) return true;
  disagreed_ = a;
  why = fault_on(a->slot->side() == LawSide::slave ? FaultSide::slave : FaultSide::master,
                 FaultCode::config_mismatch);
  return false;
}

// The law's declared inputs: a required one without a valid value for stale_timeout is stale,
// as a device's sample would be (named in the FAULT's words).
bool Teleoperation::read_declared(FaultInfo& why) noexcept {
  const auto stale = static_cast<TimeNs>(config_.stale_timeout * 1e9);
  const detail::InputSlot* late = inputs_.read(now(), stale, master_.time, slave_.time);
  if (late == nullptr) return true;
  stale_input_ = late;
  const FaultSide side = late->side() == LawSide::master  ? FaultSide::master
                         : late->side() == LawSide::slave ? FaultSide::slave
                                                          : FaultSide::none;
  why = fault_on(side, late->last_good < 0 ? FaultCode::input_missing : FaultCode::input_stale,
                 late->last_status == Status::ok ? Status::no_data : late->last_status,
                 inputs_.age(*late, now()));
  return false;
}

void Teleoperation::on_input_failure(const FaultInfo& why) noexcept {
  // A stopped or silent device: zero force on both sides, and stay faulted until re-enabled.
  // At start-up, inputs may simply not be published yet: wait up to startup_timeout for them.
  const double grace = config_.startup_timeout > 0 ? config_.startup_timeout : config_.stale_timeout;
  const bool starting = !inputs_seen_ && now() - start_time_ <= static_cast<TimeNs>(grace * 1e9);
  // A port that answers with another configuration is no late input: FAULT at once, in any state
  // (re-enabling clears it; the next cycle finds it again if it still holds).
  if (why.code == FaultCode::config_mismatch || (state_.state == OperatingStateValue::enabled && !starting))
    raise_fault(why);
  send_forces(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
}

void Teleoperation::on_deadline_breach(const DeadlineBreach& b) noexcept {
  deadline_breached_ = true;
  deadline_breach_ = b;
}

void Teleoperation::run() {
  if (deadline_breached_) {
    deadline_breached_ = false;
    FaultInfo f;
    f.code = FaultCode::deadline_missed;
    f.detail = static_cast<std::uint32_t>(deadline_breach_.missed);
    f.age_ns = deadline_breach_.latency;
    f.set_source(deadline_breach_.kind == DeadlineBreach::Kind::in_a_row ? "in a row" : "in a window");
    if (start_time_ < 0) start_time_ = now();
    raise_fault(f);  // then the cycle below sends zero force both ways
  }
  cycle_body();
  refresh_summary();
}

void Teleoperation::refresh_summary() noexcept {
  summary_.state = state_.state;
  summary_.fault = fault_;
  summary_.tracking_rms = tracking_rms();
  summary_.tracking_max = tracking_max_;
  summary_.enabled_cycles = enabled_cycles_;
  summary_.rejected_commands = rejected_;
  summary_.refused_sends = refused_sends_;
  summary_.rejected_inputs = rejected_inputs_;
  summary_.offset_errors = law_->refusals();
  summary_.master_age_mean = master_age_mean();
  summary_.master_age_max = master_age_max_;
  summary_.master_age_late = master_age_late_;
}

bool Teleoperation::waiting_for_devices() noexcept {
  const bool waiting = state_.state == OperatingStateValue::enabled &&
                       !(master_.enabled && slave_.enabled && !master_.busy && !slave_.busy);
  if (!waiting) {
    waiting_since_ = -1;
  } else if (waiting_since_ < 0) {
    waiting_since_ = now();
  } else if (now() - waiting_since_ > static_cast<TimeNs>(config_.device_timeout * 1e9)) {
    // Busy (homing, enabling) and paused devices are on their way; a disabled one is not.
    const Side* idle = !slave_.enabled && !slave_.busy && !slave_.paused      ? &slave_
                       : !master_.enabled && !master_.busy && !master_.paused ? &master_
                                                                              : nullptr;
    if (idle != nullptr) raise_fault(fault_on(idle->side, FaultCode::device_disabled));
  }
  // A controller that cannot drive its devices says so: busy, not plainly enabled.
  const bool busy = waiting && state_.state == OperatingStateValue::enabled;
  if (state_.is_busy != busy) {
    state_.is_busy = busy;
    (void)(*state_event_)(state_);
  }
  return waiting;
}

void Teleoperation::cycle_body() noexcept {
  if (start_time_ < 0) start_time_ = now();
  FaultInfo why{};
  if (!read_side(master_, why) || !read_side(slave_, why) || !read_declared(why) || !check_agreements(why))
    return on_input_failure(why);
  inputs_seen_ = true;
  read_grip(master_);
  read_grip(slave_);
  LawInputs in{master_.last, slave_.last, seconds(config())};
  in.declared = inputs_.view();
  in.outputs = outputs_.prepare();
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const bool busy = waiting_for_devices();
  if (slave_held()) engage_pending_ = true;
  // An input that must agree with the law gave nothing this cycle (a wave port that did not say
  // its b): nothing is made from what is not known to agree, nor a force from its last one.
  const bool unconfirmed = agreements_.unconfirmed();
  const bool absent = config_.needs_operator && !operator_present_;
  if (state_.state != OperatingStateValue::enabled || clutched_ || absent || busy || unconfirmed) {
    // Forces off; the law holds, so that enabling or releasing the clutch cannot jump.
    law_->hold(in);
    // A device's first position after it was busy may jump (a homed Falcon's counts become
    // absolute in that very row): engage afresh on that cycle, from that position. So does a law
    // after an input it must agree with was silent (a wave channel).
    engage_pending_ = busy || unconfirmed;
    ratcheting_ = false;
    send_forces(zero, zero);
    return;
  }
  if (engage_pending_) {
    law_->reset(in);
    held_orientation_ = slave_.orientation;
    engage_pending_ = false;
  }
  const LawCommand law = law_->step(in);
  note_refusals();
  if (!law.finite) {
    raise_fault(fault_on(law.bad_side == FaultSide::none ? FaultSide::slave : law.bad_side,
                         FaultCode::output_not_finite));
    send_forces(zero, zero);
    return;
  }
  ratcheting_ = law.limiting;
  account(law);
  // The declared outputs before the force: a port never applies a force before the energy
  // allowing it.
  refused_sends_ += outputs_.send();
  send_forces(law.master_force, law.slave_force, &law);
}

}  // namespace saw::teleop
