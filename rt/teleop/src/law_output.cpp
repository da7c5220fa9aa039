#include "saw/teleop/law_output.hpp"

namespace saw::teleop {

OutputSet::OutputSet(std::vector<std::unique_ptr<detail::OutputSlot>> slots) : slots_(std::move(slots)) {
  values_.reserve(slots_.size());
  for (auto& s : slots_) values_.push_back({s->type(), s->storage(), false});
}

void OutputSet::require(const std::function<RequiredInterface&(const std::string&)>& interface_of) {
  std::vector<detail::DeclaredSlot*> slots;
  for (auto& s : slots_) slots.push_back(s.get());
  detail::require_slots(slots, "output", interface_of);
}

void OutputSet::connected() noexcept {
  for (std::size_t i = 0; i < values_.size(); ++i) values_[i].offered = slots_[i]->function().is_bound();
}

DeclaredOutputs OutputSet::prepare() noexcept {
  for (OutputValue& v : values_) v.set = false;
  return DeclaredOutputs(values_.data(), values_.size());
}

std::uint64_t OutputSet::send() noexcept {
  std::uint64_t refused = 0;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (!values_[i].set) continue;
    values_[i].set = false;
    if (!slots_[i]->write()) ++refused;
  }
  return refused;
}

}  // namespace saw::teleop
