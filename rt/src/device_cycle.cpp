// Device's cycle: RT code, no allocation, lock, block, stdio or throw; a driver's throw is caught
// here and becomes a FAULT with what it said.
#include <cstring>
#include <exception>

#include "saw/device.hpp"
#include "saw/log.hpp"

namespace saw {

void Device::safe(SafeReason why) noexcept {
  ++status_.safe_entries;
  (void)guarded([&] {
    enter_safe_state(why);
    return Outcome::done();
  });
}

void Device::set_state(OperatingStateValue s) noexcept {
  state_.state = s;
  (void)(*state_event_)(state_);
}

void Device::start_homing() noexcept {
  homing_ = true;
  home_start_ = -1;
  state_.is_busy = busy();
}

void Device::set_moving(bool moving) noexcept {
  if (moving_ == moving) return;
  moving_ = moving;
  if (state_.is_busy == busy()) return;
  state_.is_busy = busy();
  (void)(*state_event_)(state_);
}

void Device::lose_homing() noexcept {
  if (!state_.is_homed) return;
  state_.is_homed = false;
  (void)(*state_event_)(state_);
}

void Device::button(Button b, bool pressed) noexcept {
  const auto i = static_cast<std::size_t>(b);
  if (buttons_[i] == pressed) return;
  buttons_[i] = pressed;
  (void)(*(b == Button::clutch ? clutch_event_ : operator_event_))(ButtonEvent{pressed});
}

void Device::describe(const Outcome& why) noexcept {
  const TimeNs t = now();
  fault_ = {};
  fault_.code = why.code == FaultCode::none ? FaultCode::device_error : why.code;
  fault_.detail = why.detail;
  fault_.age_ns = why.age;
  fault_.time = t;
  fault_.since_start_ns = t0_ < 0 ? 0 : t - t0_;
  fault_.set_source(why.source);
  status_.reason = {};
  std::strncpy(status_.reason.data(), why.why, DeviceStatus::max_reason);
  status_.fault = fault_;
}

void Device::update_fault(const Outcome& why) noexcept {
  if (state_.state != OperatingStateValue::fault) return raise(why);
  describe(why);
  saw::log(LogLevel::error, name().c_str(), "FAULT, now known: {} {} ({}, detail {:x})", fault_.source.data(),
           why.why, to_string(fault_.code).data(), fault_.detail);
  (void)(*fault_event_)(fault_);
}

void Device::raise(const Outcome& why, FaultOrigin origin) noexcept {
  if (state_.state == OperatingStateValue::fault) return;  // the first cause stands
  describe(why);
  status_.origin = origin;
  ++status_.faults;
  enabling_ = homing_ = enable_requested_ = moving_ = false;
  state_.is_busy = busy();
  command_ = {};
  watchdog_.disarm();
  safe(SafeReason::fault);
  if (fault_.code == FaultCode::deadline_missed)
    saw::log(LogLevel::error, name().c_str(), "FAULT ({}): deadline missed: {} periods {}",
             to_string(config_.safe_state).data(), fault_.detail, fault_.source.data());
  else
    saw::log(LogLevel::error, name().c_str(), "FAULT ({}): {} {} ({}, detail {:x})",
             to_string(config_.safe_state).data(), fault_.source.data(), why.why,
             to_string(fault_.code).data(), fault_.detail);
  (void)(*fault_event_)(fault_);
  set_state(OperatingStateValue::fault);
}

void Device::begin_enable(TimeNs t) noexcept {
  enable_requested_ = false;
  if (state_.state == OperatingStateValue::enabled && !enabling_) return;
  if (fault_.code != FaultCode::none) {
    fault_ = {};  // cleared: said once, with code none
    (void)(*fault_event_)(fault_);
  }
  enabling_ = true;
  enable_start_ = t;
  command_ = {};
  has_jp_ = has_cp_ = false;
  watchdog_.disarm();
  state_.is_busy = busy();                       // DISABLED and busy until the hardware says it is powered
  state_.state = OperatingStateValue::disabled;  // said by step_enable(), unless done at once
}

void Device::step_enable(TimeNs t) noexcept {
  const Outcome o = guarded([&] { return enable(); });
  if (o.is_failed()) return raise(o);
  if (o.is_done()) {
    enabling_ = false;
    state_.is_busy = busy();
    return set_state(OperatingStateValue::enabled);
  }
  if (t == enable_start_) (void)(*state_event_)(state_);  // DISABLED, busy: under way
  if (t - enable_start_ > config_.enable_timeout)
    raise(Outcome::failed(FaultCode::device_error, "enable timed out", o.source, o.detail),
          FaultOrigin::enable_timeout);
}

void Device::step_home(TimeNs t) noexcept {
  if (home_start_ < 0) home_start_ = t;
  const Outcome o = guarded([&] { return home(); });
  if (o.is_failed()) return raise(o);
  if (o.is_done()) {
    homing_ = false;
    state_.is_homed = true;
    state_.is_busy = busy();
    (void)(*state_event_)(state_);
    return;
  }
  if (config_.home_timeout > 0 && t - home_start_ > config_.home_timeout)
    raise(Outcome::failed(FaultCode::limit_exceeded, "homing timed out", "homing"),
          FaultOrigin::home_timeout);
}

void Device::watch_commands(TimeNs t) noexcept {
  if (!watchdog_.expired(t)) return;
  command_ = {};
  // The hardware now holds where it is (or is unpowered), not at the last command: the next
  // command's step is judged from the measured pose and joints, so that a stream resumed after a
  // pause (a clutch released) is not refused for its distance from a goal the arm never reached.
  has_jp_ = has_cp_ = false;
  saw::log(LogLevel::warning, name().c_str(), "no servo command for {} ns: {}", t - watchdog_.last_command(),
           to_string(config_.safe_state).data());
  if (config_.fault_on_command_timeout && following()) {
    raise(Outcome::failed(FaultCode::input_stale, "no servo command within command_timeout", "commands", 0,
                          t - watchdog_.last_command()),
          FaultOrigin::command_timeout);
  }
}

void Device::publish() noexcept {
  status_.state = state_.state;
  status_.watchdog_trips = watchdog_.trips();
}

void Device::on_deadline_breach(const DeadlineBreach& b) noexcept {
  deadline_breached_ = true;
  deadline_breach_ = b;
}

void Device::run() {
  const TimeNs t = now();
  if (t0_ < 0) t0_ = t;
  if (deadline_breached_) {
    deadline_breached_ = false;
    const auto& b = deadline_breach_;
    const bool row = b.kind == DeadlineBreach::Kind::in_a_row;
    raise(Outcome::failed(FaultCode::deadline_missed, "its task missed its deadline",
                          row ? "in a row" : "in a window", static_cast<std::uint32_t>(b.missed), b.latency),
          FaultOrigin::deadline_missed);
  }
  // An enable clears a fault first: a cause still present (read() sees it) faults again at once.
  if (enable_requested_) begin_enable(t);
  const Outcome in = guarded([&] { return read(); });
  if (in.is_failed()) raise(in);
  if (enabling_) step_enable(t);
  if (homing_) step_home(t);
  watch_commands(t);
  // Only a checked, fresh command of an enabled device reaches the hardware.
  static constexpr Setpoint none{};
  const Setpoint& sent = following() ? command_ : none;
  status_.safe_output = sent.mode == ServoMode::none;
  const Outcome o = guarded([&] { return write(sent); });
  if (o.is_failed()) raise(o);
  publish();
}

}  // namespace saw
