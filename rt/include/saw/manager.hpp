// Manager: one per process; adds components, connects interfaces, starts and stops tasks.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "saw/component.hpp"
#include "saw/log.hpp"
#include "saw/rt_thread.hpp"
#include "saw/task.hpp"

namespace saw {

// Thrown by connect() and start() (and returned by check()): the message names components,
// interfaces, commands, types.
class ConnectError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Thrown by start(): a component's startup() failed. The components started before it were
// stopped again (cleanup(): a device through its safe state); nothing runs. what() is
// "component 'NAME': REASON".
class StartError : public std::runtime_error {
 public:
  StartError(std::string component, const std::string& reason)
      : std::runtime_error("component '" + component + "': " + reason), component_(std::move(component)) {}
  const std::string& component() const noexcept { return component_; }

 private:
  std::string component_;
};

// Finds components that live elsewhere (another process, another host) and returns a local
// proxy for them, or nullptr. connect() asks each resolver for a server it does not know.
class RemoteResolver {
 public:
  virtual ~RemoteResolver() = default;
  virtual std::unique_ptr<Component> resolve(std::string_view name) = 0;
};

enum class ManagerState : std::uint8_t { idle, running, stepping, stopped };

struct ManagerOptions {
  bool lock_memory = true;       // mlockall when any task is real-time
  bool hold_dma_latency = true;  // /dev/cpu_dma_latency = 0 while running
  bool drain_log = true;         // a non-RT thread prints the RT log to stderr
};

class Manager {
 public:
  explicit Manager(ManagerOptions options = {});
  ~Manager();
  Manager(const Manager&) = delete;
  Manager& operator=(const Manager&) = delete;

  // The manager does not own a component added by reference: it must outlive the manager's use.
  void add(Component& c);
  Component& add(std::unique_ptr<Component> c);
  Component* find(std::string_view name) const noexcept;
  void add_resolver(std::unique_ptr<RemoteResolver> r) { resolvers_.push_back(std::move(r)); }

  // Binds client.required to server.provided by name and type. Throws ConnectError naming
  // both components, both interfaces, the command and both types on any mismatch; a connect
  // that throws has bound nothing.
  void connect(std::string_view client, std::string_view required, std::string_view server,
               std::string_view provided);
  // Whether connect() with the same arguments would succeed now: nullopt if so, else the
  // ConnectError it would throw. Binds nothing. A server that only a resolver knows is resolved
  // and added, as connect() would add it: its interface is what is checked.
  std::optional<ConnectError> check(std::string_view client, std::string_view required,
                                    std::string_view server, std::string_view provided);

  // Real threads: every periodic task on its own SCHED_FIFO thread. Each component's startup()
  // runs first, in the order added; one that throws is a StartError (see there).
  void start();
  // Deterministic: all tasks in the calling thread on a simulated clock starting at `t0`.
  void start_stepped(TimeNs t0 = 0);
  // Stepped mode: runs every task due at the next instant, in period, then offset (phase),
  // then insertion order.
  TimeNs step();
  // Stepped mode: steps until the simulated clock passes `t`.
  void step_until(TimeNs t);
  TimeNs simulated_time() const noexcept { return sim_time_; }

  void stop();
  ManagerState state() const noexcept { return state_; }

  // What start() could not get (SCHED_FIFO, mlockall, cpu_dma_latency): empty if all.
  const std::vector<std::string>& rt_warnings() const noexcept { return rt_warnings_; }
  const std::vector<Component*>& components() const noexcept { return components_; }

 private:
  // connect() in steps: find both ends by name, check everything (throws, changes nothing),
  // then bind the client's functions to the server's commands and the server's events to the
  // client's handlers.
  struct Ends;
  Ends find_ends(std::string_view client, std::string_view required, std::string_view server,
                 std::string_view provided);
  void check_ends(const Ends& e) const;
  void bind_commands(const Ends& e);
  void bind_events(const Ends& e);
  Component& get(std::string_view name) const;
  void check_ready_to_start();
  void prepare_components();

  ManagerOptions options_;
  std::vector<Component*> components_;
  std::vector<std::unique_ptr<Component>> owned_;
  std::vector<std::unique_ptr<detail::Mailbox>> mailboxes_;
  std::vector<std::unique_ptr<RemoteResolver>> resolvers_;
  // Remote server → the one local client that uses its command and event rings.
  std::map<std::string, std::string, std::less<>> remote_users_;
  std::atomic<bool> running_{false};
  std::atomic<TimeNs> first_wakeup_{0};
  ManagerState state_ = ManagerState::idle;
  std::vector<std::string> rt_warnings_;
  std::optional<rt::DmaLatencyHold> dma_hold_;
  std::unique_ptr<LogDrain> log_drain_;
  // Stepped mode.
  struct Stepped {
    Task* task;
    TimeNs next;
  };
  std::vector<Stepped> stepped_;
  TimeNs sim_time_ = 0;
  TimeNs continuous_period_ = 0;  // how often continuous tasks run in stepped mode
};

}  // namespace saw
