// LawAgreements: the declared inputs that must equal a setting of the law (Input::agrees_with),
// checked at start-up and every cycle — for the teleoperation task, not the API.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "saw/teleop/fault_info.hpp"
#include "saw/teleop/law_input.hpp"

namespace saw::teleop {

class LawModel;

namespace detail {

class LawAgreements {
 public:
  struct Agreement {
    InputSlot* slot = nullptr;
    std::string setting;
    const double* value = nullptr;  // the law's setting, found once (law_registry.hpp)
    std::string_view unit;
    std::string source;  // "its input port_wave_impedance from the master ('port.arm', through 'link.arm')"
    double seen = 0;     // the value that disagreed
  };

  // Setup, once connected: each agreeing input of `inputs`, named by `source_words`. A law whose
  // input agrees with what is no number setting of it is refused (std::invalid_argument).
  void prepare(const InputSet& inputs, const LawModel& law,
               const std::function<std::string(const InputSlot&)>& source_words);
  // Start-up: each one's first value (waited for up to `grace` s while its server says no_data)
  // equals its setting, or std::runtime_error naming both in one line.
  void check_at_start(double grace) const;
  // (RT) After this cycle's read of the declared inputs: the first that disagrees (its `seen`
  // set), or nullptr. unconfirmed() then says whether any gave no value this cycle.
  Agreement* check() noexcept;
  bool unconfirmed() const noexcept { return unconfirmed_; }
  // The agreement of `slot`, or nullptr.
  const Agreement* find(const InputSlot* slot) const noexcept;
  // (RT) "law 'L' has impedance 3 N·s/m, but <source>" into `text`; returns the setting's unit.
  std::string_view describe(const Agreement& a, FaultText& text) const noexcept;

 private:
  const LawModel* law_ = nullptr;
  std::vector<Agreement> agreements_;
  bool unconfirmed_ = false;
};

}  // namespace detail
}  // namespace saw::teleop
