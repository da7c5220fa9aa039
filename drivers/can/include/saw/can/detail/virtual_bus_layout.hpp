// The virtual CAN bus's shared-memory layout: a header, then `capacity` slots (docs/can.md).
#pragma once

#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "saw/cache_line.hpp"
#include "saw/can/frame.hpp"

namespace saw::can::detail {

inline constexpr std::uint64_t virtual_bus_magic = 0x31534E4143574153ULL;  // "SAWCANS1", little endian
inline constexpr std::uint32_t virtual_bus_version = 1;                    // any change below bumps it
inline constexpr std::uint64_t virtual_bus_min_capacity = 2;
inline constexpr std::uint64_t virtual_bus_max_capacity = std::uint64_t{1} << 20;

// Every field is an atomic, even those written once before `magic` is published: the segment is
// shared with processes we do not trust, so any byte may change under us, and a plain read of a
// byte another process writes is a data race. Each process reads the fixed fields once, at attach,
// and keeps its own copy.
struct alignas(cache_line) VirtualBusHeader {
  std::atomic<std::uint64_t> magic;      // stored last by the creator (release): the rest is ready
  std::atomic<std::uint32_t> version;    // virtual_bus_version
  std::atomic<std::uint32_t> slot_size;  // sizeof(VirtualBusSlot)
  std::atomic<std::uint64_t> capacity;   // slots, a power of two
  std::atomic<std::uint64_t> total_size;
  // The next ticket: a producer owns ticket t (and slot t & mask) after fetch_add returns t.
  alignas(cache_line) std::atomic<std::uint64_t> write_ticket;
  // Attachment ids handed out (each attachment takes one; 0 is never used): a slot names its
  // writer so that a reader can skip its own frames, as a CAN_RAW socket does.
  alignas(cache_line) std::atomic<std::uint64_t> attachments;
};

inline constexpr std::size_t frame_words = sizeof(Frame) / sizeof(std::uint64_t);
static_assert(sizeof(Frame) % sizeof(std::uint64_t) == 0 && std::has_unique_object_representations_v<Frame>,
              "a frame is copied through the slot as whole 64-bit words, padding-free");

// One frame in flight. `sequence` is the slot's seqlock word:
//   2t + 1  ticket t's producer is writing it;
//   2t + 2  ticket t's frame is complete;
//   0       never written.
// The payload words are atomics (a seqlock's data must not be a data race for the memory model,
// and TSan checks that), stored with release and loaded with acquire, which orders them against
// the sequence without a fence; on x86 these are plain moves. `check` is a hash of the ticket and the
// payload, so that a reader also rejects a mix of two producers' words (a producer a full ring late that was
// taken over, see the dead-producer rule) and a peer's garbage.
struct alignas(cache_line) VirtualBusSlot {
  std::atomic<std::uint64_t> sequence;
  std::atomic<std::uint64_t> check;
  std::atomic<std::uint64_t> time;    // the sender's CLOCK_MONOTONIC ns (bits of an int64)
  std::atomic<std::uint64_t> writer;  // the sender's attachment id
  std::array<std::atomic<std::uint64_t>, frame_words> frame;
};

static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "a lock would not work across processes");
static_assert(std::is_standard_layout_v<VirtualBusHeader> && std::is_standard_layout_v<VirtualBusSlot>);
static_assert(sizeof(VirtualBusHeader) == 3 * cache_line, "the header's layout is shared: bump the version");
static_assert(sizeof(VirtualBusSlot) == 2 * cache_line, "the slot's layout is shared: bump the version");

inline constexpr std::size_t virtual_bus_slots_offset = sizeof(VirtualBusHeader);

constexpr std::uint64_t virtual_bus_size(std::uint64_t capacity) noexcept {
  return virtual_bus_slots_offset + capacity * sizeof(VirtualBusSlot);
}

// The slot's check word: a multiply-xorshift hash of the ticket and the payload. Not security:
// it catches torn and foreign slots, and a 64-bit hash lets one in 2^64 through.
constexpr std::uint64_t slot_check(std::uint64_t ticket, std::uint64_t time, std::uint64_t writer,
                                   const std::array<std::uint64_t, frame_words>& frame) noexcept {
  constexpr std::uint64_t k = 0x9E3779B97F4A7C15ULL;
  std::uint64_t h = (ticket ^ 0xC3A5C85C97CB3127ULL) * k;
  const auto mix = [&](std::uint64_t w) {
    h = (h ^ w) * k;
    h ^= h >> 29;
  };
  mix(time);
  mix(writer);
  for (const auto w : frame) mix(w);
  return h;
}

constexpr std::array<std::uint64_t, frame_words> frame_to_words(const Frame& f) noexcept {
  return std::bit_cast<std::array<std::uint64_t, frame_words>>(f);
}

constexpr Frame words_to_frame(const std::array<std::uint64_t, frame_words>& w) noexcept {
  return std::bit_cast<Frame>(w);
}

}  // namespace saw::can::detail
