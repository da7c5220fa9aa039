#include "saw/manager.hpp"

#include <algorithm>
#include <cstdio>
#include <thread>

#include "saw/detail/access.hpp"

namespace saw {
namespace {

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

template <class List, class Name>
std::string names_of(const List& list, Name name) {
  std::string out;
  for (const auto& x : list) out += (out.empty() ? "" : ", ") + quoted(name(x));
  return out.empty() ? "none" : out;
}

bool is_queued(CommandKind k) { return k == CommandKind::write || k == CommandKind::void_command; }

// Whether the connection sends commands to the server or takes events from it: through a
// component in another process, that uses its rings.
bool uses_rings(const RequiredInterface& req, const ProvidedInterface& prov) {
  for (const auto& f : req.functions())
    if (const Command* c = prov.find_command(f.name); c != nullptr && is_queued(c->signature.kind))
      return true;
  for (const auto& h : req.handlers())
    if (prov.find_event(h->name) != nullptr) return true;
  return false;
}

// What a mailbox slot or a direct call runs: a command's execute, a handler's handle.
detail::Invoker execute_of(Command& c) {
  return {[](void* self, const void* arg) { static_cast<Command*>(self)->execute(arg); }, &c};
}

detail::Invoker handler_of(EventHandler& h) {
  return {[](void* self, const void* arg) { static_cast<EventHandler*>(self)->handle(arg); }, &h};
}

}  // namespace

Manager::Manager(ManagerOptions options) : options_(options) {}

Manager::~Manager() { stop(); }

void Manager::add(Component& c) {
  if (state_ != ManagerState::idle)
    throw ConnectError("add " + quoted(c.name()) + ": manager already started");
  if (find(c.name()) != nullptr)
    throw ConnectError("add: a component named " + quoted(c.name()) + " exists already");
  components_.push_back(&c);
  for (Component* k : c.companions()) add(*k);
}

Component& Manager::add(std::unique_ptr<Component> c) {
  add(*c);
  owned_.push_back(std::move(c));
  return *owned_.back();
}

Component* Manager::find(std::string_view name) const noexcept {
  for (auto* c : components_)
    if (c->name() == name) return c;
  return nullptr;
}

Component& Manager::get(std::string_view name) const {
  if (auto* c = find(name)) return *c;
  throw ConnectError("no component named " + quoted(name) + " (components: " +
                     names_of(components_, [](const Component* c) { return c->name(); }) + ")");
}

// The two components and interfaces one connect() joins, found by name.
struct Manager::Ends {
  std::string what;  // "connect 'client'.'required' -> 'server'.'provided': ", for messages
  Component& client;
  RequiredInterface& required;
  Component& server;
  ProvidedInterface& provided;
};

Manager::Ends Manager::find_ends(std::string_view client_name, std::string_view required_name,
                                 std::string_view server_name, std::string_view provided_name) {
  std::string what = "connect " + quoted(client_name) + "." + quoted(required_name) + " -> " +
                     quoted(server_name) + "." + quoted(provided_name) + ": ";
  if (state_ != ManagerState::idle) throw ConnectError(what + "the manager has already started");
  Component& client = get(client_name);
  if (find(server_name) == nullptr)
    for (auto& r : resolvers_)
      if (auto proxy = r->resolve(server_name)) {
        add(std::move(proxy));
        break;
      }
  Component& server = get(server_name);
  RequiredInterface* req = client.required(required_name);
  if (req == nullptr)
    throw ConnectError(what + "component " + quoted(client_name) + " has no required interface " +
                       quoted(required_name) + " (it has " +
                       names_of(client.required_interfaces(), [](const auto& r) { return r->name(); }) + ")");
  ProvidedInterface* prov = server.provided(provided_name);
  if (prov == nullptr)
    throw ConnectError(what + "component " + quoted(server_name) + " has no provided interface " +
                       quoted(provided_name) + " (it has " +
                       names_of(server.provided_interfaces(), [](const auto& p) { return p->name(); }) + ")");
  if (req->is_connected())
    throw ConnectError(what + "the required interface is already connected to " + req->connected_to());
  return {std::move(what), client, *req, server, *prov};
}

// Everything connect() could refuse, checked before anything is bound; every mismatch at once.
void Manager::check_ends(const Ends& e) const {
  const RequiredInterface& req = e.required;
  const ProvidedInterface& prov = e.provided;
  std::string errors;
  const auto check = [&](const std::string& name, const Signature& want, Need need, const Signature* have,
                         const std::string& hint = {}) {
    if (have == nullptr) {
      if (need == Need::required)
        errors += "\n  " + quoted(name) + ": the client requires " + to_string(want) +
                  ", the server provides no such " + (is_event(want.kind) ? "event" : "command") +
                  (hint.empty() ? "" : " (" + hint + ")");
    } else if (!(*have == want)) {
      const bool layout = to_string(want) == to_string(*have);  // same names: the layouts differ
      errors += "\n  " + quoted(name) + ": the client expects " + to_string(want, layout) +
                ", the server provides " + to_string(*have, layout);
    }
  };
  for (const auto& f : req.functions()) {
    const Command* c = prov.find_command(f.name);
    check(f.name, f.function->signature(), f.need, c ? &c->signature : nullptr, f.hint);
  }
  for (const auto& h : req.handlers()) {
    const EventBase* ev = prov.find_event(h->name);
    check(h->name, h->signature, h->need, ev ? &ev->signature() : nullptr);
  }
  if (!errors.empty()) throw ConnectError(e.what + "interfaces do not match:" + errors);

  // A qualified read of a component in another process waits for that process: never from an RT task.
  if (const auto* task = dynamic_cast<const Task*>(&e.client);
      e.server.is_remote() && task != nullptr && task->config().priority > 0)
    for (const auto& f : req.functions())
      if (f.function->signature().kind == CommandKind::qualified_read && prov.find_command(f.name) != nullptr)
        throw ConnectError(
            e.what + "'" + f.name +
            "' is a qualified read of a component in another process: it would make " +
            "the real-time task '" + e.client.name() + "' (SCHED_FIFO " +
            std::to_string(task->config().priority) +
            ") wait for that process. Read state instead, or call it from a non-RT component.");

  // A component in another process has one command ring and one event ring in this process,
  // each with a single producer or consumer: one client component may command it or observe
  // its events (any number may read its state).
  if (e.server.is_remote() && uses_rings(req, prov))
    if (auto it = remote_users_.find(e.server.name());
        it != remote_users_.end() && it->second != e.client.name())
      throw ConnectError(e.what + "component " + quoted(e.server.name()) +
                         " is in another process and its commands and events are used by " +
                         quoted(it->second) + " already: one client component per process may send " +
                         "its commands or receive its events (each ring has one producer and one "
                         "consumer); others may read its state");

  // A server in another process delivers its events into one ring, drained by the client's own thread.
  bool any_events = false;
  for (const auto& h : req.handlers()) any_events = any_events || prov.find_event(h->name) != nullptr;
  if (any_events && detail::Access::remote_events(e.server) != nullptr && !e.client.has_thread())
    throw ConnectError(e.what + "a client without a thread cannot receive events from another process");
}

// Commands: queued into a mailbox the server drains, unless the server has no thread.
void Manager::bind_commands(const Ends& e) {
  std::size_t max_arg = 0;
  bool any_queued = false;
  for (const auto& f : e.required.functions())
    if (const Command* c = e.provided.find_command(f.name); c != nullptr && is_queued(c->signature.kind)) {
      any_queued = true;
      max_arg = std::max(max_arg, c->signature.arg.size);
    }
  detail::Mailbox* commands = nullptr;
  if (any_queued && e.server.has_thread()) {
    mailboxes_.push_back(std::make_unique<detail::Mailbox>(
        e.client.name() + "." + e.required.name() + " -> " + e.server.name() + "." + e.provided.name(),
        e.provided.mailbox_capacity(), max_arg));
    commands = mailboxes_.back().get();
    detail::Access::add_inbound(e.server, commands);
  }
  for (const auto& f : e.required.functions()) {
    Command* c = e.provided.find_command(f.name);
    if (c == nullptr) continue;
    detail::FunctionBinding b;
    if (!is_queued(c->signature.kind)) {
      b.command = c;
      if (const auto& stamped = detail::Access::read_stamped(*c)) b.stamped = &stamped;
      b.check_values = e.server.is_remote();  // bytes from another process: checked as the client's type
    } else if (commands != nullptr) {
      b.mailbox = commands;
      b.target = commands->add_target(execute_of(*c));
    } else if (const auto& forward = detail::Access::forward(*c)) {
      b.forward = &forward;
    } else {
      b.direct = execute_of(*c);
    }
    detail::Access::bind(*f.function, b);
  }
}

// Events: queued into a mailbox the client drains, unless the client has no thread.
void Manager::bind_events(const Ends& e) {
  RequiredInterface& req = e.required;
  ProvidedInterface& prov = e.provided;
  std::size_t max_arg = 0;
  bool any_events = false;
  for (const auto& h : req.handlers())
    if (prov.find_event(h->name) != nullptr) {
      any_events = true;
      max_arg = std::max(max_arg, h->signature.arg.size);
    }
  if (!any_events) return;
  if (detail::Mailbox* remote = detail::Access::remote_events(e.server)) {
    // The server is in another process: its events arrive in the proxy's ring, numbered as the
    // proxy's provided events; the client's thread drains that ring.
    const auto& evs = prov.events();
    for (const auto& h : req.handlers())
      for (std::size_t i = 0; i < evs.size(); ++i)
        if (evs[i]->name() == h->name) {
          remote->set_target(static_cast<std::uint32_t>(i), handler_of(*h));
          h->bound = true;
        }
    detail::Access::add_inbound(e.client, remote);
    return;
  }
  detail::Mailbox* events = nullptr;
  if (e.client.has_thread()) {
    mailboxes_.push_back(std::make_unique<detail::Mailbox>(
        e.server.name() + "." + prov.name() + " events -> " + e.client.name() + "." + req.name(),
        req.event_capacity(), max_arg));
    events = mailboxes_.back().get();
    detail::Access::add_inbound(e.client, events);
  }
  for (const auto& h : req.handlers()) {
    EventBase* ev = prov.find_event(h->name);
    if (ev == nullptr) continue;
    detail::Observer o;
    if (events != nullptr) {
      o.mailbox = events;
      o.target = events->add_target(handler_of(*h));
    } else {
      o.direct = handler_of(*h);
    }
    detail::Access::add_observer(*ev, o);
    h->bound = true;
  }
}

void Manager::connect(std::string_view client, std::string_view required, std::string_view server,
                      std::string_view provided) {
  const Ends e = find_ends(client, required, server, provided);
  check_ends(e);
  bind_commands(e);
  bind_events(e);
  if (e.server.is_remote() && uses_rings(e.required, e.provided))
    remote_users_.emplace(e.server.name(), e.client.name());
  detail::Access::set_connected_to(e.required, e.server.name() + "." + e.provided.name());
}

std::optional<ConnectError> Manager::check(std::string_view client, std::string_view required,
                                           std::string_view server, std::string_view provided) {
  try {
    check_ends(find_ends(client, required, server, provided));
  } catch (const ConnectError& e) {
    return e;
  }
  return std::nullopt;
}

void Manager::check_ready_to_start() {
  if (state_ != ManagerState::idle) throw ConnectError("start: the manager has already started");
  std::string errors;
  for (auto* c : components_)
    for (const auto& r : c->required_interfaces())
      if (!r->is_connected() && r->has_required_members())
        errors += "\n  " + quoted(c->name()) + "." + quoted(r->name()) + " is not connected";
  if (!errors.empty()) throw ConnectError("start: required interfaces not connected:" + errors);
}

void Manager::prepare_components() {
  std::size_t started = 0;
  std::string reason;
  try {
    for (; started < components_.size(); ++started) {
      Component* c = components_[started];
      c->state_table().finalize();
      c->startup();
      detail::Access::set_lifecycle(*c, Lifecycle::ready);
    }
    return;
  } catch (const std::exception& e) {
    reason = e.what();
  } catch (...) {
    reason = "an exception that is not a std::exception";
  }
  // Those already started stop again, last first: a device leaves its hardware safe.
  for (std::size_t i = started; i-- > 0;) {
    try {
      components_[i]->cleanup();
    } catch (...) {  // the start's failure is what gets reported
    }
    detail::Access::set_lifecycle(*components_[i], Lifecycle::finished);
  }
  throw StartError(components_[started]->name(), reason);
}

void Manager::start() {
  check_ready_to_start();
  std::vector<Task*> tasks;
  bool any_rt = false;
  for (auto* c : components_)
    if (auto* t = dynamic_cast<Task*>(c)) {
      tasks.push_back(t);
      any_rt = any_rt || t->config().priority > 0;
    }
  if (options_.drain_log) log_drain_ = std::make_unique<LogDrain>();
  if (any_rt && options_.lock_memory)
    if (auto e = rt::lock_memory(); !e.empty()) rt_warnings_.push_back(e);
  if (any_rt && options_.hold_dma_latency) {
    dma_hold_.emplace();
    if (!dma_hold_->error().empty()) rt_warnings_.push_back(dma_hold_->error());
  }
  try {
    prepare_components();
  } catch (...) {
    dma_hold_.reset();
    log_drain_.reset();
    throw;
  }
  running_.store(true, std::memory_order_release);
  first_wakeup_.store(0, std::memory_order_relaxed);
  for (auto* c : components_) detail::Access::set_lifecycle(*c, Lifecycle::active);
  for (auto* t : tasks) detail::Access::start_thread(*t, first_wakeup_, running_);
  for (auto* t : tasks)
    while (!detail::Access::thread_ready(*t)) std::this_thread::yield();  // start-up only, not an RT path
  // Every periodic task shares one phase: the first wake-up is one period after all are set up.
  TimeNs lead = 1'000'000;
  for (auto* t : tasks)
    if (t->config().is_periodic()) lead = std::max<TimeNs>(lead, t->config().period.count());
  first_wakeup_.store(monotonic_now() + lead, std::memory_order_release);
  first_wakeup_.notify_all();
  for (auto* t : tasks)
    if (!t->rt_setup_error().empty())
      rt_warnings_.push_back("task '" + t->name() + "': " + t->rt_setup_error());
  if (!rt_warnings_.empty()) {
    std::string msg = "sawrt WARNING: running without full real-time guarantees:";
    for (const auto& w : rt_warnings_) msg += "\n  - " + w;
    std::fprintf(stderr, "%s\n  (run as root, or grant rtprio and memlock limits; see docs/deploy.md)\n",
                 msg.c_str());
  }
  state_ = ManagerState::running;
}

void Manager::start_stepped(TimeNs t0) {
  check_ready_to_start();
  prepare_components();
  sim_time_ = t0;
  stepped_.clear();
  for (auto* c : components_) {
    detail::Access::set_lifecycle(*c, Lifecycle::active);
    if (auto* t = dynamic_cast<Task*>(c)) stepped_.push_back({t, t0});
  }
  // Shorter periods first; among equals the earlier phase (offset) first, as the threads wake
  // on the grid; then the order the tasks were added.
  std::stable_sort(stepped_.begin(), stepped_.end(), [](const Stepped& a, const Stepped& b) {
    const TaskConfig& x = a.task->config();
    const TaskConfig& y = b.task->config();
    if (x.period != y.period) return x.period < y.period;
    return x.offset < y.offset;
  });
  TimeNs fastest = 0;
  for (const auto& s : stepped_)
    if (s.task->config().is_periodic() && (fastest == 0 || s.task->config().period.count() < fastest))
      fastest = s.task->config().period.count();
  if (fastest == 0) fastest = 1'000'000;
  continuous_period_ = fastest;
  state_ = ManagerState::stepping;
}

TimeNs Manager::step() {
  if (state_ != ManagerState::stepping) throw std::logic_error("step: the manager is not in stepped mode");
  TimeNs next = INT64_MAX;
  for (const auto& s : stepped_) next = std::min(next, s.next);
  if (next == INT64_MAX) return sim_time_;
  sim_time_ = next;
  for (auto& s : stepped_) {
    if (s.next != next) continue;
    detail::Access::step(*s.task, next);
    const TimeNs period =
        s.task->config().is_periodic() ? s.task->config().period.count() : continuous_period_;
    s.next += period;
  }
  return sim_time_;
}

void Manager::step_until(TimeNs t) {
  while (true) {
    TimeNs next = INT64_MAX;
    for (const auto& s : stepped_) next = std::min(next, s.next);
    if (next > t || next == INT64_MAX) break;
    step();
  }
  sim_time_ = std::max(sim_time_, t);
}

void Manager::stop() {
  if (state_ != ManagerState::running && state_ != ManagerState::stepping) return;
  running_.store(false, std::memory_order_release);
  for (auto* c : components_)
    if (auto* t = dynamic_cast<Task*>(c)) detail::Access::join(*t);
  for (auto* c : components_) {
    c->cleanup();
    detail::Access::set_lifecycle(*c, Lifecycle::finished);
  }
  dma_hold_.reset();
  log_drain_.reset();
  state_ = ManagerState::stopped;
}

}  // namespace saw
