#include "saw/bridge/proxy.hpp"

#include <unistd.h>

#include <cstring>
#include <optional>

#include "saw/bridge/futex.hpp"
#include "saw/detail/access.hpp"

namespace saw::bridge {
namespace {

bool ready(const SegmentHeader& h, TimeNs stale_after) noexcept {
  return h.state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::ready) &&
         elapsed(monotonic_now(), h.heartbeat.load(std::memory_order_acquire)) <= stale_after;
}

// Spins up to `spin` ns, then sleeps on `word` until it differs from `old`, at most until
// `deadline`. `sleeping` tells the other side to wake us. False on timeout.
bool await_change(std::atomic<std::uint32_t>& word, std::uint32_t old, std::atomic<std::uint32_t>& sleeping,
                  TimeNs spin, TimeNs deadline) noexcept {
  if (spin > 0) {
    const TimeNs until = monotonic_now() + spin;
    do {
      if (word.load(std::memory_order_acquire) != old) return true;
    } while (monotonic_now() < until);
  }
  for (;;) {
    // Dekker with the waker: it changes `word` then reads `sleeping`; we raise `sleeping` then
    // re-read `word` (both seq_cst), so one of us sees the other. `sleeping` is this client's
    // own flag (1 or 0): a client that dies asleep leaves at most its own slot's flag raised,
    // which the server clears when it frees the slot.
    sleeping.store(1, std::memory_order_seq_cst);
    const bool changed = word.load(std::memory_order_seq_cst) != old;
    const TimeNs left = deadline - monotonic_now();
    if (!changed && left > 0) futex_wait(word, old, left);
    sleeping.store(0, std::memory_order_seq_cst);
    if (changed || word.load(std::memory_order_acquire) != old) return true;
    if (deadline - monotonic_now() <= 0) return false;
  }
}

int claim(const SegmentView& v, std::uint64_t token) {
  const auto pid = static_cast<std::int32_t>(getpid());
  int index = claim_slot(v, token, pid, monotonic_now());
  if (index < 0 && reclaim_stale_slots(v, monotonic_now(), v.header().client_timeout) > 0)
    index = claim_slot(v, token, pid, monotonic_now());
  return index;
}

}  // namespace

ShmSegment attach_validated(const std::string& path, Layout& layout, std::string& why) {
  ShmSegment s = ShmSegment::attach(path, /*writable=*/false);
  why = validate(s.data(), s.size(), &layout);
  if (why.empty()) s.make_writable(layout.client_offset, layout.total_size - layout.client_offset);
  return s;
}

std::unique_ptr<Proxy::Link> Proxy::make_link(ShmSegment s, const Layout& layout, std::uint32_t slot_index,
                                              std::uint64_t token) {
  auto l = std::make_unique<Link>(Link{std::move(s), {}, slot_index, token, nullptr, nullptr});
  l->view = SegmentView(l->segment.data(), layout);
  l->commands = make_command_ring(l->view, slot_index);
  l->events = make_event_ring(l->view, slot_index);
  return l;
}

Proxy::Proxy(ShmSegment segment, const Layout& layout, int slot_index, std::uint64_t token,
             ProxyOptions options)
    : Component([&] {
        // Validated: terminated inside its field. Copied, as everything else read from the segment.
        const auto* h = static_cast<const SegmentHeader*>(segment.data());
        return std::string(h->component);
      }()),
      path_(segment.name()),
      options_(options) {
  links_.push_back(make_link(std::move(segment), layout, static_cast<std::uint32_t>(slot_index), token));
  link_ = links_.back().get();
  mailbox_on_ = link_;
  build_interface(*link_);
  monitor_ = std::thread([this] { monitor(); });
}

