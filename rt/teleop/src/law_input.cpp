#include "saw/teleop/law_input.hpp"

#include <stdexcept>

namespace saw::teleop {

InputSet::InputSet(std::vector<std::unique_ptr<detail::InputSlot>> slots) : slots_(std::move(slots)) {
  values_.reserve(slots_.size());
  for (auto& s : slots_) values_.push_back({s->type(), nullptr, false});
}

void detail::require_slots(const std::vector<DeclaredSlot*>& slots, std::string_view what,
                           const std::function<RequiredInterface&(const std::string&)>& interface_of) {
  for (DeclaredSlot* s : slots) {
    if (s->side() == LawSide::other && s->interface_name().empty())
      throw std::invalid_argument("the law's " + std::string(what) + " " + s->command() +
                                  " names no interface (its declaration's `interface`)");
    std::string hint = "the law's " + std::string(what);
    if (!s->help().empty()) hint += ": " + s->help();
    interface_of(s->interface_name())
        .add_function(s->command(), s->function(), s->required() ? Need::required : Need::optional,
                      std::move(hint));
  }
}

void InputSet::require(const std::function<RequiredInterface&(const std::string&)>& interface_of) {
  std::vector<detail::DeclaredSlot*> slots;
  for (auto& s : slots_) slots.push_back(s.get());
  detail::require_slots(slots, "input", interface_of);
}

const detail::InputSlot* InputSet::read(TimeNs now, TimeNs stale, TimeNs master_row,
                                        TimeNs slave_row) noexcept {
  if (first_read_ < 0) first_read_ = now;
  const detail::InputSlot* late = nullptr;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    detail::InputSlot& s = *slots_[i];
    const TimeNs row = s.side() == LawSide::master  ? master_row
                       : s.side() == LawSide::slave ? slave_row
                                                    : now;
    bool fresh = false;
    s.valid_now = s.read();
    if (s.valid_now) {
      s.last_good = now;
      fresh = row != s.last_row;
      s.last_row = row;
    }
    values_[i].value = s.value();
    values_[i].fresh = fresh;
    if (late == nullptr && s.required() && age(s, now) > stale) late = &s;
  }
  return late;
}

TimeNs InputSet::age(const detail::InputSlot& slot, TimeNs now) const noexcept {
  return now - (slot.last_good >= 0 ? slot.last_good : first_read_);
}

}  // namespace saw::teleop
