#include <cmath>
#include <stdexcept>

#include "saw/component.hpp"
#include "saw/provided_interface.hpp"
#include "saw/required_interface.hpp"

namespace saw {
namespace {
void check_setup(const Component& owner, const std::string& iface, const std::string& what) {
  if (owner.lifecycle() != Lifecycle::constructed)
    throw std::logic_error("component '" + owner.name() + "' interface '" + iface + "': '" + what +
                           "' added after start");
}
}  // namespace

void ProvidedInterface::check_new_name(const std::string& name, bool event) const {
  check_setup(owner_, name_, name);
  if (event ? find_event(name) != nullptr : find_command(name) != nullptr)
    throw std::invalid_argument("component '" + owner_.name() + "' provided interface '" + name_ + "': '" +
                                name + "' added twice");
}

void ProvidedInterface::add(Command c) {
  check_new_name(c.name, false);
  commands_.push_back(std::make_unique<Command>(std::move(c)));
}

Command* ProvidedInterface::find_command(std::string_view name) const noexcept {
  for (const auto& c : commands_)
    if (c->name == name) return c.get();
  return nullptr;
}

void ProvidedInterface::limit(std::string_view name, double min, double max) {
  const std::string where = "component '" + owner_.name() + "' provided interface '" + name_ +
                            "': limits of '" + std::string(name) + "': ";
  check_setup(owner_, name_, std::string(name));
  Command* c = find_command(name);
  if (c == nullptr || c->signature.kind != CommandKind::write)
    throw std::invalid_argument(where + "no write command of that name");
  if (!std::isfinite(min) || !std::isfinite(max) || min > max)
    throw std::invalid_argument(where + "bounds must be finite with min <= max");
  c->limits = Limits{min, max};
}

EventBase* ProvidedInterface::find_event(std::string_view name) const noexcept {
  for (const auto& e : events_)
    if (e->name() == name) return e.get();
  return nullptr;
}

void RequiredInterface::check_new_name(const std::string& name, bool handler) const {
  check_setup(owner_, name_, name);
  const auto twice = [&] {
    throw std::invalid_argument("component '" + owner_.name() + "' required interface '" + name_ + "': '" +
                                name + "' added twice");
  };
  if (!handler)
    for (const auto& f : functions_)
      if (f.name == name) twice();
  if (handler)
    for (const auto& h : handlers_)
      if (h->name == name) twice();
}

void RequiredInterface::add_function(std::string name, FunctionBase& function, Need need, std::string hint) {
  check_new_name(name, false);
  functions_.push_back({std::move(name), &function, need, std::move(hint)});
}

void RequiredInterface::add_handler(EventHandler h) {
  check_new_name(h.name, true);
  handlers_.push_back(std::make_unique<EventHandler>(std::move(h)));
}

bool RequiredInterface::has_required_members() const noexcept {
  for (const auto& f : functions_)
    if (f.need == Need::required) return true;
  for (const auto& h : handlers_)
    if (h->need == Need::required) return true;
  return false;
}

}  // namespace saw
