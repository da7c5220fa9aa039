// Input<T>: a value a law asks the teleoperation task for by declaration — one read command of the
// master's or the slave's device — and DeclaredInputs, how the law finds its values each cycle.
// (Output<T>, the write commands a law sends to, are law_output.hpp.)
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
// A value is "fresh" in the cycle it was read with a new row of its side's sample (a passivity
// port's wave: one shown again, nothing arrived, is no wave).
template <Plain T>
struct Input {
  LawSide side = LawSide::master;
  std::string_view command;
  bool required = true;
  std::string_view help = "";
  std::string_view interface = "";  // LawSide::other: the task's required interface (e.g. "camera")
  // A check beyond check_value (finite, ranges): a value it refuses is no valid value (a port's
  // energy must be ≥ 0). A constant expression: a function, not a capture.
  bool (*valid)(const T&) noexcept = nullptr;
  // The name of one of the law's settings (a number) this value must equal to the last bit: the
  // two ends of a wave channel share b. The task compares them at start-up (waiting for a first
  // value, as for a device in another process: a failed start naming both), and every cycle: a
  // value that differs is FAULT (config_mismatch), and a cycle without a value holds the law.
  std::string_view agrees_with = "";
};

// One declared input's value as the law sees it this cycle (DeclaredInputs is a view of these).
struct DeclaredValue {
  TypeInfo type{};
  const void* value = nullptr;  // the last valid value, or nullptr before the first
  bool fresh = false;           // read valid this cycle, with a new row of its side
};

namespace detail {

// What an input and an output of a law have alike: a command on one of the task's interfaces.
class DeclaredSlot {
 public:
  DeclaredSlot(LawSide side, std::string_view command, bool required, std::string_view interface,
               std::string_view help)
      : side_(side), command_(command), interface_(interface), help_(help), required_(required) {}
  virtual ~DeclaredSlot() = default;
  DeclaredSlot(const DeclaredSlot&) = delete;
  DeclaredSlot& operator=(const DeclaredSlot&) = delete;

  LawSide side() const noexcept { return side_; }
  const std::string& command() const noexcept { return command_; }
  // The task's required interface it goes through: "master", "slave", or the declaration's own.
  std::string interface_name() const {
    return side_ == LawSide::master ? "master" : side_ == LawSide::slave ? "slave" : interface_;
  }
  bool required() const noexcept { return required_; }
  const std::string& help() const noexcept { return help_; }
  virtual FunctionBase& function() noexcept = 0;
  virtual TypeInfo type() const noexcept = 0;

 private:
  LawSide side_;
  std::string command_, interface_, help_;
  bool required_;
};

// Setup: each slot's function on its interface (required or optional, as declared), which
// `interface_of` finds or makes by name; `what` ("input", "output") for the connect error's hint.
void require_slots(const std::vector<DeclaredSlot*>& slots, std::string_view what,
                   const std::function<RequiredInterface&(const std::string&)>& interface_of);

// One declared input as the task holds it: its function, and the last valid value it read.
class InputSlot : public DeclaredSlot {
 public:
  InputSlot(LawSide side, std::string_view command, bool required, std::string_view interface,
            std::string_view help, std::string_view agrees_with)
      : DeclaredSlot(side, command, required, interface, help), agrees_with_(agrees_with) {}

  const std::string& agrees_with() const noexcept { return agrees_with_; }
  // Reads once; a value that is not valid (check_value, the input's own check) or not read keeps
  // the last good one. True when a valid value was read now.
  virtual bool read() noexcept = 0;
  // The last valid value, or nullptr before the first.
  virtual const void* value() const noexcept = 0;

  TimeNs last_good = -1;            // the task's time of the last valid read
  TimeNs last_row = -1;             // its side's row time at the last valid read (freshness)
  bool valid_now = false;           // this cycle's read gave a valid value
  Status last_status = Status::ok;  // of this cycle's read (invalid: read, but refused)

 private:
  std::string agrees_with_;
};

template <Plain T>
class TypedInputSlot final : public InputSlot {
 public:
  explicit TypedInputSlot(const Input<T>& in)
      : InputSlot(in.side, in.command, in.required, in.interface, in.help, in.agrees_with),
        valid_(in.valid) {}
  FunctionBase& function() noexcept override { return fn_; }
  TypeInfo type() const noexcept override { return type_info_of<T>(); }
  bool read() noexcept override {
    T v{};
    last_status = fn_.is_bound() ? fn_(v) : Status::disconnected;
    if (last_status != Status::ok) return false;
    if (!check_value(v) || (valid_ != nullptr && !valid_(v))) {
      last_status = Status::invalid;
      return false;
    }
    value_ = v;
    has_ = true;
    return true;
  }
  const void* value() const noexcept override { return has_ ? &value_ : nullptr; }

 private:
  FunctionRead<T> fn_;
  bool (*valid_)(const T&) noexcept;
  T value_{};
  bool has_ = false;
};

}  // namespace detail

class DeclaredInputs;

// A law's declared inputs as the task runs them: required on their sides at setup, read each cycle.
class InputSet {
 public:
  InputSet() = default;
  explicit InputSet(std::vector<std::unique_ptr<detail::InputSlot>> slots);
  // Setup: each input's function on its interface (required or optional, as declared), which
  // `interface_of` finds or makes by name ("master", "slave", or an input's own).
  void require(const std::function<RequiredInterface&(const std::string&)>& interface_of);
  // One cycle (RT): reads each; `master_row` and `slave_row` are the times of the sides' samples
  // this cycle (an input of a third interface is fresh whenever read). The first required input
  // without a valid value for longer than `stale` ns (since its last one, or since the first
  // read), or nullptr.
  const detail::InputSlot* read(TimeNs now, TimeNs stale, TimeNs master_row, TimeNs slave_row) noexcept;
  // How long `slot` has had no valid value at `now`.
  TimeNs age(const detail::InputSlot& slot, TimeNs now) const noexcept;
  DeclaredInputs view() const noexcept;
  std::size_t size() const noexcept { return slots_.size(); }
  const std::vector<std::unique_ptr<detail::InputSlot>>& slots() const noexcept { return slots_; }

 private:
  std::vector<std::unique_ptr<detail::InputSlot>> slots_;
  std::vector<DeclaredValue> values_;  // made with the slots: the law's view, no allocation after
  TimeNs first_read_ = -1;
};

// The declared inputs' values this cycle, in declaration order. A test builds one over its own
// values (a span of DeclaredValue).
class DeclaredInputs {
 public:
  DeclaredInputs() = default;
  DeclaredInputs(const DeclaredValue* values, std::size_t count) noexcept : values_(values), count_(count) {}
  std::size_t size() const noexcept { return count_; }
  // The i-th declared input's last valid value; nullptr before its first, or if T is not its type.
  template <Plain T>
  const T* get(std::size_t i) const noexcept {
    if (i >= count_ || values_[i].type.name != type_info_of<T>().name) return nullptr;
    return static_cast<const T*>(values_[i].value);
  }
  // Whether the i-th input was read valid this cycle with a new row of its side.
  bool fresh(std::size_t i) const noexcept { return i < count_ && values_[i].fresh; }

 private:
  const DeclaredValue* values_ = nullptr;
  std::size_t count_ = 0;
};

inline DeclaredInputs InputSet::view() const noexcept {
  return DeclaredInputs(values_.data(), values_.size());
}

}  // namespace saw::teleop
