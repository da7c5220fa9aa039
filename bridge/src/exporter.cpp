#include "saw/bridge/exporter.hpp"

#include <unistd.h>

#include <cstring>

#include "saw/bridge/futex.hpp"

namespace saw::bridge {
namespace {

void copy_name(char* dst, std::size_t n, std::string_view src) {
  const auto k = std::min(n - 1, src.size());
  std::memcpy(dst, src.data(), k);
  dst[k] = '\0';
}

bool owner_alive(const void* mapping, std::size_t size) {
  return validate(mapping, size).empty() &&
         process_alive(static_cast<const SegmentHeader*>(mapping)->owner_pid.load(std::memory_order_acquire));
}

std::uint64_t fnv1a(std::uint64_t h, std::string_view s) {
  for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return h;
}

// A value that crosses the process boundary must declare its layout (see TypeInfo).
void check_registered(const std::string& component, const std::string& name, const Signature& sig) {
  for (const TypeInfo* t : {&sig.arg, &sig.result})
    if (t->size != 0 && t->version == 0)
      throw BridgeError("export: " + component + " '" + name + "' carries " + std::string(t->name) +
                        ", which has no layout version: declare `static constexpr std::uint32_t "
                        "layout_version = 1;` in it to let it cross a process boundary");
}

}  // namespace

Exporter::Exporter(Component& component, const std::string& provided, ExportOptions options)
    : service_spin_(options.service_spin), segment_([&] {
        ProvidedInterface* p = component.provided(provided);
        if (p == nullptr)
          throw BridgeError("export: component '" + component.name() + "' has no provided interface '" +
                            provided + "'");
        LayoutParams lp;
        lp.component = component.name();
        lp.interface = provided;
        std::size_t mirror = 8, command_payload = 8,
                    event_payload = 8;  // the mirror starts with the row time
        for (const auto& c : p->commands()) {
          if (c->signature.kind == CommandKind::qualified_read &&
              (c->signature.arg.size > QueryArea::max_bytes ||
               c->signature.result.size > QueryArea::max_bytes))
            throw BridgeError("export: qualified read '" + c->name + "' has values over " +
                              std::to_string(QueryArea::max_bytes) + " bytes");
          check_registered(component.name(), c->name, c->signature);
          ++lp.manifest_count;
          if (c->signature.kind == CommandKind::read)
            mirror += (c->signature.arg.size + 7) / 8 * 8;
          else
            command_payload = std::max(command_payload, c->signature.arg.size);
        }
        for (const auto& e : p->events()) {
          check_registered(component.name(), e->name(), e->signature());
          ++lp.manifest_count;
          event_payload = std::max(event_payload, e->signature().arg.size);
        }
        lp.mirror_bytes = mirror;
        lp.slot_count = options.slots;
        lp.ring_capacity = options.ring_capacity;
        lp.command_payload = command_payload;
        lp.event_payload = event_payload;
        const Layout l = Layout::of(lp);
        ShmSegment s = ShmSegment::create("/saw." + component.name(), l.total_size, owner_alive);
        initialize(s.data(), lp, l, static_cast<std::int32_t>(getpid()));
        return s;
      }()) {
  ProvidedInterface& p = *component.provided(provided);
  void* mem = segment_.data();
  ManifestEntry* m = manifest(mem);
  std::uint32_t index = 0, offset = 8;
  std::uint64_t hash = 14695981039346656037ULL;
  const auto describe = [&](const std::string& name, const Signature& sig) {
    ManifestEntry& e = m[index];
    copy_name(e.name, sizeof e.name, name);
    e.kind = static_cast<std::uint8_t>(sig.kind);
    e.has_limits = 0;
    e.arg_size = static_cast<std::uint32_t>(sig.arg.size);
    e.result_size = static_cast<std::uint32_t>(sig.result.size);
    e.arg_version = sig.arg.version;
    e.result_version = sig.result.version;
    copy_name(e.arg_type, sizeof e.arg_type, sig.arg.name);
    copy_name(e.result_type, sizeof e.result_type, sig.result.name);
    hash = fnv1a(fnv1a(fnv1a(fnv1a(hash, name), sig.arg.name), sig.result.name),
                 std::to_string(e.kind) + ":" + std::to_string(e.arg_size) + ":" +
                     std::to_string(e.arg_version) + ":" + std::to_string(e.result_size) + ":" +
                     std::to_string(e.result_version));
  };
  for (const auto& c : p.commands()) {
    describe(c->name, c->signature);
    if (c->limits) {
      m[index].has_limits = 1;
      m[index].limit_min = c->limits->min;
      m[index].limit_max = c->limits->max;
    }
    if (c->signature.kind == CommandKind::read) {
      m[index].mirror_offset = offset;
      reads_.push_back({c.get(), offset, static_cast<std::uint32_t>(c->signature.arg.size)});
      offset += static_cast<std::uint32_t>((c->signature.arg.size + 7) / 8 * 8);
    }
    commands_.push_back(c.get());
    ++index;
  }
  for (const auto& e : p.events()) {
    describe(e->name(), e->signature());
    // Events travel with their ordinal among events, which is how the proxy's mailbox numbers them.
    const auto ordinal = static_cast<std::uint32_t>(taps_.size());
    taps_.push_back(std::make_unique<EventTap>(
        EventTap{this, ordinal, static_cast<std::uint32_t>(e->signature().arg.size)}));
    Observer o;
    o.direct = {[](void* self, const void* arg) {
                  auto* t = static_cast<EventTap*>(self);
                  t->exporter->emit(t->index, arg, t->size);
                },
                taps_.back().get()};
    e->add_observer(o);
    ++index;
  }
  staging_.resize(offset + 8);
  header(mem).interface_hash = hash;
  for (std::uint32_t i = 0; i < header(mem).slot_count; ++i) {
    Slot s;
    s.commands = make_command_ring(mem, i);
    s.events = make_event_ring(mem, i);
    slots_.push_back(std::move(s));
  }
  component.add_cycle_hook(this);
  service_ = std::thread([this] { serve(); });
  header(mem).heartbeat.store(monotonic_now(), std::memory_order_relaxed);
  header(mem).state.store(static_cast<std::uint32_t>(SegmentState::ready), std::memory_order_release);
}

Exporter::~Exporter() {
  stop_.store(true, std::memory_order_release);
  if (segment_.data() != nullptr) {
    auto& h = header(segment_.data());
    h.state.store(static_cast<std::uint32_t>(SegmentState::closed), std::memory_order_release);
    h.service_bell.fetch_add(1, std::memory_order_release);
    futex_wake_all(h.service_bell);
  }
  if (service_.joinable()) service_.join();
}

void Exporter::serve() {
  void* mem = segment_.data();
  auto& h = header(mem);
  TimeNs last_reclaim = 0, last_query = 0;
  while (!stop_.load(std::memory_order_acquire)) {
    const auto bell = h.service_bell.load(std::memory_order_acquire);
    for (std::uint32_t i = 0; i < h.slot_count; ++i) {
      QueryArea& q = slot(mem, i).query;
      const auto request = q.request.load(std::memory_order_acquire);
      if (request == q.reply.load(std::memory_order_relaxed)) continue;
      Status st = Status::invalid;
      if (q.command < commands_.size() && commands_[q.command]->signature.kind == CommandKind::qualified_read)
        st = commands_[q.command]->read(q.arg, q.result);
      q.status = static_cast<std::uint32_t>(st);
      // Dekker with a sleeping client (see the proxy): publish, then look whether it sleeps.
      q.reply.store(request, std::memory_order_seq_cst);
      if (q.waiting.load(std::memory_order_seq_cst) != 0) futex_wake_all(q.reply);
      last_query = monotonic_now();
    }
    // Dead clients' slots are reclaimed every 50 ms, not on every query (it costs a syscall per slot).
    const TimeNs t = monotonic_now();
    if (t - last_reclaim >= 50'000'000) {
      (void)reclaim_dead_slots(mem);
      last_reclaim = t;
    }
    // Busy for a while after a query (callers that want sub-microsecond answers), then asleep.
    if (t - last_query < service_spin_) continue;
    h.service_sleeping.store(1, std::memory_order_seq_cst);
    if (h.service_bell.load(std::memory_order_seq_cst) == bell)
      futex_wait(h.service_bell, bell, 50'000'000);  // woken by a query, or every 50 ms
    h.service_sleeping.store(0, std::memory_order_relaxed);
  }
}

Exporter::Slot* Exporter::claimed(std::uint32_t i) noexcept {
  ClientSlot& s = slot(segment_.data(), i);
  if (s.owner_pid.load(std::memory_order_acquire) == 0) return nullptr;
  Slot& view = slots_[i];
  // A new owner since we last looked: reload the cached ring indices.
  if (const auto g = s.generation.load(std::memory_order_acquire); g != view.generation) {
    view.commands->resync();
    view.events->resync();
    view.generation = g;
  }
  return &view;
}

void Exporter::emit(std::uint32_t index, const void* arg, std::size_t size) noexcept {
  for (std::uint32_t i = 0; i < slots_.size(); ++i) {
    Slot* live = claimed(i);
    if (live == nullptr) continue;
    Slot& view = *live;
    std::byte* rec = view.events->try_reserve();
    if (rec == nullptr) {
      ++events_refused_;
      continue;
    }
    std::memcpy(rec, &index, sizeof index);
    if (size != 0) std::memcpy(rec + Mailbox::header_bytes(), arg, size);
    view.events->commit();
  }
}

void Exporter::after_cycle(Component&, TimeNs time) noexcept {
  void* mem = segment_.data();
  header(mem).heartbeat.store(monotonic_now(), std::memory_order_release);
  std::memcpy(staging_.data(), &time, sizeof time);  // the row's time: proxies stamp reads with it
  for (const Read& r : reads_) (void)r.command->read(nullptr, staging_.data() + r.offset);
  mirror_write(mem, staging_.data(), staging_.size() - 8);
  // Non-RT clients may sleep on the bell: one wake-up call per cycle at most, none if nobody sleeps.
  SegmentHeader& h = header(mem);
  h.update_bell.fetch_add(1, std::memory_order_seq_cst);
  if (h.update_sleepers.load(std::memory_order_seq_cst) != 0) futex_wake_all(h.update_bell);
  for (std::uint32_t i = 0; i < slots_.size(); ++i) {
    Slot* live = claimed(i);
    if (live == nullptr) continue;
    Slot& view = *live;
    // At most one ring's worth per cycle, as local mailboxes.
    for (std::size_t n = 0; n < view.commands->capacity(); ++n) {
      const std::byte* rec = view.commands->front();
      if (rec == nullptr) break;
      std::uint32_t index = 0;
      std::memcpy(&index, rec, sizeof index);
      if (index < commands_.size() && commands_[index]->execute) {
        commands_[index]->execute(rec + Mailbox::header_bytes());
        ++commands_run_;
      }
      view.commands->pop();
    }
  }
}

}  // namespace saw::bridge