// The interface as the manifest describes it (validated: sizes fit, names terminated).
void Proxy::build_interface(const Link& l) {
  const SegmentHeader& h = l.view.header();
  const Layout& layout = l.view.layout();
  interface_hash_ = h.interface_hash;
  incarnation_ = h.incarnation;
  mirror_bytes_ = (std::size_t{layout.mirror_words} - 1) * 8;
  history_rows_ = layout.mirror_rows;
  events_ = std::make_unique<detail::Mailbox>(name() + " events (shared memory)", &l.server().events_head,
                                              &l.client().events_tail, l.view.event_storage(l.slot),
                                              layout.ring_capacity, layout.event_slot_size);
  auto& p = provide(std::string(h.interface));
  const auto type = [&](const char* name, std::uint32_t size, std::uint32_t version) {
    type_names_.emplace_back(name);
    return TypeInfo{type_names_.back(), size, version};
  };
  for (std::uint32_t i = 0; i < layout.manifest_count; ++i) {
    ManifestEntry e;
    std::memcpy(&e, &l.view.manifest()[i], sizeof e);
    const auto kind = static_cast<CommandKind>(e.kind);
    const Signature sig{kind, e.arg_size ? type(e.arg_type, e.arg_size, e.arg_version) : TypeInfo{},
                        e.result_size ? type(e.result_type, e.result_size, e.result_version) : TypeInfo{}};
    if (kind == CommandKind::void_event || kind == CommandKind::write_event) {
      detail::Access::add_event_remote(p, e.name, sig);
      // Numbered by ordinal among events (as the exporter sends them); a no-op until connect binds a handler.
      events_->set_target(static_cast<std::uint32_t>(p.events().size() - 1),
                          detail::Invoker{[](void*, const void*) {}, nullptr});
      continue;
    }
    Command c;
    c.name = e.name;
    c.signature = sig;
    if (e.has_limits != 0) c.limits = Limits{e.limit_min, e.limit_max};
    if (kind == CommandKind::read) {
      const std::uint32_t offset = e.mirror_offset, size = e.arg_size;
      slices_.push_back({e.name, offset, size});
      auto& stamped = detail::Access::read_stamped(c);
      stamped = [this, offset, size](void* out, RowStamp& stamp) {
        Link& lk = link();
        if (!alive(lk)) return Status::disconnected;
        // Before the server's first row the mirror holds zeros, which no server said: no data, as
        // a state table in this process says (a restarted server's reads say nothing until it runs).
        if (lk.view.header().rows_written.load(std::memory_order_acquire) == 0) return Status::no_data;
        alignas(16) std::byte block[max_mirror_bytes + 8];
        if (!mirror_read(lk.view, block, mirror_bytes_)) return Status::busy;
        std::memcpy(&stamp.time, block, sizeof stamp.time);  // the server's row time
        stamp.tick = 0;
        std::memcpy(out, block + offset, size);
        return Status::ok;
      };
      c.read = [f = stamped](const void*, void* out) {
        RowStamp ignored;
        return f(out, ignored);
      };
    } else if (kind == CommandKind::qualified_read) {
      // Waits for the server's service thread: for non-RT callers only (connect refuses RT ones).
      c.read = [this, i, arg = e.arg_size, res = e.result_size](const void* q, void* r) {
        return query(i, arg, res, q, r);
      };
    } else {
      c.execute = [](const void*) {};  // never used: forward takes the call
      detail::Access::forward(c) = [this, i, size = e.arg_size](const void* arg) {
        Link& lk = link();
        if (!alive(lk)) return Status::disconnected;
        std::byte* rec = lk.commands->try_reserve();
        if (rec == nullptr) {
          commands_refused_.store(commands_refused_.load(std::memory_order_relaxed) + 1,
                                  std::memory_order_relaxed);  // one writer: the calling thread
          return Status::queue_full;
        }
        std::memcpy(rec, &i, sizeof i);
        if (size != 0) std::memcpy(rec + detail::Mailbox::header_bytes(), arg, size);
        lk.commands->commit();
        return Status::ok;
      };
    }
    detail::Access::add_command(p, std::move(c));
  }
}

