// Output<T>: a value a law sends by declaration — one write command of the master's or the slave's
// device (a passivity port's energy or wave) — and DeclaredOutputs, how the law sets them each cycle.
#pragma once

#include <cstddef>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "saw/functions.hpp"
#include "saw/required_interface.hpp"
#include "saw/teleop/law_input.hpp"
#include "saw/type_info.hpp"

namespace saw::teleop {

// Declared by a law (static constexpr auto declared_outputs = std::tuple{Output<double>{...}, ...}):
// the task requires `command` (a write command of type T) on that side's interface; a value the
// law sets in a cycle it steps is sent that cycle, before the devices' forces (a port never
// applies a force before the energy allowing it). Nothing is sent while the law holds. A value the
// device refuses counts in the task's refused sends. An optional output (required = false) the
// device does not offer is not sent, and not counted: the law's fallback is its own (the surgical
// law's move_cp: the operator aligns the master by hand). The task's own writes (servo_cf, ...)
// are not declared.
template <Plain T>
struct Output {
  LawSide side = LawSide::master;
  std::string_view command;
  bool required = true;
  std::string_view help = "";
  std::string_view interface = "";  // LawSide::other: the task's required interface
};

// One declared output as the law sets it this cycle (DeclaredOutputs is a view of these).
struct OutputValue {
  TypeInfo type{};
  void* value = nullptr;  // where the value is set: storage of the output's type
  bool set = false;       // set this cycle: to be sent
  bool offered = true;    // the device has the command (an optional output's may not)
};

// The law's declared outputs, in declaration order: in.outputs.set(0, energy) sends it this cycle.
// A test builds one over its own values and reads back what the law set.
class DeclaredOutputs {
 public:
  DeclaredOutputs() = default;
  DeclaredOutputs(OutputValue* values, std::size_t count) noexcept : values_(values), count_(count) {}
  std::size_t size() const noexcept { return count_; }
  // Sets the i-th output; false (nothing set) if there is none, T is not its type, or the device
  // does not offer it (an optional output: the law falls back on its own).
  template <Plain T>
  bool set(std::size_t i, const T& v) const noexcept {
    if (i >= count_ || !values_[i].offered || values_[i].type.name != type_info_of<T>().name) return false;
    std::memcpy(values_[i].value, &v, sizeof(T));
    values_[i].set = true;
    return true;
  }
  // The value set this cycle, or nullptr (not set, or not of type T).
  template <Plain T>
  const T* get(std::size_t i) const noexcept {
    if (i >= count_ || !values_[i].set || values_[i].type.name != type_info_of<T>().name) return nullptr;
    return static_cast<const T*>(values_[i].value);
  }

 private:
  OutputValue* values_ = nullptr;
  std::size_t count_ = 0;
};

namespace detail {

// One declared output as the task holds it: its function and the value the law set.
class OutputSlot : public DeclaredSlot {
 public:
  using DeclaredSlot::DeclaredSlot;
  virtual void* storage() noexcept = 0;
  // Sends the stored value: false when the device refuses it (an unbound one is never set).
  virtual bool write() noexcept = 0;
};

template <Plain T>
class TypedOutputSlot final : public OutputSlot {
 public:
  explicit TypedOutputSlot(const Output<T>& out)
      : OutputSlot(out.side, out.command, out.required, out.interface, out.help) {}
  FunctionBase& function() noexcept override { return fn_; }
  TypeInfo type() const noexcept override { return type_info_of<T>(); }
  void* storage() noexcept override { return &value_; }
  bool write() noexcept override { return fn_(value_) == Status::ok; }

 private:
  FunctionWrite<T> fn_;
  T value_{};
};

}  // namespace detail

// A law's declared outputs as the task runs them: required on their sides at setup, sent each
// cycle the law set them.
class OutputSet {
 public:
  OutputSet() = default;
  explicit OutputSet(std::vector<std::unique_ptr<detail::OutputSlot>> slots);
  // Setup: each output's function on its interface, as InputSet::require.
  void require(const std::function<RequiredInterface&(const std::string&)>& interface_of);
  // Start-up, once connected: which outputs the devices offer (an optional one's may not).
  void connected() noexcept;
  // The law's view for this cycle: nothing set yet.
  DeclaredOutputs prepare() noexcept;
  // (RT) Sends what the law set; returns how many the devices refused. An optional output the
  // device does not offer cannot be set (connected() says so): nothing is sent, nothing counted.
  std::uint64_t send() noexcept;
  std::size_t size() const noexcept { return slots_.size(); }

 private:
  std::vector<std::unique_ptr<detail::OutputSlot>> slots_;
  std::vector<OutputValue> values_;
};

}  // namespace saw::teleop
