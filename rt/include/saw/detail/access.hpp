// Access: the framework's way in to the setup-only members of the core's classes (internal).
#pragma once

#include <atomic>
#include <string>
#include <utility>

#include "saw/component.hpp"
#include "saw/detail/binding.hpp"
#include "saw/detail/cycle_hook.hpp"
#include "saw/detail/mailbox.hpp"
#include "saw/functions.hpp"
#include "saw/provided_interface.hpp"
#include "saw/required_interface.hpp"
#include "saw/task.hpp"

namespace saw::detail {

// These members are private so that the public headers show a component's author only what a
// component uses. The manager, tasks, proxies, the bridge and the gateway reach them here: one
// friend per class instead of one per user, and a grep for "Access::" finds every use. Not an
// API: it changes with the framework.
struct Access {
  // Component
  static void add_inbound(Component& c, Mailbox* m) { c.add_inbound(m); }
  static void add_cycle_hook(Component& c, CycleHook* h) { c.add_cycle_hook(h); }
  static void set_lifecycle(Component& c, Lifecycle l) noexcept { c.set_lifecycle(l); }
  static void cycle(Component& c, TimeNs time) noexcept { c.cycle(time); }
  static Mailbox* remote_events(Component& c) noexcept { return c.remote_events(); }

  // Task
  static void start_thread(Task& t, const std::atomic<TimeNs>& first_wakeup,
                           const std::atomic<bool>& running) {
    t.start_thread(first_wakeup, running);
  }
  static bool thread_ready(const Task& t) noexcept { return t.thread_ready(); }
  static void join(Task& t) { t.join(); }
  static void step(Task& t, TimeNs time) noexcept { t.step(time); }
  // As the periodic loop does when a wake-up finds the deadline policy breached (tests of what a
  // component does then, on the stepped clock, which is never late).
  static void deadline_breach(Task& t, const DeadlineBreach& b) noexcept { t.breach(b); }

  // Function objects and event handlers
  static void bind(FunctionBase& f, const FunctionBinding& b) noexcept { f.bind(b); }
  static void unbind(FunctionBase& f) noexcept { f.unbind(); }
  static void set_connected_to(RequiredInterface& r, std::string s) { r.set_connected_to(std::move(s)); }

  // Events
  static void add_observer(EventBase& e, Observer o) { e.add_observer(o); }
  static Status emit_described(EventBase& e, const void* arg) noexcept { return e.emit_described(arg); }

  // Interfaces rebuilt from a description (proxies, mirrors)
  static void add_command(ProvidedInterface& p, Command c) { p.add(std::move(c)); }
  static EventBase& add_event_remote(ProvidedInterface& p, std::string name, Signature s) {
    return p.add_event_remote(std::move(name), s);
  }
  static ForwardCall& forward(Command& c) noexcept { return c.forward_; }
  static const ForwardCall& forward(const Command& c) noexcept { return c.forward_; }
  static StampedRead& read_stamped(Command& c) noexcept { return c.read_stamped_; }
  static const StampedRead& read_stamped(const Command& c) noexcept { return c.read_stamped_; }
};

}  // namespace saw::detail