Status Proxy::query(std::uint32_t index, std::uint32_t arg_size, std::uint32_t result_size, const void* q,
                    void* r) noexcept {
  Link& l = link();
  if (!alive(l)) return Status::disconnected;
  ClientSlot& c = l.client();
  ServerSlot& s = l.server();
  std::memcpy(c.query_arg, q, arg_size);
  c.query_command.store(index, std::memory_order_relaxed);
  const auto request = c.query_request.load(std::memory_order_relaxed) + 1;
  // Dekker with the service thread (see Exporter::serve): the request, then its flag; a service
  // thread that spins reads the request, one asleep (or about to be) is rung.
  c.query_request.store(request, std::memory_order_seq_cst);
  if (l.view.header().service_sleeping.load(std::memory_order_seq_cst) != 0) {
    auto& bell = l.view.client_common().service_bell;
    bell.fetch_add(1, std::memory_order_seq_cst);
    futex_wake_all(bell);
  }
  const TimeNs deadline = monotonic_now() + options_.stale_after;
  for (;;) {
    const auto reply = s.query_reply.load(std::memory_order_acquire);
    if (reply == request) break;
    if (!await_change(s.query_reply, reply, c.query_waiting, options_.spin, deadline)) return Status::timeout;
  }
  const auto st = s.query_status.load(std::memory_order_relaxed);
  if (st > static_cast<std::uint32_t>(Status::invalid)) return Status::invalid;  // not a status we know
  if (static_cast<Status>(st) == Status::ok) std::memcpy(r, s.query_result, result_size);
  return static_cast<Status>(st);
}

Proxy::~Proxy() {
  stop_.store(1, std::memory_order_release);
  futex_wake_all(stop_);
  if (monitor_.joinable()) monitor_.join();
  for (const auto& l : links_) release_slot(l->view, l->slot, l->token);
}

std::string Proxy::last_error() const {
  const std::lock_guard lock(error_mutex_);
  return error_;
}

void Proxy::set_error(const std::string& why) noexcept {
  try {
    const std::lock_guard lock(error_mutex_);
    error_ = why;
  } catch (...) {  // out of memory for a message: keep the previous one
  }
}

void Proxy::adopt() noexcept {
  Link* next = offered_.exchange(nullptr, std::memory_order_acq_rel);
  if (next == nullptr) return;
  next->commands->resync();
  link_ = next;  // from here on this thread never touches the previous link
}

bool Proxy::alive(const Link& l) const noexcept {
  // The server is running, and still counts this slot as ours.
  return ready(l.view.header(), options_.stale_after) &&
         l.client().owner.load(std::memory_order_acquire) == l.token;
}

bool Proxy::wait_for_update(std::uint32_t& seen, TimeNs timeout) noexcept {
  Link& l = link();
  SegmentHeader& h = l.view.header();
  const TimeNs deadline = monotonic_now() + timeout;
  if (h.update_bell.load(std::memory_order_acquire) == seen &&
      !await_change(h.update_bell, seen, l.client().update_waiting, options_.spin, deadline))
    return false;
  seen = h.update_bell.load(std::memory_order_acquire);
  return true;
}

std::uint64_t Proxy::rows_written() noexcept {
  Link& l = link();
  return alive(l) ? l.view.header().rows_written.load(std::memory_order_acquire) : 0;
}

Proxy::RowStatus Proxy::read_row(std::uint64_t row, void* block) noexcept {
  Link& l = link();
  if (!alive(l)) return RowStatus::disconnected;
  switch (mirror_read_row(l.view, row, block, mirror_bytes_)) {
    case RowRead::ok:
      return RowStatus::ok;
    case RowRead::overwritten:
      return RowStatus::overwritten;
    case RowRead::not_written:
      break;
  }
  return RowStatus::not_written;
}

bool Proxy::read_slice(std::string_view name, std::uint32_t& offset, std::uint32_t& size) const noexcept {
  for (const Slice& s : slices_)
    if (s.name == name) {
      offset = s.offset;
      size = s.size;
      return true;
    }
  return false;
}

