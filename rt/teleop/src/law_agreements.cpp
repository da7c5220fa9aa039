#include "saw/teleop/detail/law_agreements.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/law_setting.hpp"

namespace saw::teleop::detail {

void LawAgreements::prepare(const InputSet& inputs, const LawModel& law,
                            const std::function<std::string(const InputSlot&)>& source_words) {
  law_ = &law;
  for (const auto& slot : inputs.slots()) {
    if (slot->agrees_with().empty()) continue;
    std::string_view unit;
    const double* value = law.setting_address(slot->agrees_with(), unit);
    if (slot->type().name != type_info_of<double>().name || value == nullptr)
      throw std::invalid_argument("law '" + std::string(law.name()) + "': its input " + slot->command() +
                                  " agrees with '" + slot->agrees_with() +
                                  "', which is no number setting of it");
    agreements_.push_back({slot.get(), slot->agrees_with(), value, unit, source_words(*slot)});
  }
}

void LawAgreements::check_at_start(double grace) const {
  for (const Agreement& a : agreements_) {
    const double want = *a.value;
    const std::string u = a.unit.empty() ? "" : " " + std::string(a.unit);
    const std::string said = "law '" + std::string(law_->name()) + "' has " + a.setting + " " +
                             setting_number(want) + u + ", but " + a.source;
    // A server in another process may not have published its first row yet: wait for it, as the
    // task waits for its inputs. Not the RT path.
    InputSlot& slot = *a.slot;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace);
    while (!slot.read() && slot.last_status == Status::no_data && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto* got = static_cast<const double*>(slot.value());
    if (got == nullptr || slot.last_status != Status::ok)
      throw std::runtime_error(said + " gives none (" + std::string(saw::to_string(slot.last_status)) +
                               "): " + slot.help());
    // Equal to the last bit: both are the deployment's numbers, carried as float64.
    if (*got != want) {
      std::string shown = setting_number(*got);
      if (shown == setting_number(want)) {  // they differ past %g's digits: say by how much
        char b[48];
        std::snprintf(b, sizeof b, "%.17g (%+.3g)", *got, *got - want);
        shown = b;
      }
      throw std::runtime_error(said + " is " + shown + u + ": " + slot.help());
    }
  }
}

LawAgreements::Agreement* LawAgreements::check() noexcept {
  unconfirmed_ = false;
  for (Agreement& a : agreements_) {
    if (!a.slot->valid_now) {
      unconfirmed_ = true;
      continue;
    }
    const double seen = *static_cast<const double*>(a.slot->value());
    if (seen != *a.value) {  // to the last bit, as at start-up
      a.seen = seen;
      return &a;
    }
  }
  return nullptr;
}

const LawAgreements::Agreement* LawAgreements::find(const InputSlot* slot) const noexcept {
  for (const Agreement& a : agreements_)
    if (a.slot == slot) return &a;
  return nullptr;
}

std::string_view LawAgreements::describe(const Agreement& a, FaultText& text) const noexcept {
  const std::string_view unit = a.unit;
  const double want = *a.value;
  text.append("law '")
      .append(law_->name())
      .append("' has ")
      .append(a.setting)
      .append(" ")
      .append(want)
      .append(unit.empty() ? "" : " ")
      .append(unit)
      .append(", but ")
      .append(a.source);
  return unit;
}

}  // namespace saw::teleop::detail
