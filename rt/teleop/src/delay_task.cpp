#include "saw/teleop/delay_task.hpp"

#include <limits>
#include <stdexcept>

namespace saw::teleop {
namespace {

TimeNs period_of(const TaskConfig& task) {
  if (task.period.count() <= 0) throw std::invalid_argument("DelayTask must be periodic");
  return task.period.count();
}

void check(const LinkConfig& link, const char* which) {
  constexpr TimeNs ten_s = 10'000'000'000;
  if (link.delay < 0 || link.delay > ten_s || link.jitter < 0 || link.jitter > ten_s)
    throw std::invalid_argument(std::string("DelayTask ") + which + ": delay and jitter must be 0..10 s");
  if (!(link.loss >= 0 && link.loss <= 0.5))
    throw std::invalid_argument(std::string("DelayTask ") + which + ": loss must be 0..0.5");
}

DelayConfig checked(DelayConfig c) {
  check(c.measured, "measured");
  check(c.commands, "commands");
  return c;
}

DelayConfig only_delay(double delay_seconds) {
  if (!(delay_seconds >= 0) || delay_seconds > 10)
    throw std::invalid_argument("DelayTask delay must be 0..10 s");
  DelayConfig c;
  c.measured.delay = static_cast<TimeNs>(delay_seconds * 1e9);
  return c;
}

}  // namespace

DelayTask::DelayTask(std::string name, TaskConfig task, double delay_seconds)
    : DelayTask(std::move(name), task, only_delay(delay_seconds)) {}

DelayTask::DelayTask(std::string name, TaskConfig task, DelayConfig config)
    : Task(std::move(name), task),
      delay_(checked(config).measured.delay),
      commands_direct_(config.commands.delay == 0 && config.commands.jitter == 0 &&
                       config.commands.loss == 0),
      command_hold_(config.command_hold > 0 ? config.command_hold
                                            : config.commands.jitter + 5 * period_of(task)),
      measured_(config.measured, period_of(task)),
      commands_(config.commands, period_of(task)) {
  namespace arm = crtk::arm;
  auto& p = provide(std::string(arm::interface_name));
  crtk::provide(p, arm::measured_cp, state_table(), &measured_cp_);
  crtk::provide(p, arm::measured_cv, state_table(), &measured_cv_);
  crtk::provide(p, delayed_arm::source_time, state_table(), &source_time_);
  crtk::provide(p, delayed_arm::delay, state_table(), &delay_);
  crtk::provide(p, arm::servo_cf, [this](const Wrench& w) { pass_command(w); });
  crtk::provide(p, port::energy, state_table(), &port_energy_);
  crtk::provide(p, port::remote_energy, [this](const double& e) { pass_energy(e); });
  crtk::provide(p, port::wave, state_table(), &port_wave_);
  crtk::provide(p, port::remote_wave, [this](const Vec3& w) { pass_wave(w); });
  // Configuration, not a signal: read through at once (undelayed), at start-up as at run time.
  p.add_command_read_value<double>(std::string(port::wave_impedance.name), [this](double& out) noexcept {
    return read_impedance_.is_bound() ? read_impedance_(out) : Status::disconnected;
  });
  // What this is and whom it carries, for a client that must name the component behind it (the
  // teleoperation names the port whose wave impedance it checks). Connected before any read.
  p.add_command_read_value<ComponentDescription>("description", [this](ComponentDescription& d) noexcept {
    d = ComponentDescription{};
    ComponentDescription::set(d.kind, "delay");
    ComponentDescription::set(d.roles[0], "source");
    ComponentDescription::set(d.servers[0], source_->connected_to());
    return Status::ok;
  });
  clutch_ = &crtk::provide(p, arm::clutch);
  operator_present_ = &crtk::provide(p, arm::operator_present);

  auto& r = require("source");
  source_ = &r;
  crtk::require(r, arm::measured_cp, read_cp_);
  crtk::require(r, arm::measured_cv, read_cv_);
  crtk::require(r, arm::servo_cf, write_cf_, Need::optional);
  crtk::require(r, port::energy, read_energy_, Need::optional);
  crtk::require(r, port::remote_energy, write_remote_energy_, Need::optional);
  crtk::require(r, port::wave, read_wave_, Need::optional);
  crtk::require(r, port::remote_wave, write_remote_wave_, Need::optional);
  crtk::require(r, port::wave_impedance, read_impedance_, Need::optional);
  crtk::require(
      r, arm::clutch, [this](const ButtonEvent& b) { (void)(*clutch_)(b); }, Need::optional);
  crtk::require(
      r, arm::operator_present, [this](const ButtonEvent& b) { (void)(*operator_present_)(b); },
      Need::optional);
}

void DelayTask::pass_command(const Wrench& w) noexcept {
  if (commands_direct_) return void(write_cf_(w));
  commands_.send(now(), DelayedCommand{w, remote_energy_, remote_wave_, has_remote_wave_, remote_wave_b_});
  has_remote_wave_ = false;  // each wave in one packet only
}

void DelayTask::pass_wave(const Vec3& w) noexcept {
  if (commands_direct_ && write_remote_wave_.is_bound()) return void(write_remote_wave_(w));
  remote_wave_ = w;
  has_remote_wave_ = true;
  remote_wave_b_ = source_impedance();
}

double DelayTask::source_impedance() const noexcept {
  double b = 0;
  if (!read_impedance_.is_bound()) return 0;  // no port's b to keep: a plain device
  return read_impedance_(b) == Status::ok ? b : std::numeric_limits<double>::quiet_NaN();
}

void DelayTask::pass_energy(double e) noexcept {
  // Checked by the port that uses it; here it only travels (with the next command).
  if (commands_direct_ && write_remote_energy_.is_bound())
    (void)write_remote_energy_(e);
  else
    remote_energy_ = e;
}

void DelayTask::run() {
  const TimeNs t = now();
  // A failed read sends nothing: a dead source shows as a source time that stops advancing,
  // never as fresh rows of this task.
  DelayedSample sample;
  RowStamp stamp;
  if (read_cp_(sample.cp, stamp) == Status::ok && read_cv_(sample.cv) == Status::ok) {
    sample.source_time = stamp.time;
    if (read_energy_.is_bound() && read_energy_(sample.port_energy) != Status::ok) sample.port_energy = -1;
    if (read_wave_.is_bound() && read_wave_(sample.port_wave) != Status::ok) sample.port_wave = {};
    measured_.send(t, sample);
    // Until the first sample arrives, the output is the source as it is now (nothing older exists).
    if (!have_output_) {
      measured_cp_ = sample.cp;
      measured_cv_ = sample.cv;
      source_time_ = sample.source_time;
      port_energy_ = sample.port_energy;
      port_wave_ = sample.port_wave;
    }
  }
  DelayedSample shown;
  if (measured_.receive(t, shown)) {
    measured_cp_ = shown.cp;
    measured_cv_ = shown.cv;
    source_time_ = shown.source_time;
    port_energy_ = shown.port_energy;
    port_wave_ = shown.port_wave;
    have_output_ = true;
  }
  if (commands_direct_) return;
  DelayedCommand c;
  if (commands_.receive(t, c)) {
    held_ = c;
    held_since_ = t;
    // A wave made for a port with one b is energy for that b only: a port that answers another
    // now (restarted while the wave travelled) is not given it. A read-command copy: RT-safe.
    if (c.has_wave && write_remote_wave_.is_bound()) {
      if (source_impedance() == c.port_b)
        (void)write_remote_wave_(c.remote_wave);
      else
        ++waves_dropped_;
    }
  }
  if (held_since_ < 0 || t - held_since_ > command_hold_) return;
  // The energy first: a port never applies a force before the energy that allows it.
  if (held_.remote_energy >= 0 && write_remote_energy_.is_bound())
    (void)write_remote_energy_(held_.remote_energy);
  (void)write_cf_(held_.wrench);
}

}  // namespace saw::teleop
