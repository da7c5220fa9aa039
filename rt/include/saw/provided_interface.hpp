// ProvidedInterface: the named set of commands and events a component offers to clients.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/command_kind.hpp"
#include "saw/detail/binding.hpp"
#include "saw/detail/mailbox.hpp"
#include "saw/state_table.hpp"

namespace saw {

class Component;
namespace detail {
struct Access;
}

// One provided command. void/write commands are executed by `execute` in the server's
// thread; read and qualified-read commands are run by `read` in the caller's thread.
struct Command {
  std::string name;
  Signature signature;
  std::function<void(const void* arg)> execute;            // void, write
  std::function<Status(const void* arg, void* out)> read;  // read (arg unused), qualified read
  const StateTable* table = nullptr;                       // read commands backed by a column
  std::uint32_t column = 0;
  std::optional<Limits> limits;  // write commands (see Limits)

 private:
  friend struct detail::Access;
  // Only a proxy (a component in another process) sets these; see detail/binding.hpp.
  detail::ForwardCall forward_;
  detail::StampedRead read_stamped_;
};

// Events are emitted from the server's thread only (one producer per observer mailbox).
class EventBase {
 public:
  EventBase(std::string name, Signature signature) : name_(std::move(name)), signature_(signature) {}
  const std::string& name() const noexcept { return name_; }
  const Signature& signature() const noexcept { return signature_; }
  std::size_t observer_count() const noexcept { return observers_.size(); }
  // Deliveries refused because an observer's mailbox was full.
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 protected:
  Status emit_erased(const void* arg, std::size_t size) noexcept {
    Status result = Status::ok;
    for (const auto& o : observers_) {
      if (o.mailbox == nullptr) {
        o.direct(arg);
      } else if (o.mailbox->push(o.target, arg, size) != Status::ok) {
        dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        result = Status::queue_full;
      }
    }
    return result;
  }

 private:
  friend struct detail::Access;
  void add_observer(detail::Observer o) { observers_.push_back(o); }
  // For events built from a description (a proxy's): emits `arg`, signature().arg.size bytes.
  Status emit_described(const void* arg) noexcept { return emit_erased(arg, signature_.arg.size); }

  std::string name_;
  Signature signature_;
  std::vector<detail::Observer> observers_;
  std::atomic<std::uint64_t> dropped_{0};
};

class EventVoid : public EventBase {
 public:
  explicit EventVoid(std::string name) : EventBase(std::move(name), {CommandKind::void_event}) {}
  // Queues the event for every observer; queue_full if any observer's mailbox was full.
  Status operator()() noexcept { return emit_erased(nullptr, 0); }
};

template <Plain T>
class EventWrite : public EventBase {
 public:
  explicit EventWrite(std::string name)
      : EventBase(std::move(name), {CommandKind::write_event, type_info_of<T>()}) {}
  Status operator()(const T& value) noexcept { return emit_erased(&value, sizeof(T)); }
};

class ProvidedInterface {
 public:
  static constexpr std::size_t default_mailbox_capacity = 64;

  ProvidedInterface(Component& owner, std::string name) : owner_(owner), name_(std::move(name)) {}
  ProvidedInterface(const ProvidedInterface&) = delete;
  ProvidedInterface& operator=(const ProvidedInterface&) = delete;

  const std::string& name() const noexcept { return name_; }
  Component& owner() const noexcept { return owner_; }

  // Queued, executed in the server's thread at the start of its next cycle.
  template <class F>
  void add_command_void(std::string name, F&& f) {
    Command c;
    c.name = std::move(name);
    c.signature = {CommandKind::void_command};
    c.execute = [f = std::forward<F>(f)](const void*) { f(); };
    add(std::move(c));
  }
  template <Plain T, class F>
  void add_command_write(std::string name, F&& f) {
    Command c;
    c.name = std::move(name);
    c.signature = {CommandKind::write, type_info_of<T>()};
    c.execute = [f = std::forward<F>(f)](const void* a) { f(*static_cast<const T*>(a)); };
    add(std::move(c));
  }
  // Served from a state-table column, lock-free, in the caller's thread.
  template <Plain T>
  void add_command_read(std::string name, StateColumn<T> column) {
    Command c;
    c.name = std::move(name);
    c.signature = {CommandKind::read, type_info_of<T>()};
    c.table = column.table;
    c.column = column.index;
    c.read = [table = column.table, index = column.index](const void*, void* out) {
      return table->read_latest_erased(index, out, nullptr);
    };
    add(std::move(c));
  }
  // Served by `f`, `Status(T&) noexcept`, in the caller's thread (any thread, an RT one too: it
  // must not allocate, lock or block): for a value that needs no row, readable before the
  // server's first cycle (a setting fixed at construction). Another process reads it from the
  // bridge's mirror, which the exporter fills by calling `f` each cycle.
  template <Plain T, class F>
  void add_command_read_value(std::string name, F&& f) {
    Command c;
    c.name = std::move(name);
    c.signature = {CommandKind::read, type_info_of<T>()};
    c.read = [f = std::forward<F>(f)](const void*, void* out) { return f(*static_cast<T*>(out)); };
    add(std::move(c));
  }
  // A const, thread-safe function of the qualifier, run in the caller's thread.
  template <Plain Q, Plain R, class F>
  void add_command_qualified_read(std::string name, F&& f) {
    Command c;
    c.name = std::move(name);
    c.signature = {CommandKind::qualified_read, type_info_of<Q>(), type_info_of<R>()};
    c.read = [f = std::forward<F>(f)](const void* q, void* r) {
      f(*static_cast<const Q*>(q), *static_cast<R*>(r));
      return Status::ok;
    };
    add(std::move(c));
  }

  EventVoid& add_event_void(std::string name) { return add_event<EventVoid>(std::move(name)); }
  template <Plain T>
  EventWrite<T>& add_event_write(std::string name) {
    return add_event<EventWrite<T>>(std::move(name));
  }

  // Slots in each client's command mailbox.
  void set_mailbox_capacity(std::size_t n) { mailbox_capacity_ = n; }
  std::size_t mailbox_capacity() const noexcept { return mailbox_capacity_; }

  Command* find_command(std::string_view name) const noexcept;
  // Declares that every number in write command `name`'s argument lies in [min, max] (see
  // Limits). Throws std::invalid_argument for an unknown or non-write command or bad bounds.
  void limit(std::string_view name, double min, double max);
  EventBase* find_event(std::string_view name) const noexcept;
  const std::vector<std::unique_ptr<Command>>& commands() const noexcept { return commands_; }
  const std::vector<std::unique_ptr<EventBase>>& events() const noexcept { return events_; }

 private:
  friend struct detail::Access;
  // For proxies, which rebuild an interface from a description: a command as it is, and an
  // event of a given signature that something else emits.
  EventBase& add_event_remote(std::string name, Signature s) {
    check_new_name(name, true);
    events_.push_back(std::make_unique<EventBase>(std::move(name), s));
    return *events_.back();
  }
  void add(Command c);
  // Commands and events are separate namespaces (CRTK has both a read and an event
  // `operating_state`); within each, a name is unique.
  void check_new_name(const std::string& name, bool event) const;
  template <class E>
  E& add_event(std::string name) {
    check_new_name(name, true);
    auto e = std::make_unique<E>(std::move(name));
    E& ref = *e;
    events_.push_back(std::move(e));
    return ref;
  }

  Component& owner_;
  std::string name_;
  std::vector<std::unique_ptr<Command>> commands_;
  std::vector<std::unique_ptr<EventBase>> events_;
  std::size_t mailbox_capacity_ = default_mailbox_capacity;
};

}  // namespace saw
