// Component: a named unit with provided and required interfaces and a state table; no thread.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "saw/clock.hpp"
#include "saw/provided_interface.hpp"
#include "saw/required_interface.hpp"
#include "saw/state_table.hpp"

namespace saw {

namespace detail {
struct Access;
struct CycleHook;
}  // namespace detail

enum class Lifecycle : std::uint8_t { constructed, ready, active, finished };
std::string_view to_string(Lifecycle l);

// A component without a thread runs its commands in the caller's thread (as cisst's devices
// do), so they must be thread-safe; a Task queues them instead.
class Component {
 public:
  explicit Component(std::string name, std::size_t state_rows = StateTable::default_rows);
  virtual ~Component();
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;

  const std::string& name() const noexcept { return name_; }
  Lifecycle lifecycle() const noexcept { return lifecycle_.load(std::memory_order_acquire); }
  virtual bool has_thread() const noexcept { return false; }

  ProvidedInterface& provide(std::string name);
  RequiredInterface& require(std::string name);
  ProvidedInterface* provided(std::string_view name) const noexcept;
  RequiredInterface* required(std::string_view name) const noexcept;
  const std::vector<std::unique_ptr<ProvidedInterface>>& provided_interfaces() const noexcept {
    return provided_;
  }
  const std::vector<std::unique_ptr<RequiredInterface>>& required_interfaces() const noexcept {
    return required_;
  }

  StateTable& state_table() noexcept { return state_table_; }
  const StateTable& state_table() const noexcept { return state_table_; }

  // Time of the current cycle: real monotonic time, or the simulated clock in stepped mode.
  TimeNs now() const noexcept { return cycle_time_; }
  // From run(): the time this cycle's state row stands for, when it is not the cycle's — a
  // component that republishes measurements taken elsewhere stamps them with their arrival, so
  // that readers see them age when they stop coming. At most now().
  void stamp_row(TimeNs t) noexcept { row_time_ = t < cycle_time_ ? t : cycle_time_; }

  // Called by the manager outside any RT path.
  virtual void startup() {}
  virtual void cleanup() {}
  // One cycle of work, called by the component's task after its mailboxes are drained.
  virtual void run() {}

  // True for a proxy of a component in another process: a call may have to wait for it.
  virtual bool is_remote() const noexcept { return false; }

  // Components this one owns and that run beside it (a second task at another phase of the
  // period): the manager adds each, by reference, right after this one.
  virtual std::vector<Component*> companions() { return {}; }

 private:
  // The framework's own (tasks, the manager, proxies, the bridge), through detail::Access: a
  // component's author never calls these.
  friend struct detail::Access;
  // A proxy of a component in another process returns the mailbox its events arrive in.
  virtual detail::Mailbox* remote_events() noexcept { return nullptr; }
  // Setup: a mailbox this component drains at the start of every cycle.
  void add_inbound(detail::Mailbox* m);
  // Setup: code run at the end of every cycle, after the state-table row.
  void add_cycle_hook(detail::CycleHook* h) { hooks_.push_back(h); }
  void set_lifecycle(Lifecycle l) noexcept { lifecycle_.store(l, std::memory_order_release); }
  // One full cycle: mailboxes, run(), then the state-table row stamped `time`.
  void cycle(TimeNs time) noexcept;
  std::size_t process_mailboxes() noexcept;

  std::string name_;
  std::atomic<Lifecycle> lifecycle_{Lifecycle::constructed};
  std::vector<std::unique_ptr<ProvidedInterface>> provided_;
  std::vector<std::unique_ptr<RequiredInterface>> required_;
  StateTable state_table_;
  std::vector<detail::Mailbox*> inbound_;
  std::vector<detail::CycleHook*> hooks_;
  TimeNs cycle_time_ = 0;
  TimeNs row_time_ = 0;
};

}  // namespace saw
