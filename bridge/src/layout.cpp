#include "saw/bridge/layout.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <new>

#include "saw/bridge/shm_segment.hpp"

namespace saw::bridge {
namespace {
constexpr std::uint64_t align_up(std::uint64_t v, std::uint64_t a) { return (v + a - 1) / a * a; }
}  // namespace

Layout Layout::of(const LayoutParams& p) {
  Layout l{};
  l.command_slot_size = static_cast<std::uint32_t>(SpscRing::round_slot_size(16 + p.command_payload));
  l.event_slot_size = static_cast<std::uint32_t>(SpscRing::round_slot_size(16 + p.event_payload));
  const std::uint64_t capacity = SpscRing::round_capacity(p.ring_capacity);
  l.manifest_offset = align_up(sizeof(SegmentHeader), cache_line);
  l.mirror_offset = align_up(l.manifest_offset + p.manifest_count * sizeof(ManifestEntry), cache_line);
  l.mirror_words = 1 + (p.mirror_bytes + 7) / 8;  // seq word + data
  l.slots_offset = align_up(l.mirror_offset + l.mirror_words * 8, cache_line);
  l.slot_stride =
      align_up(sizeof(ClientSlot) + capacity * (l.command_slot_size + l.event_slot_size), cache_line);
  l.total_size = l.slots_offset + l.slot_stride * p.slot_count;
  return l;
}

void initialize(void* memory, const LayoutParams& p, const Layout& l, std::int32_t owner_pid) {
  auto* h = new (memory) SegmentHeader{};
  h->magic = segment_magic;
  h->layout_version = layout_version;
  h->header_size = sizeof(SegmentHeader);
  h->interface_hash = p.interface_hash;
  h->incarnation = (static_cast<std::uint64_t>(owner_pid) << 40) ^
                   static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  h->total_size = l.total_size;
  h->manifest_offset = l.manifest_offset;
  h->manifest_count = p.manifest_count;
  h->mirror_offset = l.mirror_offset;
  h->mirror_words = l.mirror_words;
  h->slots_offset = l.slots_offset;
  h->slot_stride = l.slot_stride;
  h->slot_count = p.slot_count;
  h->ring_capacity = static_cast<std::uint32_t>(SpscRing::round_capacity(p.ring_capacity));
  h->command_slot_size = l.command_slot_size;
  h->event_slot_size = l.event_slot_size;
  std::strncpy(h->component, p.component.c_str(), sizeof h->component - 1);
  std::strncpy(h->interface, p.interface.c_str(), sizeof h->interface - 1);
  auto* words = mirror(memory);
  for (std::uint64_t i = 0; i < l.mirror_words; ++i) new (&words[i]) std::atomic<std::uint64_t>(0);
  for (std::uint32_t i = 0; i < p.slot_count; ++i) new (&slot(memory, i)) ClientSlot{};
  h->owner_pid.store(owner_pid, std::memory_order_relaxed);
  h->heartbeat.store(0, std::memory_order_relaxed);
  h->state.store(static_cast<std::uint32_t>(SegmentState::initializing), std::memory_order_release);
}

std::string validate(const void* memory, std::size_t size) {
  if (size < sizeof(SegmentHeader))
    return "truncated: " + std::to_string(size) + " bytes, a header needs " +
           std::to_string(sizeof(SegmentHeader));
  const auto* h = static_cast<const SegmentHeader*>(memory);
  if (h->magic != segment_magic) {
    char found[32];
    std::snprintf(found, sizeof found, "0x%016llx", static_cast<unsigned long long>(h->magic));
    return std::string("not a sawrt bridge segment (magic ") + found + ")";
  }
  if (h->layout_version != layout_version)
    return "layout version " + std::to_string(h->layout_version) +
           " in the segment, this process speaks version " + std::to_string(layout_version);
  if (h->header_size != sizeof(SegmentHeader))
    return "header of " + std::to_string(h->header_size) + " bytes, expected " +
           std::to_string(sizeof(SegmentHeader));
  if (h->total_size > size)
    return "truncated: " + std::to_string(size) + " bytes mapped, the header says " +
           std::to_string(h->total_size);
  LayoutParams p;
  p.manifest_count = static_cast<std::uint32_t>(h->manifest_count);
  p.mirror_bytes = (h->mirror_words - 1) * 8;
  p.slot_count = h->slot_count;
  p.ring_capacity = h->ring_capacity;
  p.command_payload = h->command_slot_size - 16u;
  p.event_payload = h->event_slot_size - 16u;
  const Layout l = Layout::of(p);
  if (h->manifest_count > 4096 || l.manifest_offset != h->manifest_offset || l.total_size != h->total_size ||
      l.slots_offset != h->slots_offset || l.slot_stride != h->slot_stride)
    return "inconsistent layout: offsets do not match the sizes the header gives";
  return {};
}

SegmentHeader& header(void* memory) noexcept { return *static_cast<SegmentHeader*>(memory); }

ManifestEntry* manifest(void* memory) noexcept {
  return reinterpret_cast<ManifestEntry*>(static_cast<std::byte*>(memory) + header(memory).manifest_offset);
}

std::atomic<std::uint64_t>* mirror(void* memory) noexcept {
  return reinterpret_cast<std::atomic<std::uint64_t>*>(static_cast<std::byte*>(memory) +
                                                       header(memory).mirror_offset);
}

ClientSlot& slot(void* memory, std::uint32_t index) noexcept {
  const auto& h = header(memory);
  return *reinterpret_cast<ClientSlot*>(static_cast<std::byte*>(memory) + h.slots_offset +
                                        index * h.slot_stride);
}

namespace {
std::byte* ring_storage(void* memory, std::uint32_t index, bool events) {
  const auto& h = header(memory);
  auto* base = reinterpret_cast<std::byte*>(&slot(memory, index)) + sizeof(ClientSlot);
  return events ? base + std::uint64_t{h.ring_capacity} * h.command_slot_size : base;
}
}  // namespace

SpscRing command_ring(void* memory, std::uint32_t index) {
  const auto& h = header(memory);
  return SpscRing(&slot(memory, index).commands, ring_storage(memory, index, false), h.ring_capacity,
                  h.command_slot_size);
}

SpscRing event_ring(void* memory, std::uint32_t index) {
  const auto& h = header(memory);
  return SpscRing(&slot(memory, index).events, ring_storage(memory, index, true), h.ring_capacity,
                  h.event_slot_size);
}

void mirror_write(void* memory, const void* data, std::size_t size) noexcept {
  auto* w = mirror(memory);
  const auto words = (size + 7) / 8;
  const auto seq = w[0].load(std::memory_order_relaxed);
  w[0].store(seq + 1, std::memory_order_relaxed);
  for (std::size_t i = 0; i < words; ++i) {
    std::uint64_t v = 0;
    std::memcpy(&v, static_cast<const std::byte*>(data) + i * 8, std::min<std::size_t>(8, size - i * 8));
    w[1 + i].store(v, std::memory_order_release);
  }
  w[0].store(seq + 2, std::memory_order_release);
}

bool mirror_read(void* memory, void* data, std::size_t size) noexcept {
  auto* w = mirror(memory);
  const auto words = (size + 7) / 8;
  for (int attempt = 0; attempt < 64; ++attempt) {
    const auto s1 = w[0].load(std::memory_order_acquire);
    if (s1 & 1U) continue;
    for (std::size_t i = 0; i < words; ++i) {
      const auto v = w[1 + i].load(std::memory_order_acquire);
      std::memcpy(static_cast<std::byte*>(data) + i * 8, &v, std::min<std::size_t>(8, size - i * 8));
    }
    if (w[0].load(std::memory_order_relaxed) == s1) return true;
  }
  return false;
}

std::unique_ptr<SpscRing> make_command_ring(void* memory, std::uint32_t index) {
  const auto& h = header(memory);
  return std::make_unique<SpscRing>(&slot(memory, index).commands, ring_storage(memory, index, false),
                                    h.ring_capacity, h.command_slot_size);
}

std::unique_ptr<SpscRing> make_event_ring(void* memory, std::uint32_t index) {
  const auto& h = header(memory);
  return std::make_unique<SpscRing>(&slot(memory, index).events, ring_storage(memory, index, true),
                                    h.ring_capacity, h.event_slot_size);
}

int claim_slot(void* memory, std::int32_t pid) noexcept {
  const auto& h = header(memory);
  for (std::uint32_t i = 0; i < h.slot_count; ++i) {
    auto& s = slot(memory, i);
    std::int32_t expected = 0;
    if (s.owner_pid.compare_exchange_strong(expected, pid, std::memory_order_acq_rel)) {
      // The rings are not reset: the server may be draining this slot right now. The new owner
      // continues from the indices as they are (commands a dead owner left are still run: they
      // were accepted), and, as the event ring's consumer, skips the events queued for the
      // previous owner.
      s.events.tail.store(s.events.head.load(std::memory_order_acquire), std::memory_order_release);
      s.generation.fetch_add(1, std::memory_order_release);
      return static_cast<int>(i);
    }
  }
  return -1;
}

void release_slot(void* memory, std::uint32_t index, std::int32_t pid) noexcept {
  std::int32_t expected = pid;
  slot(memory, index).owner_pid.compare_exchange_strong(expected, 0, std::memory_order_acq_rel);
}

std::uint32_t reclaim_dead_slots(void* memory) noexcept {
  const auto& h = header(memory);
  std::uint32_t n = 0;
  for (std::uint32_t i = 0; i < h.slot_count; ++i) {
    auto& s = slot(memory, i);
    std::int32_t pid = s.owner_pid.load(std::memory_order_acquire);
    if (pid != 0 && !process_alive(pid) &&
        s.owner_pid.compare_exchange_strong(pid, 0, std::memory_order_acq_rel))
      ++n;
  }
  return n;
}

}  // namespace saw::bridge