std::unique_ptr<Proxy::Link> Proxy::try_reconnect() {
  std::optional<ShmSegment> s;
  Layout layout;
  std::string why;
  try {
    s.emplace(attach_validated(path_, layout, why));
  } catch (const BridgeError&) {
    return nullptr;  // no server under that name (yet)
  }
  if (!why.empty()) {
    set_error("shared-memory segment " + path_ + " refused: " + why);
    return nullptr;
  }
  const SegmentHeader& h = *static_cast<const SegmentHeader*>(s->data());
  const bool same_server = h.incarnation == incarnation_;
  const bool slot_lost =
      links_.back()->client().owner.load(std::memory_order_acquire) != links_.back()->token;
  // One still starting, another interface, or the same server that merely stalled: not ours.
  if (!ready(h, options_.stale_after) || h.interface_hash != interface_hash_ || (same_server && !slot_lost))
    return nullptr;
  const std::uint64_t token = new_claim_token();
  const SegmentView view(s->data(), layout);
  const int index = claim(view, token);
  if (index < 0) {
    set_error("shared-memory segment " + path_ + ": all client slots are taken");
    return nullptr;
  }
  incarnation_ = h.incarnation;
  return make_link(std::move(*s), layout, static_cast<std::uint32_t>(index), token);
}

void Proxy::monitor_once() {
  Link* newest = links_.back().get();
  // Our slots stay ours while we beat: the server frees the slots of clients that stop.
  for (const auto& l : links_) l->client().heartbeat.store(monotonic_now(), std::memory_order_release);
  if (offered_.load(std::memory_order_acquire) != nullptr || events_->offer_pending())
    return;  // one switch at a time: wait until both threads have taken the last one
  // A consumer may have attached to the event mailbox since the last switch.
  if (mailbox_on_ != newest && events_->consumer_attached() && events_->offer_ring(newest->events.get())) {
    mailbox_on_ = newest;
    return;
  }
  // The calling thread uses the newest link, the mailbox `mailbox_on_`: the others can go.
  std::erase_if(links_, [&](const std::unique_ptr<Link>& l) {
    if (l.get() == newest || l.get() == mailbox_on_) return false;
    release_slot(l->view, l->slot, l->token);
    return true;
  });
  if (alive(*newest)) return;
  std::unique_ptr<Link> next = try_reconnect();
  if (next == nullptr) return;
  links_.push_back(std::move(next));
  newest = links_.back().get();
  if (events_->consumer_attached() && events_->offer_ring(newest->events.get())) mailbox_on_ = newest;
  offered_.store(newest, std::memory_order_release);
  reconnects_.fetch_add(1, std::memory_order_relaxed);
}

void Proxy::monitor() {
  while (stop_.load(std::memory_order_acquire) == 0) {
    futex_wait(stop_, 0, options_.reconnect_poll);
    try {
      monitor_once();
    } catch (const std::exception& e) {  // a segment we could not use: stay disconnected, say why
      set_error(std::string("reconnect failed: ") + e.what());
    } catch (...) {
      set_error("reconnect failed");
    }
  }
}

std::unique_ptr<Component> ShmResolver::resolve(std::string_view name) {
  const std::string path = "/saw." + std::string(name);
  std::optional<ShmSegment> s;
  Layout layout;
  std::string why;
  try {
    s.emplace(attach_validated(path, layout, why));
  } catch (const BridgeError&) {
    return nullptr;  // not exported on this host
  }
  if (!why.empty()) throw ConnectError("shared-memory segment " + path + " refused: " + why);
  const SegmentView view(s->data(), layout);
  const SegmentHeader& h = view.header();
  const auto age = elapsed(monotonic_now(), h.heartbeat.load(std::memory_order_acquire));
  if (!ready(h, options_.stale_after))
    throw ConnectError("shared-memory segment " + path + ": its server (pid " +
                       std::to_string(h.owner_pid.load()) + ") is not running (heartbeat " +
                       std::to_string(age / 1'000'000) + " ms old)");
  const std::uint64_t token = new_claim_token();
  const int index = claim(view, token);
  if (index < 0)
    throw ConnectError("shared-memory segment " + path + ": all " + std::to_string(layout.slot_count) +
                       " client slots are taken");
  try {
    return std::make_unique<Proxy>(std::move(*s), layout, index, token, options_);
  } catch (const std::exception& e) {  // a manifest the proxy cannot rebuild: say so at connect
    throw ConnectError("shared-memory segment " + path + " refused: " + e.what());
  }
}

}  // namespace saw::bridge
