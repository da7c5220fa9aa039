// RequiredInterface: the named set of functions and event handlers a component needs.
#pragma once

#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "saw/functions.hpp"

namespace saw {

class Component;

struct FunctionSlot {
  std::string name;
  FunctionBase* function;
  Need need;
  std::string hint;  // said when a server lacks it: what to connect (e.g. "put a passivity_port ...")
};

// Runs in the client's thread when the client is a task (queued), else in the emitter's.
struct EventHandler {
  std::string name;
  Signature signature;
  Need need;
  std::function<void(const void*)> handle;
  bool bound = false;  // set by connect()
};

class RequiredInterface {
 public:
  static constexpr std::size_t default_event_capacity = 64;

  RequiredInterface(Component& owner, std::string name) : owner_(owner), name_(std::move(name)) {}
  RequiredInterface(const RequiredInterface&) = delete;
  RequiredInterface& operator=(const RequiredInterface&) = delete;

  const std::string& name() const noexcept { return name_; }
  Component& owner() const noexcept { return owner_; }

  // The function object lives in the client (usually a member); it must outlive the manager's use.
  // `hint` is added to the connect error of a server without it.
  void add_function(std::string name, FunctionBase& function, Need need = Need::required,
                    std::string hint = {});

  template <class F>
  void add_event_handler_void(std::string name, F&& f, Need need = Need::required) {
    add_handler(
        {std::move(name), {CommandKind::void_event}, need, [f = std::forward<F>(f)](const void*) { f(); }});
  }
  template <Plain T, class F>
  void add_event_handler_write(std::string name, F&& f, Need need = Need::required) {
    add_handler({std::move(name),
                 {CommandKind::write_event, type_info_of<T>()},
                 need,
                 [f = std::forward<F>(f)](const void* a) {
                   // Copied, then checked: the bytes may sit in another process's memory. An
                   // event that is not a valid T (from a broken peer) is not delivered.
                   T v;
                   std::memcpy(static_cast<void*>(&v), a, sizeof v);
                   if (check_value(v)) f(v);
                 }});
  }

  // Slots in the mailbox that carries this interface's events from its server.
  void set_event_capacity(std::size_t n) { event_capacity_ = n; }
  std::size_t event_capacity() const noexcept { return event_capacity_; }

  const std::vector<FunctionSlot>& functions() const noexcept { return functions_; }
  const std::vector<std::unique_ptr<EventHandler>>& handlers() const noexcept { return handlers_; }

  // "server.provided" once connected, else empty.
  const std::string& connected_to() const noexcept { return connected_to_; }
  bool is_connected() const noexcept { return !connected_to_.empty(); }

  // True if any function or handler is required: such an interface must be connected to start.
  bool has_required_members() const noexcept;

 private:
  friend struct detail::Access;
  void set_connected_to(std::string s) { connected_to_ = std::move(s); }
  void add_handler(EventHandler h);
  void check_new_name(const std::string& name, bool handler) const;

  Component& owner_;
  std::string name_;
  std::vector<FunctionSlot> functions_;
  std::vector<std::unique_ptr<EventHandler>> handlers_;
  std::size_t event_capacity_ = default_event_capacity;
  std::string connected_to_;
};

}  // namespace saw
