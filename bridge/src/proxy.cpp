#include "saw/bridge/proxy.hpp"

#include <unistd.h>

#include <cstring>
#include <optional>

#include "saw/bridge/futex.hpp"

namespace saw::bridge {

Proxy::Proxy(ShmSegment segment, int slot_index, TimeNs stale_after)
    : Component(header(segment.data()).component),
      segment_(std::move(segment)),
      slot_(slot_index),
      stale_after_(stale_after) {
  void* mem = segment_.data();
  const SegmentHeader& h = header(mem);
  mirror_bytes_ = (h.mirror_words - 1) * 8;
  commands_ = make_command_ring(mem, static_cast<std::uint32_t>(slot_));
  const auto& slot_ref = slot(mem, static_cast<std::uint32_t>(slot_));
  events_ = std::make_unique<Mailbox>(
      std::string(h.component) + " events (shared memory)", const_cast<SpscRingControl*>(&slot_ref.events),
      reinterpret_cast<std::byte*>(const_cast<ClientSlot*>(&slot_ref)) + sizeof(ClientSlot) +
          std::uint64_t{h.ring_capacity} * h.command_slot_size,
      h.ring_capacity, h.event_slot_size);
  auto& p = provide(h.interface);
  const ManifestEntry* m = manifest(mem);
  const auto type = [&](const char* name, std::uint32_t size) {
    type_names_.emplace_back(name);
    return TypeInfo{type_names_.back(), size};
  };
  for (std::uint32_t i = 0; i < h.manifest_count; ++i) {
    const ManifestEntry& e = m[i];
    const auto kind = static_cast<CommandKind>(e.kind);
    const Signature sig{kind, e.arg_size ? type(e.arg_type, e.arg_size) : TypeInfo{},
                        e.result_size ? type(e.result_type, e.result_size) : TypeInfo{}};
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
    if (kind == CommandKind::read) {
      const std::uint32_t offset = e.mirror_offset, size = e.arg_size;
      c.read_stamped = [this, offset, size](void* out, RowStamp& stamp) {
        if (!server_alive()) return Status::disconnected;
        alignas(16) std::byte block[4096];
        if (mirror_bytes_ > sizeof block) return Status::invalid;
        if (!mirror_read(segment_.data(), block, mirror_bytes_)) return Status::busy;
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
        if (!server_alive()) return Status::disconnected;
        QueryArea& area = slot(segment_.data(), static_cast<std::uint32_t>(slot_)).query;
        SegmentHeader& hdr = header(segment_.data());
        std::memcpy(area.arg, q, arg);
        area.command = i;
        const auto request = area.request.load(std::memory_order_relaxed) + 1;
        area.request.store(request, std::memory_order_release);
        hdr.service_bell.fetch_add(1, std::memory_order_release);
        futex_wake_all(hdr.service_bell);
        const TimeNs deadline = monotonic_now() + stale_after_;
        for (;;) {
          const auto reply = area.reply.load(std::memory_order_acquire);
          if (reply == request) break;
          const TimeNs left = deadline - monotonic_now();
          if (left <= 0) return Status::timeout;
          futex_wait(area.reply, reply, left);
        }
        const auto st = static_cast<Status>(area.status);
        if (st == Status::ok) std::memcpy(r, area.result, res);
        return st;
      };
    } else {
      c.execute = [](const void*) {};  // never used: forward takes the call
      c.forward = [this, i, size = e.arg_size](const void* arg) {
        if (!server_alive()) return Status::disconnected;
        std::byte* rec = commands_->try_reserve();
        if (rec == nullptr) return Status::queue_full;
        std::memcpy(rec, &i, sizeof i);
        if (size != 0) std::memcpy(rec + Mailbox::header_bytes(), arg, size);
        commands_->commit();
        return Status::ok;
      };
    }
    p.add_command(std::move(c));
  }
}

Proxy::~Proxy() {
  release_slot(segment_.data(), static_cast<std::uint32_t>(slot_), static_cast<std::int32_t>(getpid()));
}

bool Proxy::server_alive() const noexcept {
  const SegmentHeader& h = header(segment_.data());
  return h.state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::ready) &&
         monotonic_now() - h.heartbeat.load(std::memory_order_acquire) <= stale_after_;
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
  if (h.state.load(std::memory_order_acquire) != static_cast<std::uint32_t>(SegmentState::ready) ||
      age > Proxy::default_stale_after)
    throw ConnectError("shared-memory segment " + path + ": its server (pid " +
                       std::to_string(h.owner_pid.load()) + ") is not running (heartbeat " +
                       std::to_string(age / 1'000'000) + " ms old)");
  const auto pid = static_cast<std::int32_t>(getpid());
  int index = claim_slot(s->data(), pid);
  if (index < 0 && reclaim_dead_slots(s->data()) > 0) index = claim_slot(s->data(), pid);
  if (index < 0)
    throw ConnectError("shared-memory segment " + path + ": all " + std::to_string(h.slot_count) +
                       " client slots are taken");
  return std::make_unique<Proxy>(std::move(*s), index);
}

}  // namespace saw::bridge
