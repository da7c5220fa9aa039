// The shared-memory bridge's segment layout: header, state mirror, per-client slots.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "saw/cache_line.hpp"
#include "saw/spsc_ring.hpp"

namespace saw::bridge {

inline constexpr std::uint64_t segment_magic = 0x3147445242574153ULL;  // "SAWBRDG1", little endian
inline constexpr std::uint32_t layout_version = 3;                     // any change below bumps this

enum class SegmentState : std::uint32_t { initializing = 0, ready = 1, closed = 2 };

// Fixed-width, standard-layout, address-free: the same bytes in every process.
struct alignas(cache_line) SegmentHeader {
  std::uint64_t magic;
  std::uint32_t layout_version;
  std::uint32_t header_size;
  std::uint64_t interface_hash;  // of the exported interface: names, kinds, type names and sizes
  std::uint64_t incarnation;     // differs between two servers that used the same name
  std::uint64_t total_size;
  std::uint64_t manifest_offset, manifest_count;
  std::uint64_t mirror_offset, mirror_words;
  std::uint64_t slots_offset, slot_stride;
  std::uint32_t slot_count, ring_capacity, command_slot_size, event_slot_size;
  char component[64];
  char interface[64];
  alignas(cache_line) std::atomic<std::int32_t> owner_pid;
  std::atomic<std::uint32_t> state;
  std::atomic<std::int64_t> heartbeat;          // owner's CLOCK_MONOTONIC ns, refreshed every cycle
  std::atomic<std::uint32_t> service_bell;      // bumped by clients with a query
  std::atomic<std::uint32_t> service_sleeping;  // the service thread is (about to be) in futex_wait
  // Bumped by the owner after every state row; woken (one call per cycle at most) only when
  // update_sleepers says a non-RT client waits on it.
  alignas(cache_line) std::atomic<std::uint32_t> update_bell;
  std::atomic<std::uint32_t> update_sleepers;
};

// A qualified read in flight: the client fills `command` and `arg`, then bumps `request`
// (release); the server's service thread runs the query and stores `reply` = `request`
// (release) after `result`. The bytes change hands by those two atomics only.
struct alignas(cache_line) QueryArea {
  static constexpr std::size_t max_bytes = 256;
  std::atomic<std::uint32_t> request;
  std::atomic<std::uint32_t> reply;
  std::atomic<std::uint32_t> waiting;  // the client sleeps on `reply`: the server must wake it
  std::uint32_t command;
  std::uint32_t status;  // saw::Status of the query
  alignas(16) std::byte arg[max_bytes];
  alignas(16) std::byte result[max_bytes];
};

// One client's slot: claimed by compare-and-swap of owner_pid from 0, reclaimed when that
// process is gone. Both rings' storage follows the slot header. A claim keeps the ring indices
// (the server may be mid-drain), drops the events queued for the previous owner and bumps
// `generation`; the server resyncs its cached indices when it sees a new generation.
struct alignas(cache_line) ClientSlot {
  std::atomic<std::int32_t> owner_pid;
  std::atomic<std::uint32_t> generation;  // bumped on every claim: a stale view can tell
  SpscRingControl commands;               // client → server
  SpscRingControl events;                 // server → client
  QueryArea query;                        // qualified reads, answered by the service thread
};

// One exported command or event, in the order the manifest gives them (their wire index).
struct ManifestEntry {
  char name[48];
  std::uint8_t kind;        // saw::CommandKind
  std::uint8_t has_limits;  // write commands: 1 when limit_min/limit_max are declared (saw::Limits)
  std::uint8_t reserved[2];
  std::uint32_t arg_size, result_size;
  std::uint32_t mirror_offset;                // read commands: where the value sits in the state mirror
  std::uint32_t arg_version, result_version;  // the types' layout versions (TypeInfo::version)
  char arg_type[96];
  char result_type[96];
  double limit_min, limit_max;
};

struct LayoutParams {
  std::string component;
  std::string interface;
  std::uint32_t manifest_count = 0;
  std::uint64_t interface_hash = 0;
  std::size_t mirror_bytes = 0;
  std::uint32_t slot_count = 8;
  std::uint32_t ring_capacity = 64;
  std::size_t command_payload = 64;  // largest command argument
  std::size_t event_payload = 64;    // largest event argument
};

// Offsets and sizes for a segment with these parameters.
struct Layout {
  std::uint64_t manifest_offset, mirror_offset, mirror_words, slots_offset, slot_stride, total_size;
  std::uint32_t command_slot_size, event_slot_size;
  static Layout of(const LayoutParams& p);
};

// Writes a fresh header (state initializing, owner = this process) into zeroed memory.
void initialize(void* memory, const LayoutParams& p, const Layout& l, std::int32_t owner_pid);

// Checks a mapping before anything is read from it: "" if sound, else what is wrong, naming
// the values found and expected (bad magic, other layout version, truncated file).
std::string validate(const void* memory, std::size_t size);

// Views into a validated mapping.
SegmentHeader& header(void* memory) noexcept;
ManifestEntry* manifest(void* memory) noexcept;
std::atomic<std::uint64_t>* mirror(void* memory) noexcept;
ClientSlot& slot(void* memory, std::uint32_t index) noexcept;
SpscRing command_ring(void* memory, std::uint32_t index);
SpscRing event_ring(void* memory, std::uint32_t index);
std::unique_ptr<SpscRing> make_command_ring(void* memory, std::uint32_t index);
std::unique_ptr<SpscRing> make_event_ring(void* memory, std::uint32_t index);

// The state mirror: one seqlocked block (fence-free, as the state table's rows). One writer.
void mirror_write(void* memory, const void* data, std::size_t size) noexcept;
// False if the writer was mid-update on every try.
bool mirror_read(void* memory, void* data, std::size_t size) noexcept;

// Claims a free slot (or one whose owner died) for `pid`; returns its index or -1 if all taken.
int claim_slot(void* memory, std::int32_t pid) noexcept;
void release_slot(void* memory, std::uint32_t index, std::int32_t pid) noexcept;
// Frees the slots of processes that are gone; returns how many.
std::uint32_t reclaim_dead_slots(void* memory) noexcept;

}  // namespace saw::bridge
