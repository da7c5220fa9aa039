#include "saw/teleop/law_input.hpp"

#include <stdexcept>

namespace saw::teleop {

void InputSet::require(const std::function<RequiredInterface&(const std::string&)>& interface_of) {
  for (auto& s : slots_) {
    if (s->side() == LawSide::other && s->interface_name().empty())
      throw std::invalid_argument("the law's input " + s->command() +
                                  " names no interface (Input::interface)");
    interface_of(s->interface_name())
        .add_function(s->command(), s->function(), s->required() ? Need::required : Need::optional);
  }
}

const detail::InputSlot* InputSet::read(TimeNs now, TimeNs stale) noexcept {
  if (first_read_ < 0) first_read_ = now;
  const detail::InputSlot* late = nullptr;
  for (auto& s : slots_) {
    if (s->read()) s->last_good = now;
    if (late == nullptr && s->required() && age(*s, now) > stale) late = s.get();
  }
  return late;
}

TimeNs InputSet::age(const detail::InputSlot& slot, TimeNs now) const noexcept {
  return now - (slot.last_good >= 0 ? slot.last_good : first_read_);
}

}  // namespace saw::teleop
