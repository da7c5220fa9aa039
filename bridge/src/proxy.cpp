#include "saw/bridge/proxy.hpp"

#include <unistd.h>

#include <cstring>
#include <optional>

#include "saw/bridge/futex.hpp"

namespace saw::bridge {
namespace {

bool ready(const SegmentHeader& h, TimeNs stale_after) noexcept {
  return h.state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::ready) &&
         monotonic_now() - h.heartbeat.load(std::memory_order_acquire) <= stale_after;
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
    // re-read `word` (both seq_cst), so one of us sees the other.
    sleeping.fetch_add(1, std::memory_order_seq_cst);
    const bool changed = word.load(std::memory_order_seq_cst) != old;
    const TimeNs left = deadline - monotonic_now();
    if (!changed && left > 0) futex_wait(word, old, left);
    sleeping.fetch_sub(1, std::memory_order_seq_cst);
    if (changed || word.load(std::memory_order_acquire) != old) return true;
    if (deadline - monotonic_now() <= 0) return false;
  }
}

}  // namespace

std::unique_ptr<Proxy::Link> Proxy::make_link(ShmSegment s, std::uint32_t slot_index) {
  auto l = std::make_unique<Link>(Link{std::move(s), slot_index, nullptr, nullptr});
  l->commands = make_command_ring(l->segment.data(), slot_index);
  l->events = make_event_ring(l->segment.data(), slot_index);
  return l;
}

Proxy::Proxy(ShmSegment segment, int slot_index, ProxyOptions options)
    : Component(header(segment.data()).component), path_(segment.name()), options_(options) {
  links_.push_back(make_link(std::move(segment), static_cast<std::uint32_t>(slot_index)));
  link_ = links_.back().get();
  mailbox_on_ = link_;
  void* mem = link_->segment.data();
  const SegmentHeader& h = header(mem);
  interface_hash_ = h.interface_hash;
  mirror_bytes_ = (h.mirror_words - 1) * 8;
  auto& slot_ref = slot(mem, link_->slot);
  events_ = std::make_unique<Mailbox>(std::string(h.component) + " events (shared memory)", &slot_ref.events,
                                      reinterpret_cast<std::byte*>(&slot_ref) + sizeof(ClientSlot) +
                                          std::uint64_t{h.ring_capacity} * h.command_slot_size,
                                      h.ring_capacity, h.event_slot_size);
  auto& p = provide(h.interface);
  const ManifestEntry* m = manifest(mem);
  const auto type = [&](const char* name, std::uint32_t size, std::uint32_t version) {
    type_names_.emplace_back(name);
    return TypeInfo{type_names_.back(), size, version};
  };
  for (std::uint32_t i = 0; i < h.manifest_count; ++i) {
    const ManifestEntry& e = m[i];
    const auto kind = static_cast<CommandKind>(e.kind);
    const Signature sig{kind, e.arg_size ? type(e.arg_type, e.arg_size, e.arg_version) : TypeInfo{},
                        e.result_size ? type(e.result_type, e.result_size, e.result_version) : TypeInfo{}};
    if (kind == CommandKind::void_event || kind == CommandKind::write_event) {
      p.add_event_remote(e.name, sig);
      // Numbered by ordinal among events (as the exporter sends them); a no-op until connect binds a handler.
      events_->set_target(static_cast<std::uint32_t>(p.events().size() - 1),
                          Invoker{[](void*, const void*) {}, nullptr});
      continue;
    }
    Command c;
    c.name = e.name;
    c.signature = sig;
    if (e.has_limits != 0) c.limits = Limits{e.limit_min, e.limit_max};
    if (kind == CommandKind::read) {
      const std::uint32_t offset = e.mirror_offset, size = e.arg_size;
      c.read_stamped = [this, offset, size](void* out, RowStamp& stamp) {
        Link& l = link();
        if (!alive(l)) return Status::disconnected;
        alignas(16) std::byte block[4096];
        if (mirror_bytes_ > sizeof block) return Status::invalid;
        if (!mirror_read(l.segment.data(), block, mirror_bytes_)) return Status::busy;
        std::memcpy(&stamp.time, block, sizeof stamp.time);  // the server's row time
        stamp.tick = 0;
        std::memcpy(out, block + offset, size);
        return Status::ok;
      };
      c.read = [f = c.read_stamped](const void*, void* out) {
        RowStamp ignored;
        return f(out, ignored);
      };
    } else if (kind == CommandKind::qualified_read) {
      // Waits for the server's service thread: for non-RT callers only (connect refuses RT ones).
      c.read = [this, i, arg = e.arg_size, res = e.result_size](const void* q, void* r) {
        Link& l = link();
        if (!alive(l)) return Status::disconnected;
        QueryArea& area = slot(l.segment.data(), l.slot).query;
        SegmentHeader& hdr = header(l.segment.data());
        std::memcpy(area.arg, q, arg);
        area.command = i;
        const auto request = area.request.load(std::memory_order_relaxed) + 1;
        area.request.store(request, std::memory_order_release);
        hdr.service_bell.fetch_add(1, std::memory_order_seq_cst);
        if (hdr.service_sleeping.load(std::memory_order_seq_cst) != 0) futex_wake_all(hdr.service_bell);
        const TimeNs deadline = monotonic_now() + options_.stale_after;
        for (;;) {
          const auto reply = area.reply.load(std::memory_order_acquire);
          if (reply == request) break;
          if (!await_change(area.reply, reply, area.waiting, options_.spin, deadline)) return Status::timeout;
        }
        const auto st = static_cast<Status>(area.status);
        if (st == Status::ok) std::memcpy(r, area.result, res);
        return st;
      };
    } else {
      c.execute = [](const void*) {};  // never used: forward takes the call
      c.forward = [this, i, size = e.arg_size](const void* arg) {
        Link& l = link();
        if (!alive(l)) return Status::disconnected;
        std::byte* rec = l.commands->try_reserve();
        if (rec == nullptr) {
          commands_refused_.store(commands_refused_.load(std::memory_order_relaxed) + 1,
                                  std::memory_order_relaxed);  // one writer: the calling thread
          return Status::queue_full;
        }
        std::memcpy(rec, &i, sizeof i);
        if (size != 0) std::memcpy(rec + Mailbox::header_bytes(), arg, size);
        l.commands->commit();
        return Status::ok;
      };
    }
    p.add_command(std::move(c));
  }
  monitor_ = std::thread([this] { monitor(); });
}

