// Input<T>: a value a law asks the teleoperation task for by declaration — one read command of the
// master's or the slave's device — and DeclaredInputs, how the law finds its values each cycle.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "saw/clock.hpp"
#include "saw/functions.hpp"
#include "saw/required_interface.hpp"
#include "saw/type_info.hpp"
#include "saw/value_check.hpp"

namespace saw::teleop {

// Whose read command: the master's or the slave's device, or a third one (an endoscope arm) the
// task requires by the interface name the input gives, connected or not as the deployment says.
enum class LawSide : std::uint8_t { master, slave, other };

// Declared by a law (static constexpr auto declared_inputs = std::tuple{Input<Wrench>{...}, ...}):
// the task requires `command` (a read command of type T) on that side's interface, reads it every
// cycle it reads the devices, and hands the law its last valid value. A required input that has
// had no valid value for the task's stale_timeout is the task's FAULT, as a stale device is; an
// optional one may stay unconnected. The task's own reads (measured_cp, ...) are not declared.
template <Plain T>
struct Input {
  LawSide side = LawSide::master;
  std::string_view command;
  bool required = true;
  std::string_view help = "";
  std::string_view interface = "";  // LawSide::other: the task's required interface (e.g. "camera")
};

namespace detail {

// One declared input as the task holds it: its function, and the last valid value it read.
class InputSlot {
 public:
  InputSlot(LawSide side, std::string_view command, bool required, std::string_view interface)
      : side_(side), command_(command), interface_(interface), required_(required) {}
  virtual ~InputSlot() = default;
  InputSlot(const InputSlot&) = delete;
  InputSlot& operator=(const InputSlot&) = delete;

  LawSide side() const noexcept { return side_; }
  const std::string& command() const noexcept { return command_; }
  // The task's required interface it is read through: "master", "slave", or the input's own.
  std::string interface_name() const {
    return side_ == LawSide::master ? "master" : side_ == LawSide::slave ? "slave" : interface_;
  }
  bool required() const noexcept { return required_; }
  virtual FunctionBase& function() noexcept = 0;
  virtual TypeInfo type() const noexcept = 0;
  // Reads once; a value that is not valid (check_value) or not read keeps the last good one.
  // True when a valid value was read now.
  virtual bool read() noexcept = 0;
  // The last valid value, or nullptr before the first.
  virtual const void* value() const noexcept = 0;

  TimeNs last_good = -1;  // the task's time of the last valid read

 private:
  LawSide side_;
  std::string command_, interface_;
  bool required_;
};

template <Plain T>
class TypedInputSlot final : public InputSlot {
 public:
  explicit TypedInputSlot(const Input<T>& in) : InputSlot(in.side, in.command, in.required, in.interface) {}
  FunctionBase& function() noexcept override { return fn_; }
  TypeInfo type() const noexcept override { return type_info_of<T>(); }
  bool read() noexcept override {
    T v{};
    if (!fn_.is_bound() || fn_(v) != Status::ok || !check_value(v)) return false;
    value_ = v;
    has_ = true;
    return true;
  }
  const void* value() const noexcept override { return has_ ? &value_ : nullptr; }

 private:
  FunctionRead<T> fn_;
  T value_{};
  bool has_ = false;
};

}  // namespace detail

class DeclaredInputs;

// A law's declared inputs as the task runs them: required on their sides at setup, read each cycle.
class InputSet {
 public:
  InputSet() = default;
  explicit InputSet(std::vector<std::unique_ptr<detail::InputSlot>> slots) : slots_(std::move(slots)) {}
  // Setup: each input's function on its interface (required or optional, as declared), which
  // `interface_of` finds or makes by name ("master", "slave", or an input's own).
  void require(const std::function<RequiredInterface&(const std::string&)>& interface_of);
  // One cycle (RT): reads each. The first required input without a valid value for longer than
  // `stale` ns (since its last one, or since the first read), or nullptr.
  const detail::InputSlot* read(TimeNs now, TimeNs stale) noexcept;
  // How long `slot` has had no valid value at `now`.
  TimeNs age(const detail::InputSlot& slot, TimeNs now) const noexcept;
  DeclaredInputs view() const noexcept;
  std::size_t size() const noexcept { return slots_.size(); }

 private:
  std::vector<std::unique_ptr<detail::InputSlot>> slots_;
  TimeNs first_read_ = -1;
};

// The declared inputs' values this cycle, in declaration order.
class DeclaredInputs {
 public:
  DeclaredInputs() = default;
  explicit DeclaredInputs(const std::vector<std::unique_ptr<detail::InputSlot>>& slots) noexcept
      : slots_(slots.data()), count_(slots.size()) {}
  std::size_t size() const noexcept { return count_; }
  // The i-th declared input's last valid value; nullptr before its first, or if T is not its type.
  template <Plain T>
  const T* get(std::size_t i) const noexcept {
    if (i >= count_ || slots_[i]->type().name != type_info_of<T>().name) return nullptr;
    return static_cast<const T*>(slots_[i]->value());
  }

 private:
  const std::unique_ptr<detail::InputSlot>* slots_ = nullptr;
  std::size_t count_ = 0;
};

inline DeclaredInputs InputSet::view() const noexcept { return DeclaredInputs(slots_); }

}  // namespace saw::teleop
