#include "saw/component.hpp"

#include <stdexcept>

#include "saw/detail/cycle_hook.hpp"

namespace saw {

std::string_view to_string(Lifecycle l) {
  switch (l) {
    case Lifecycle::constructed:
      return "constructed";
    case Lifecycle::ready:
      return "ready";
    case Lifecycle::active:
      return "active";
    case Lifecycle::finished:
      return "finished";
  }
  return "?";
}

Component::Component(std::string name, std::size_t state_rows)
    : name_(std::move(name)), state_table_(state_rows) {
  if (name_.empty()) throw std::invalid_argument("component name must not be empty");
}

Component::~Component() = default;

ProvidedInterface& Component::provide(std::string name) {
  if (lifecycle() != Lifecycle::constructed)
    throw std::logic_error("component '" + name_ + "': provided interface '" + name + "' added after start");
  if (provided(name) != nullptr)
    throw std::invalid_argument("component '" + name_ + "': provided interface '" + name + "' added twice");
  provided_.push_back(std::make_unique<ProvidedInterface>(*this, std::move(name)));
  return *provided_.back();
}

RequiredInterface& Component::require(std::string name) {
  if (lifecycle() != Lifecycle::constructed)
    throw std::logic_error("component '" + name_ + "': required interface '" + name + "' added after start");
  if (required(name) != nullptr)
    throw std::invalid_argument("component '" + name_ + "': required interface '" + name + "' added twice");
  required_.push_back(std::make_unique<RequiredInterface>(*this, std::move(name)));
  return *required_.back();
}

ProvidedInterface* Component::provided(std::string_view name) const noexcept {
  for (const auto& p : provided_)
    if (p->name() == name) return p.get();
  return nullptr;
}

RequiredInterface* Component::required(std::string_view name) const noexcept {
  for (const auto& r : required_)
    if (r->name() == name) return r.get();
  return nullptr;
}

void Component::add_inbound(detail::Mailbox* m) {
  m->set_consumer_attached();
  inbound_.push_back(m);
}

std::size_t Component::process_mailboxes() noexcept {
  std::size_t n = 0;
  for (detail::Mailbox* m : inbound_) n += m->drain();
  return n;
}

void Component::cycle(TimeNs time) noexcept {
  cycle_time_ = time;
  row_time_ = time;
  process_mailboxes();
  run();
  state_table_.advance(row_time_);
  for (detail::CycleHook* h : hooks_) h->after_cycle(*this, row_time_);
}

}  // namespace saw
