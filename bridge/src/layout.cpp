#include "saw/bridge/layout.hpp"

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <new>
#include <random>
#include <set>

#include "saw/bridge/shm_segment.hpp"
#include "saw/clock.hpp"
#include "saw/command_kind.hpp"

namespace saw::bridge {
namespace {

// Overflow-checked arithmetic: a value from the segment can be anything.
bool add(std::uint64_t& r, std::uint64_t a, std::uint64_t b) { return !__builtin_add_overflow(a, b, &r); }
bool mul(std::uint64_t& r, std::uint64_t a, std::uint64_t b) { return !__builtin_mul_overflow(a, b, &r); }
bool align_up(std::uint64_t& r, std::uint64_t v, std::uint64_t a) {
  if (!add(r, v, a - 1)) return false;
  r = r / a * a;
  return true;
}

std::string number(const char* what, std::uint64_t v, const char* bound) {
  return std::string(what) + " " + std::to_string(v) + " " + bound;
}

bool terminated(const char* field, std::size_t n) { return std::memchr(field, '\0', n) != nullptr; }

std::string check_entry(const ManifestEntry& e, std::uint32_t i, const Layout& l) {
  const std::string where = "manifest entry " + std::to_string(i) + ": ";
  if (!terminated(e.name, sizeof e.name) || !terminated(e.arg_type, sizeof e.arg_type) ||
      !terminated(e.result_type, sizeof e.result_type))
    return where + "a name is not terminated inside its field";
  if (e.kind > static_cast<std::uint8_t>(CommandKind::write_event))
    return where + "kind " + std::to_string(e.kind) + " is not a command or event kind";
  const auto kind = static_cast<CommandKind>(e.kind);
  const std::uint64_t arg = e.arg_size, result = e.result_size;
  if (e.has_limits > 1) return where + "has_limits is " + std::to_string(e.has_limits);
  if (e.has_limits == 1 && !(e.limit_min <= e.limit_max))  // also false for NaN
    return where + "limits are not an interval";
  switch (kind) {
    case CommandKind::read: {
      std::uint64_t end = 0;
      if (e.mirror_offset < 8 || !add(end, e.mirror_offset, arg) || end > (l.mirror_words - 1ULL) * 8)
        return where + "its value (" + std::to_string(arg) + " bytes at " + std::to_string(e.mirror_offset) +
               ") is not inside the state mirror (" + std::to_string((l.mirror_words - 1ULL) * 8) + " bytes)";
      break;
    }
    case CommandKind::qualified_read:
      if (arg > query_max_bytes || result > query_max_bytes)
        return where + "a qualified read's values exceed " + std::to_string(query_max_bytes) + " bytes";
      break;
    case CommandKind::void_command:
    case CommandKind::write:
      if (arg + 16 > l.command_slot_size)
        return where + "its argument (" + std::to_string(arg) + " bytes) does not fit a command slot (" +
               std::to_string(l.command_slot_size) + ")";
      break;
    case CommandKind::void_event:
    case CommandKind::write_event:
      if (arg + 16 > l.event_slot_size)
        return where + "its argument (" + std::to_string(arg) + " bytes) does not fit an event slot (" +
               std::to_string(l.event_slot_size) + ")";
      break;
  }
  return {};
}

}  // namespace

std::string Layout::compute(const LayoutParams& p, Layout& out) {
  if (p.manifest_count > max_manifest_entries)
    return number("manifest of", p.manifest_count,
                  ("entries, at most " + std::to_string(max_manifest_entries)).c_str());
  if (p.mirror_bytes > max_mirror_bytes)
    return number("state mirror of", p.mirror_bytes,
                  ("bytes, at most " + std::to_string(max_mirror_bytes)).c_str());
  if (p.mirror_rows < 1 || p.mirror_rows > max_mirror_rows)
    return number("state mirror of", p.mirror_rows,
                  ("rows is outside 1.." + std::to_string(max_mirror_rows)).c_str());
  if (p.slot_count < 1 || p.slot_count > max_slots)
    return number("slot count", p.slot_count, ("is outside 1.." + std::to_string(max_slots)).c_str());
  if (p.ring_capacity < 2 || p.ring_capacity > max_ring_capacity || !std::has_single_bit(p.ring_capacity))
    return number("ring capacity", p.ring_capacity,
                  ("is not a power of two in 2.." + std::to_string(max_ring_capacity)).c_str());
  if (p.command_payload > max_record_size - 16 || p.event_payload > max_record_size - 16)
    return "a command or event argument exceeds " + std::to_string(max_record_size - 16) + " bytes";
  Layout l;
  l.manifest_count = p.manifest_count;
  l.mirror_words = static_cast<std::uint32_t>(1 + (p.mirror_bytes + 7) / 8);  // seq word + data
  l.mirror_rows = p.mirror_rows;
  l.slot_count = p.slot_count;
  l.ring_capacity = p.ring_capacity;
  l.command_slot_size = static_cast<std::uint32_t>((16 + p.command_payload + 15) / 16 * 16);
  l.event_slot_size = static_cast<std::uint32_t>((16 + p.event_payload + 15) / 16 * 16);
  // The bounds above keep every product below 2^40; the checks stay, for whoever raises them.
  std::uint64_t t = 0, u = 0;
  bool ok = align_up(l.manifest_offset, sizeof(SegmentHeader), cache_line);
  ok = ok && mul(t, l.manifest_count, sizeof(ManifestEntry)) && add(t, t, l.manifest_offset) &&
       align_up(l.mirror_offset, t, cache_line);
  ok = ok && mul(t, l.mirror_words, 8) && mul(t, t, l.mirror_rows) && add(t, t, l.mirror_offset) &&
       align_up(l.server_slots_offset, t, cache_line);
  ok = ok && mul(t, l.ring_capacity, l.event_slot_size) && add(t, t, sizeof(ServerSlot)) &&
       align_up(l.server_slot_stride, t, cache_line);
  ok = ok && mul(t, l.server_slot_stride, l.slot_count) && add(t, t, l.server_slots_offset) &&
       align_up(l.client_offset, t, page_size);
  ok = ok && add(t, l.client_offset, sizeof(ClientCommon)) && align_up(l.client_slots_offset, t, cache_line);
  ok = ok && mul(t, l.ring_capacity, l.command_slot_size) && add(t, t, sizeof(ClientSlot)) &&
       align_up(l.client_slot_stride, t, cache_line);
  ok = ok && mul(u, l.client_slot_stride, l.slot_count) && add(u, u, l.client_slots_offset) &&
       align_up(l.total_size, u, page_size);
  if (!ok) return "layout arithmetic overflows";
  out = l;
  return {};
}

void initialize(const SegmentView& v, std::string_view component, std::string_view interface,
                std::uint64_t interface_hash, std::int32_t owner_pid) {
  const Layout& l = v.layout();
  auto* h = new (v.base()) SegmentHeader{};
  h->magic = segment_magic;
  h->layout_version = layout_version;
  h->header_size = sizeof(SegmentHeader);
  h->interface_hash = interface_hash;
  h->incarnation = (static_cast<std::uint64_t>(owner_pid) << 40) ^
                   static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  h->total_size = l.total_size;
  h->client_timeout = 0;
  h->manifest_count = l.manifest_count;
  h->mirror_words = l.mirror_words;
  h->mirror_rows = l.mirror_rows;
  h->slot_count = l.slot_count;
  h->ring_capacity = l.ring_capacity;
  h->command_slot_size = l.command_slot_size;
  h->event_slot_size = l.event_slot_size;
  const auto copy = [](char* dst, std::size_t n, std::string_view src) {
    const auto k = std::min(n - 1, src.size());
    if (k != 0) std::memcpy(dst, src.data(), k);
    dst[k] = '\0';
  };
  copy(h->component, sizeof h->component, component);
  copy(h->interface, sizeof h->interface, interface);
  // Every page of the history touched here, not by the RT thread's first pass through it.
  auto* words = v.mirror();
  for (std::uint64_t i = 0; i < std::uint64_t{l.mirror_words} * l.mirror_rows; ++i)
    new (&words[i]) std::atomic<std::uint64_t>(0);
  h->rows_written.store(0, std::memory_order_relaxed);
  for (std::uint32_t i = 0; i < l.slot_count; ++i) {
    new (&v.server_slot(i)) ServerSlot{};
    new (&v.client_slot(i)) ClientSlot{};
  }
  new (&v.client_common()) ClientCommon{};
  h->owner_pid.store(owner_pid, std::memory_order_relaxed);
  h->heartbeat.store(0, std::memory_order_relaxed);
  h->state.store(static_cast<std::uint32_t>(SegmentState::initializing), std::memory_order_release);
}

std::string validate(const void* memory, std::size_t size, Layout* out) {
  if (memory == nullptr || size < sizeof(SegmentHeader))
    return "truncated: " + std::to_string(size) + " bytes, a header needs " +
           std::to_string(sizeof(SegmentHeader));
  // One copy of the header, read once: the segment may change under us.
  SegmentHeader h;
  std::memcpy(static_cast<void*>(&h), memory, sizeof h);
  if (h.magic != segment_magic) {
    char found[32];
    std::snprintf(found, sizeof found, "0x%016llx", static_cast<unsigned long long>(h.magic));
    return std::string("not a sawrt bridge segment (magic ") + found + ")";
  }
  if (h.layout_version != layout_version)
    return "layout version " + std::to_string(h.layout_version) +
           " in the segment, this process speaks version " + std::to_string(layout_version);
  if (h.header_size != sizeof(SegmentHeader))
    return "header of " + std::to_string(h.header_size) + " bytes, expected " +
           std::to_string(sizeof(SegmentHeader));
  if (!terminated(h.component, sizeof h.component) || !terminated(h.interface, sizeof h.interface))
    return "the component or interface name is not terminated inside its field";
  if (h.mirror_words < 1) return "a state mirror of 0 words (it needs its sequence word)";
  LayoutParams p;
  p.manifest_count = h.manifest_count;
  p.mirror_bytes = (std::uint64_t{h.mirror_words} - 1) * 8;
  p.mirror_rows = h.mirror_rows;
  p.slot_count = h.slot_count;
  p.ring_capacity = h.ring_capacity;
  if (h.command_slot_size < 16 || h.event_slot_size < 16 || h.command_slot_size % 16 != 0 ||
      h.event_slot_size % 16 != 0)
    return "ring slots of " + std::to_string(h.command_slot_size) + " and " +
           std::to_string(h.event_slot_size) + " bytes: each must be a multiple of 16, at least 16";
  p.command_payload = h.command_slot_size - 16U;
  p.event_payload = h.event_slot_size - 16U;
  Layout l;
  if (auto why = Layout::compute(p, l); !why.empty()) return "out of bounds: " + why;
  if (l.total_size != h.total_size)
    return "inconsistent layout: the header says " + std::to_string(h.total_size) +
           " bytes, its counts make " + std::to_string(l.total_size);
  if (l.total_size > size)
    return "truncated: " + std::to_string(size) + " bytes mapped, the header says " +
           std::to_string(l.total_size);
  if (h.client_timeout < 0 || h.client_timeout > 60'000'000'000LL)
    return "client timeout of " + std::to_string(h.client_timeout) + " ns is outside 0..60 s";
  const auto* base = static_cast<const std::byte*>(memory);
  std::set<std::string> commands, events;  // a name is unique among commands, and among events
  for (std::uint32_t i = 0; i < l.manifest_count; ++i) {
    ManifestEntry e;
    std::memcpy(&e, base + l.manifest_offset + std::uint64_t{i} * sizeof(ManifestEntry), sizeof e);
    if (auto why = check_entry(e, i, l); !why.empty()) return why;
    const bool event = e.kind >= static_cast<std::uint8_t>(CommandKind::void_event);
    if (!(event ? events : commands).emplace(e.name).second)
      return "manifest entry " + std::to_string(i) + ": '" + e.name + "' is named twice";
  }
  if (out != nullptr) *out = l;
  return {};
}

void mirror_write(const SegmentView& v, std::uint64_t& rows, const void* data, std::size_t size) noexcept {
  const std::uint64_t row = rows;
  auto* w = v.mirror(row);
  const auto words = std::min<std::size_t>((size + 7) / 8, v.layout().mirror_words - 1U);
  w[0].store(2 * row + 1, std::memory_order_relaxed);  // odd: being written
  for (std::size_t i = 0; i < words; ++i) {
    std::uint64_t x = 0;
    std::memcpy(&x, static_cast<const std::byte*>(data) + i * 8, std::min<std::size_t>(8, size - i * 8));
    w[1 + i].store(x, std::memory_order_release);
  }
  w[0].store(2 * row + 2, std::memory_order_release);  // even: row `row` is done
  rows = row + 1;
  v.header().rows_written.store(rows, std::memory_order_release);
}

namespace {

// The block expected to say `seq` (a row's 2n + 2, or 0 for the zeros before the first row):
// 0 if copied whole, > 0 if it says more (overwritten, or being), < 0 if less (not yet written).
int read_block(const std::atomic<std::uint64_t>* w, std::uint64_t seq, std::size_t words, void* data,
               std::size_t size) noexcept {
  const auto s1 = w[0].load(std::memory_order_acquire);
  if (s1 != seq) return s1 > seq ? 1 : -1;
  for (std::size_t i = 0; i < words; ++i) {
    const auto x = w[1 + i].load(std::memory_order_acquire);
    std::memcpy(static_cast<std::byte*>(data) + i * 8, &x, std::min<std::size_t>(8, size - i * 8));
  }
  return w[0].load(std::memory_order_relaxed) == s1 ? 0 : 1;
}

}  // namespace

bool mirror_read(const SegmentView& v, void* data, std::size_t size) noexcept {
  const auto words = std::min<std::size_t>((size + 7) / 8, v.layout().mirror_words - 1U);
  for (int attempt = 0; attempt < 64; ++attempt) {
    const auto n = v.header().rows_written.load(std::memory_order_acquire);
    if (read_block(v.mirror(n == 0 ? 0 : n - 1), 2 * n, words, data, size) == 0) return true;
  }
  return false;
}

RowRead mirror_read_row(const SegmentView& v, std::uint64_t row, void* data, std::size_t size) noexcept {
  const auto words = std::min<std::size_t>((size + 7) / 8, v.layout().mirror_words - 1U);
  const int r = read_block(v.mirror(row), 2 * row + 2, words, data, size);
  return r == 0 ? RowRead::ok : r > 0 ? RowRead::overwritten : RowRead::not_written;
}

int claim_slot(const SegmentView& v, std::uint64_t token, std::int32_t pid, std::int64_t now) noexcept {
  for (std::uint32_t i = 0; i < v.layout().slot_count; ++i) {
    ClientSlot& s = v.client_slot(i);
    std::uint64_t expected = 0;
    if (!s.owner.compare_exchange_strong(expected, token, std::memory_order_acq_rel)) continue;
    s.owner_pid.store(pid, std::memory_order_relaxed);
    s.heartbeat.store(now, std::memory_order_release);
    s.update_waiting.store(0, std::memory_order_relaxed);
    s.query_waiting.store(0, std::memory_order_relaxed);
    // Commands go on from the ring's head as the last owner left it (the server's consumer
    // index is its own); events queued for the last owner are skipped.
    s.events_tail.store(v.server_slot(i).events_head.load(std::memory_order_acquire),
                        std::memory_order_release);
    // The server answers when request differs from its last reply: start level with it.
    s.query_request.store(v.server_slot(i).query_reply.load(std::memory_order_acquire),
                          std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;
}

void release_slot(const SegmentView& v, std::uint32_t index, std::uint64_t token) noexcept {
  if (index >= v.layout().slot_count) return;
  ClientSlot& s = v.client_slot(index);
  s.update_waiting.store(0, std::memory_order_relaxed);
  s.query_waiting.store(0, std::memory_order_relaxed);
  std::uint64_t expected = token;
  s.owner.compare_exchange_strong(expected, 0, std::memory_order_acq_rel);
}

std::uint32_t reclaim_stale_slots(const SegmentView& v, std::int64_t now, std::int64_t timeout) noexcept {
  std::uint32_t n = 0;
  for (std::uint32_t i = 0; i < v.layout().slot_count; ++i) {
    ClientSlot& s = v.client_slot(i);
    std::uint64_t token = s.owner.load(std::memory_order_acquire);
    // A heartbeat further in the future than the timeout is no more alive than one in the past.
    const std::int64_t age = elapsed(now, s.heartbeat.load(std::memory_order_acquire));
    if (token == 0 || (age <= timeout && age >= -timeout)) continue;
    // A dead client's sleeper flags would make the server wake a futex every cycle forever.
    s.update_waiting.store(0, std::memory_order_relaxed);
    s.query_waiting.store(0, std::memory_order_relaxed);
    if (s.owner.compare_exchange_strong(token, 0, std::memory_order_acq_rel)) ++n;
  }
  return n;
}

bool segment_owner_alive(const ShmSegment& old) noexcept {
  if (old.size() < sizeof(SegmentHeader)) return false;  // a creation that died before sizing it
  const auto* h = static_cast<const SegmentHeader*>(old.data());
  // A zero magic is a creation that died before writing its header, or a live owner's header
  // that a peer scribbled over: the owner's pid and heartbeat below tell which.
  if (h->magic != 0 && h->magic != segment_magic) return true;  // not ours to remove
  // Pids wrap (32768 by default): a process that began after the segment was made holds a
  // reused pid and says nothing about the owner.
  const auto pid = h->owner_pid.load(std::memory_order_acquire);
  if (process_alive(pid) && !process_started_after(pid, old.modified_ns())) return true;
  // Its pid is gone (or reused) here, but the owner may live in another pid namespace: it does if its
  // heartbeat still moves (a killed owner's last beat stays as it was).
  const auto beat = h->heartbeat.load(std::memory_order_acquire);
  if (const auto age = elapsed(monotonic_now(), beat); age > 1'000'000'000 || age < -1'000'000'000)
    return false;
  for (int i = 0; i < 20; ++i) {
    ::usleep(10'000);
    if (h->heartbeat.load(std::memory_order_acquire) != beat) return true;
  }
  return false;
}

std::uint64_t new_claim_token() noexcept {
  std::uint64_t r = 0;
  try {
    std::random_device rd;
    r = (std::uint64_t{rd()} << 32) ^ rd();
  } catch (...) {
    r = static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  }
  r ^= static_cast<std::uint64_t>(::getpid()) << 16;
  return r == 0 ? 1 : r;
}

}  // namespace saw::bridge
