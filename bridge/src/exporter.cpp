#include "saw/bridge/exporter.hpp"

#include <unistd.h>

#include <cstring>

#include "saw/bridge/futex.hpp"
#include "saw/detail/access.hpp"
#include "saw/detail/mailbox.hpp"

namespace saw::bridge {
namespace {

// Names are checked to fit (check_fits) before the segment exists: a truncated name would
// match another type, or none, in every client.
template <std::size_t N>
void copy_name(char (&dst)[N], std::string_view src) {
  const auto k = std::min(N - 1, src.size());
  if (k != 0) std::memcpy(dst, src.data(), k);  // src.data() may be null when empty
  dst[k] = '\0';
}

// A name that leaves room for its field's terminating NUL.
void check_fits(std::size_t field, std::string_view name, const std::string& what) {
  if (name.size() < field) return;
  throw BridgeError("export: " + what + " \"" + std::string(name) + "\" is " + std::to_string(name.size()) +
                    " characters, longer than the " + std::to_string(field - 1) +
                    " a bridge manifest holds: give it a shorter name");
}

std::uint64_t fnv1a(std::uint64_t h, std::string_view s) {
  for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return h;
}

// A value that crosses the process boundary must be registered: a stable name and a layout
// version (see type_info.hpp), and names that fit the manifest whole.
void check_registered(const std::string& component, const std::string& name, const Signature& sig) {
  const std::string what = component + " '" + name + "'";
  check_fits(sizeof ManifestEntry::name, name, "the name of " + what);
  for (const TypeInfo* t : {&sig.arg, &sig.result}) {
    if (t->size != 0 && t->version == 0)
      throw BridgeError("export: " + what + " carries " + std::string(t->name) +
                        ", which is not registered for other processes: declare in it "
                        "`static constexpr std::string_view type_name = \"ns::Type\";` and "
                        "`static constexpr std::uint32_t layout_version = 1;` (an enum: "
                        "`constexpr std::string_view enum_type_name(E)` beside it)");
    static_assert(sizeof ManifestEntry::arg_type == sizeof ManifestEntry::result_type);
    check_fits(sizeof ManifestEntry::arg_type, t->name, "the type name in " + what);
  }
}

// The commands a segment carries: the interface's, then its task's `period_statistics` (from the
// `task` interface every Task provides), so that the task's health crosses with the one interface
// a component exports. Wire indices follow this order.
std::vector<Command*> exported_commands(const Component& component, const ProvidedInterface& p) {
  std::vector<Command*> all;
  for (const auto& c : p.commands()) all.push_back(c.get());
  const ProvidedInterface* task = component.provided("task");
  Command* stats = task == nullptr || task == &p ? nullptr : task->find_command("period_statistics");
  if (stats != nullptr && stats->signature.kind == CommandKind::read &&
      p.find_command(stats->name) == nullptr)
    all.push_back(stats);
  return all;
}

LayoutParams params_of(const Component& component, const ProvidedInterface& p, const ExportOptions& o) {
  check_fits(sizeof SegmentHeader::component, component.name(), "the component name");
  check_fits(sizeof SegmentHeader::interface, p.name(), "the interface name of " + component.name());
  LayoutParams lp;
  std::size_t mirror = 8, command_payload = 8, event_payload = 8;  // the mirror starts with the row time
  for (const Command* c : exported_commands(component, p)) {
    if (c->signature.kind == CommandKind::qualified_read &&
        (c->signature.arg.size > query_max_bytes || c->signature.result.size > query_max_bytes))
      throw BridgeError("export: qualified read '" + c->name + "' has values over " +
                        std::to_string(query_max_bytes) + " bytes");
    check_registered(component.name(), c->name, c->signature);
    ++lp.manifest_count;
    if (c->signature.kind == CommandKind::read)
      mirror += (c->signature.arg.size + 7) / 8 * 8;
    else
      command_payload = std::max(command_payload, c->signature.arg.size);
  }
  for (const auto& e : p.events()) {
    check_registered(component.name(), e->name(), e->signature());
    ++lp.manifest_count;
    event_payload = std::max(event_payload, e->signature().arg.size);
  }
  lp.mirror_bytes = mirror;
  lp.mirror_rows = o.history_rows;
  lp.slot_count = o.slots;
  lp.ring_capacity = static_cast<std::uint32_t>(detail::SpscRing::round_capacity(o.ring_capacity));
  lp.command_payload = command_payload;
  lp.event_payload = event_payload;
  return lp;
}

}  // namespace

Exporter::Exporter(Component& component, const std::string& provided, ExportOptions options)
    : service_spin_(options.service_spin), client_timeout_(options.client_timeout) {
  ProvidedInterface* p = component.provided(provided);
  if (p == nullptr)
    throw BridgeError("export: component '" + component.name() + "' has no provided interface '" + provided +
                      "'");
  Layout layout;
  if (auto why = Layout::compute(params_of(component, *p, options), layout); !why.empty())
    throw BridgeError("export: " + component.name() + "." + provided + ": " + why);
  segment_ = ShmSegment::create("/saw." + component.name(), layout.total_size, segment_owner_alive);
  view_ = SegmentView(segment_.data(), layout);
  initialize(view_, component.name(), provided, 0, static_cast<std::int32_t>(getpid()));
  view_.header().client_timeout = client_timeout_;
  describe(component, *p);
  record_.resize(layout.command_slot_size);
  last_reply_.assign(layout.slot_count, 0);
  for (std::uint32_t i = 0; i < layout.slot_count; ++i)
    slots_.push_back(Slot{make_command_ring(view_, i), make_event_ring(view_, i)});
  detail::Access::add_cycle_hook(component, this);
  service_ = std::thread([this] { serve(); });
  view_.header().heartbeat.store(monotonic_now(), std::memory_order_relaxed);
  view_.header().state.store(static_cast<std::uint32_t>(SegmentState::ready), std::memory_order_release);
}

// The manifest (names, kinds, types, limits) and the interface hash clients compare.
void Exporter::describe(const Component& component, const ProvidedInterface& p) {
  ManifestEntry* m = view_.manifest();
  std::uint32_t index = 0, offset = 8;
  std::uint64_t hash = 14695981039346656037ULL;
  const auto entry = [&](const std::string& name, const Signature& sig) -> ManifestEntry& {
    ManifestEntry& e = m[index];
    copy_name(e.name, name);
    e.kind = static_cast<std::uint8_t>(sig.kind);
    e.has_limits = 0;
    e.arg_size = static_cast<std::uint32_t>(sig.arg.size);
    e.result_size = static_cast<std::uint32_t>(sig.result.size);
    e.arg_version = sig.arg.version;
    e.result_version = sig.result.version;
    copy_name(e.arg_type, sig.arg.name);
    copy_name(e.result_type, sig.result.name);
    hash = fnv1a(fnv1a(fnv1a(fnv1a(hash, name), sig.arg.name), sig.result.name),
                 std::to_string(e.kind) + ":" + std::to_string(e.arg_size) + ":" +
                     std::to_string(e.arg_version) + ":" + std::to_string(e.result_size) + ":" +
                     std::to_string(e.result_version));
    return e;
  };
  for (Command* c : exported_commands(component, p)) {
    ManifestEntry& e = entry(c->name, c->signature);
    if (c->limits) {
      e.has_limits = 1;
      e.limit_min = c->limits->min;
      e.limit_max = c->limits->max;
    }
    if (c->signature.kind == CommandKind::read) {
      e.mirror_offset = offset;
      reads_.push_back({c, offset, static_cast<std::uint32_t>(c->signature.arg.size)});
      offset += static_cast<std::uint32_t>((c->signature.arg.size + 7) / 8 * 8);
    }
    commands_.push_back(c);
    ++index;
  }
  for (const auto& ev : p.events()) {
    entry(ev->name(), ev->signature());
    // Events travel with their ordinal among events, which is how the proxy's mailbox numbers them.
    const auto ordinal = static_cast<std::uint32_t>(taps_.size());
    taps_.push_back(std::make_unique<EventTap>(
        EventTap{this, ordinal, static_cast<std::uint32_t>(ev->signature().arg.size)}));
    detail::Observer o;
    o.direct = {[](void* self, const void* arg) {
                  auto* t = static_cast<EventTap*>(self);
                  t->exporter->emit(t->index, arg, t->size);
                },
                taps_.back().get()};
    detail::Access::add_observer(*ev, o);
    ++index;
  }
  staging_.resize(offset + 8);
  view_.header().interface_hash = hash;
}

Exporter::~Exporter() {
  stop_.store(true, std::memory_order_release);
  if (segment_.data() != nullptr) {
    view_.header().state.store(static_cast<std::uint32_t>(SegmentState::closed), std::memory_order_release);
    auto& bell = view_.client_common().service_bell;
    bell.fetch_add(1, std::memory_order_release);
    futex_wake_all(bell);
  }
  if (service_.joinable()) service_.join();
}

std::uint64_t Exporter::ring_errors() const noexcept {
  std::uint64_t n = 0;
  for (const Slot& s : slots_) n += s.commands->corrupt_count() + s.events->corrupt_count();
  return n;
}

bool Exporter::answer_queries() {
  alignas(16) std::byte arg[query_max_bytes], result[query_max_bytes];
  bool answered = false;
  for (std::uint32_t i = 0; i < view_.layout().slot_count; ++i) {
    ClientSlot& c = view_.client_slot(i);
    ServerSlot& s = view_.server_slot(i);
    // seq_cst: the sleep check in serve() reads every slot's request after raising its flag.
    const auto request = c.query_request.load(std::memory_order_seq_cst);
    if (request == last_reply_[i]) continue;
    last_reply_[i] = request;
    answered = true;
    // Copied before it is looked at: the client may change it while we work.
    const auto index = c.query_command.load(std::memory_order_relaxed);
    std::memcpy(arg, c.query_arg, sizeof arg);
    Status st = Status::invalid;
    const Command* cmd = index < commands_.size() ? commands_[index] : nullptr;
    if (cmd != nullptr && cmd->signature.kind == CommandKind::qualified_read &&
        (cmd->signature.arg.check == nullptr || cmd->signature.arg.check(arg, nullptr)))
      st = cmd->read(arg, result);
    if (st == Status::invalid) bump(queries_refused_);
    if (st == Status::ok) std::memcpy(s.query_result, result, cmd->signature.result.size);
    s.query_status.store(static_cast<std::uint32_t>(st), std::memory_order_relaxed);
    // Dekker with a sleeping client (see the proxy): publish, then look whether it sleeps.
    s.query_reply.store(request, std::memory_order_seq_cst);
    if (c.query_waiting.load(std::memory_order_seq_cst) != 0) futex_wake_all(s.query_reply);
  }
  return answered;
}

void Exporter::serve() {
  auto& bell_word = view_.client_common().service_bell;
  auto& sleeping = view_.header().service_sleeping;
  TimeNs last_reclaim = 0, last_query = 0;
  while (!stop_.load(std::memory_order_acquire)) {
    const TimeNs t = monotonic_now();
    if (answer_queries()) last_query = t;
    // Slots of clients whose heartbeat stopped are freed every 50 ms, not on every query.
    if (t - last_reclaim >= 50'000'000) {
      const auto n = reclaim_stale_slots(view_, t, client_timeout_);
      slots_reclaimed_.store(load(slots_reclaimed_) + n, std::memory_order_relaxed);
      last_reclaim = t;
    }
    // Busy for a while after a query (callers that want sub-microsecond answers): a client then
    // writes its request and nothing else. Then asleep: Dekker with the client, which writes its
    // request, then rings the bell only if it sees this flag raised; here the flag is raised,
    // then every request read again (answer_queries, seq_cst), so one of the two sees the other.
    if (t - last_query < service_spin_) continue;
    const auto bell = bell_word.load(std::memory_order_acquire);
    sleeping.store(1, std::memory_order_seq_cst);
    if (!answer_queries())
      futex_wait(bell_word, bell, 50'000'000);  // woken by a query, or every 50 ms
    else
      last_query = t;
    sleeping.store(0, std::memory_order_relaxed);
  }
}

void Exporter::emit(std::uint32_t index, const void* arg, std::size_t size) noexcept {
  for (std::uint32_t i = 0; i < slots_.size(); ++i) {
    if (view_.client_slot(i).owner.load(std::memory_order_acquire) == 0) continue;
    detail::SpscRing& ring = *slots_[i].events;
    std::byte* rec = ring.try_reserve();
    if (rec == nullptr) {
      bump(events_refused_);
      continue;
    }
    std::memcpy(rec, &index, sizeof index);
    if (size != 0) std::memcpy(rec + detail::Mailbox::header_bytes(), arg, size);
    ring.commit();
  }
}

void Exporter::run_commands(Slot& slot) noexcept {
  detail::SpscRing& ring = *slot.commands;
  // At most one ring's worth per cycle, as local mailboxes.
  for (std::size_t n = 0; n < ring.capacity(); ++n) {
    const std::byte* rec = ring.front();
    if (rec == nullptr) break;
    std::memcpy(record_.data(), rec, record_.size());  // ours from here: the client can't change it
    ring.pop();
    std::uint32_t index = 0;
    std::memcpy(&index, record_.data(), sizeof index);
    Command* c = index < commands_.size() ? commands_[index] : nullptr;
    const std::byte* arg = record_.data() + detail::Mailbox::header_bytes();
    const bool runs =
        c != nullptr && c->execute &&
        (c->signature.kind == CommandKind::void_command || c->signature.kind == CommandKind::write) &&
        (c->signature.arg.check == nullptr || c->signature.arg.check(arg, c->limits ? &*c->limits : nullptr));
    if (!runs) {
      bump(commands_refused_);
      continue;
    }
    c->execute(arg);
    bump(commands_run_);
  }
}

void Exporter::after_cycle(Component&, TimeNs time) noexcept {
  SegmentHeader& h = view_.header();
  h.heartbeat.store(monotonic_now(), std::memory_order_release);
  std::memcpy(staging_.data(), &time, sizeof time);  // the row's time: proxies stamp reads with it
  for (const Read& r : reads_) (void)r.command->read(nullptr, staging_.data() + r.offset);
  mirror_write(view_, mirror_rows_, staging_.data(), staging_.size() - 8);
  // Non-RT clients may sleep on the bell: one wake-up call per cycle at most, none if nobody sleeps.
  h.update_bell.fetch_add(1, std::memory_order_seq_cst);
  bool sleepers = false;
  for (std::uint32_t i = 0; i < slots_.size(); ++i) {
    const ClientSlot& c = view_.client_slot(i);
    if (c.owner.load(std::memory_order_acquire) == 0) continue;
    sleepers = sleepers || c.update_waiting.load(std::memory_order_seq_cst) != 0;
    run_commands(slots_[i]);
  }
  if (sleepers) futex_wake_all(h.update_bell);
}

}  // namespace saw::bridge