Proxy::~Proxy() {
  stop_.store(1, std::memory_order_release);
  futex_wake_all(stop_);
  if (monitor_.joinable()) monitor_.join();
  for (const auto& l : links_) release_slot(l->segment.data(), l->slot, static_cast<std::int32_t>(getpid()));
}

void Proxy::adopt() noexcept {
  Link* next = offered_.exchange(nullptr, std::memory_order_acq_rel);
  if (next == nullptr) return;
  next->commands->resync();
  link_ = next;  // from here on this thread never touches the previous link
}

bool Proxy::alive(const Link& l) const noexcept {
  return ready(header(l.segment.data()), options_.stale_after);
}

bool Proxy::wait_for_update(std::uint32_t& seen, TimeNs timeout) noexcept {
  Link& l = link();
  SegmentHeader& h = header(l.segment.data());
  const TimeNs deadline = monotonic_now() + timeout;
  if (h.update_bell.load(std::memory_order_acquire) == seen &&
      !await_change(h.update_bell, seen, h.update_sleepers, options_.spin, deadline))
    return false;
  seen = h.update_bell.load(std::memory_order_acquire);
  return true;
}

std::unique_ptr<Proxy::Link> Proxy::try_reconnect() {
  std::optional<ShmSegment> s;
  try {
    s.emplace(ShmSegment::attach(path_));
  } catch (const BridgeError&) {
    return nullptr;  // no server under that name (yet)
  }
  if (!validate(s->data(), s->size()).empty()) return nullptr;
  const SegmentHeader& h = header(s->data());
  const SegmentHeader& current = header(links_.back()->segment.data());
  // The same server (stalled, not gone), one still starting, or another interface: not ours.
  if (h.incarnation == current.incarnation || !ready(h, options_.stale_after) ||
      h.interface_hash != interface_hash_)
    return nullptr;
  const auto pid = static_cast<std::int32_t>(getpid());
  int index = claim_slot(s->data(), pid);
  if (index < 0 && reclaim_dead_slots(s->data()) > 0) index = claim_slot(s->data(), pid);
  if (index < 0) return nullptr;
  return make_link(std::move(*s), static_cast<std::uint32_t>(index));
}

void Proxy::monitor() {
  while (stop_.load(std::memory_order_acquire) == 0) {
    futex_wait(stop_, 0, options_.reconnect_poll);
    if (offered_.load(std::memory_order_acquire) != nullptr || events_->offer_pending())
      continue;  // one switch at a time: wait until both threads have taken the last one
    Link* newest = links_.back().get();
    // A consumer may have attached to the event mailbox since the last switch.
    if (mailbox_on_ != newest && events_->consumer_attached() && events_->offer_ring(newest->events.get())) {
      mailbox_on_ = newest;
      continue;
    }
    // The calling thread uses the newest link, the mailbox `mailbox_on_`: the others can go.
    std::erase_if(links_, [&](const std::unique_ptr<Link>& l) {
      if (l.get() == newest || l.get() == mailbox_on_) return false;
      release_slot(l->segment.data(), l->slot, static_cast<std::int32_t>(getpid()));
      return true;
    });
    if (ready(header(newest->segment.data()), options_.stale_after)) continue;
    std::unique_ptr<Link> next = try_reconnect();
    if (next == nullptr) continue;
    links_.push_back(std::move(next));
    newest = links_.back().get();
    if (events_->consumer_attached() && events_->offer_ring(newest->events.get())) mailbox_on_ = newest;
    offered_.store(newest, std::memory_order_release);
    reconnects_.fetch_add(1, std::memory_order_relaxed);
  }
}

std::unique_ptr<Component> ShmResolver::resolve(std::string_view name) {
  const std::string path = "/saw." + std::string(name);
  std::optional<ShmSegment> s;
  try {
    s.emplace(ShmSegment::attach(path));
  } catch (const BridgeError&) {
    return nullptr;  // not exported on this host
  }
  if (const auto why = validate(s->data(), s->size()); !why.empty())
    throw ConnectError("shared-memory segment " + path + " refused: " + why);
  const SegmentHeader& h = header(s->data());
  const auto age = monotonic_now() - h.heartbeat.load(std::memory_order_acquire);
  if (!ready(h, options_.stale_after))
    throw ConnectError("shared-memory segment " + path + ": its server (pid " +
                       std::to_string(h.owner_pid.load()) + ") is not running (heartbeat " +
                       std::to_string(age / 1'000'000) + " ms old)");
  const auto pid = static_cast<std::int32_t>(getpid());
  int index = claim_slot(s->data(), pid);
  if (index < 0 && reclaim_dead_slots(s->data()) > 0) index = claim_slot(s->data(), pid);
  if (index < 0)
    throw ConnectError("shared-memory segment " + path + ": all " + std::to_string(h.slot_count) +
                       " client slots are taken");
  return std::make_unique<Proxy>(std::move(*s), index, options_);
}

}  // namespace saw::bridge
