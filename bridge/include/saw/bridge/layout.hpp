// The shared-memory bridge's segment layout: what the server writes, what clients write, where.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "saw/cache_line.hpp"
#include "saw/detail/spsc_ring.hpp"

namespace saw::bridge {

inline constexpr std::uint64_t segment_magic = 0x3147445242574153ULL;  // "SAWBRDG1", little endian
inline constexpr std::uint32_t layout_version = 6;                     // any change below bumps this
inline constexpr std::size_t page_size = 4096;

enum class SegmentState : std::uint32_t { initializing = 0, ready = 1, closed = 2 };

// A segment is two regions, each starting on a page:
//   server region (written by the server only; mapped read-only by clients)
//     SegmentHeader | ManifestEntry × manifest_count | state mirror (mirror_rows rows of mirror_words)
//     | (ServerSlot + event ring) × slot_count
//   client region (written by clients; the server reads it and trusts none of it)
//     ClientCommon | (ClientSlot + command ring) × slot_count
// The server computes every offset once, from its own parameters, and never reads one back;
// a client computes them once, from the header it validated, and keeps its copy (Layout).

// Fixed-width, standard-layout, address-free: the same bytes in every process. The first
// four fields never move, whatever the layout version, so that any version can tell whether a
// segment's owner still lives before replacing it.
struct alignas(cache_line) SegmentHeader {
  std::uint64_t magic;
  std::uint32_t layout_version;
  std::atomic<std::int32_t> owner_pid;  // for messages; liveness is the heartbeat
  std::atomic<std::int64_t> heartbeat;  // owner's CLOCK_MONOTONIC ns, refreshed every cycle
  std::atomic<std::uint32_t> state;     // SegmentState
  std::uint32_t header_size;
  std::uint64_t interface_hash;  // of the exported interface: names, kinds, type names and sizes
  std::uint64_t incarnation;     // differs between two servers that used the same name
  std::uint64_t total_size;
  std::int64_t client_timeout;  // ns: a client slot whose heartbeat is older than this is free
  std::uint32_t manifest_count, mirror_words, slot_count, ring_capacity;
  std::uint32_t command_slot_size, event_slot_size;
  std::uint32_t mirror_rows;  // the state mirror keeps this many rows, the newest last written
  char component[64];
  char interface[64];
  // Bumped by the owner after every state row; woken (one call per cycle at most) only when a
  // client's slot says it sleeps on it.
  alignas(cache_line) std::atomic<std::uint32_t> update_bell;
  std::atomic<std::uint32_t> service_sleeping;  // the service thread is (about to be) in futex_wait
  // Rows written to the state mirror (release, after the row): row n is in block n % mirror_rows
  // until row n + mirror_rows overwrites it.
  std::atomic<std::uint64_t> rows_written;
};

// Server-written half of a client's slot; the event ring's storage follows it.
struct alignas(cache_line) ServerSlot {
  std::atomic<std::uint64_t> commands_tail;                    // commands consumed (the server's count)
  alignas(cache_line) std::atomic<std::uint64_t> events_head;  // events published
  // A qualified read's answer: `status` and `result`, then `reply` = the request's number (release).
  alignas(cache_line) std::atomic<std::uint32_t> query_reply;
  std::atomic<std::uint32_t> query_status;  // saw::Status
  alignas(16) std::byte query_result[256];
};

// Client-written half of a slot: claimed by compare-and-swap of `owner` from 0, kept by
// refreshing `heartbeat`, reclaimed (by the server or another client) when the heartbeat is
// older than the server's client timeout. The command ring's storage follows it.
struct alignas(cache_line) ClientSlot {
  std::atomic<std::uint64_t> owner;           // the claim's token; 0: free
  std::atomic<std::int32_t> owner_pid;        // for messages only
  std::atomic<std::uint32_t> update_waiting;  // the client sleeps on the header's update_bell
  std::atomic<std::int64_t> heartbeat;        // the client's CLOCK_MONOTONIC ns
  alignas(cache_line) std::atomic<std::uint64_t> commands_head;
  alignas(cache_line) std::atomic<std::uint64_t> events_tail;
  // A qualified read: the client fills `query_command` and `query_arg`, then bumps `query_request`
  // (release); `query_waiting` says it sleeps on the server slot's `query_reply`.
  alignas(cache_line) std::atomic<std::uint32_t> query_request;
  std::atomic<std::uint32_t> query_waiting;
  std::atomic<std::uint32_t> query_command;
  alignas(16) std::byte query_arg[256];
};

struct alignas(cache_line) ClientCommon {
  std::atomic<std::uint32_t> service_bell;  // bumped by a client whose query finds the service thread asleep
};

inline constexpr std::size_t query_max_bytes = sizeof(ClientSlot::query_arg);

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

// Bounds every segment keeps within; validation refuses a header outside them.
inline constexpr std::uint32_t max_manifest_entries = 1024;
inline constexpr std::uint32_t max_slots = 64;
inline constexpr std::uint32_t max_ring_capacity = 4096;
inline constexpr std::uint32_t max_record_size = 4096;  // a ring slot: 16-byte header + argument
inline constexpr std::uint32_t max_mirror_bytes = 4096;
inline constexpr std::uint32_t max_mirror_rows = 4096;

struct LayoutParams {
  std::uint32_t manifest_count = 0;
  std::size_t mirror_bytes = 0;
  std::uint32_t mirror_rows = 1;  // the rows of history the mirror keeps
  std::uint32_t slot_count = 8;
  std::uint32_t ring_capacity = 64;
  std::size_t command_payload = 64;  // largest command argument
  std::size_t event_payload = 64;    // largest event argument
};

// Every offset and size of a segment, computed with overflow-checked 64-bit arithmetic from a
// few counts. Each process keeps its own copy: nothing here is read from shared memory again.
struct Layout {
  std::uint32_t manifest_count = 0, mirror_words = 0, mirror_rows = 0, slot_count = 0, ring_capacity = 0;
  std::uint32_t command_slot_size = 0, event_slot_size = 0;
  std::uint64_t manifest_offset = 0, mirror_offset = 0, server_slots_offset = 0, server_slot_stride = 0;
  std::uint64_t client_offset = 0, client_slots_offset = 0, client_slot_stride = 0, total_size = 0;

  // "" and `out` filled, or what is out of bounds.
  static std::string compute(const LayoutParams& p, Layout& out);
};

// A mapping seen through a Layout this process computed. Indices are the caller's to bound
// (every loop runs to the private slot_count).
class SegmentView {
 public:
  SegmentView() = default;
  SegmentView(void* memory, const Layout& layout) : base_(static_cast<std::byte*>(memory)), layout_(layout) {}

  const Layout& layout() const noexcept { return layout_; }
  std::byte* base() const noexcept { return base_; }
  SegmentHeader& header() const noexcept { return *reinterpret_cast<SegmentHeader*>(base_); }
  ManifestEntry* manifest() const noexcept {
    return reinterpret_cast<ManifestEntry*>(base_ + layout_.manifest_offset);
  }
  // Row `row`'s block of the state mirror (its sequence word, then mirror_words - 1 data words).
  std::atomic<std::uint64_t>* mirror(std::uint64_t row = 0) const noexcept {
    return reinterpret_cast<std::atomic<std::uint64_t>*>(base_ + layout_.mirror_offset) +
           (row % layout_.mirror_rows) * layout_.mirror_words;
  }
  ServerSlot& server_slot(std::uint32_t i) const noexcept {
    return *reinterpret_cast<ServerSlot*>(base_ + layout_.server_slots_offset +
                                          i * layout_.server_slot_stride);
  }
  std::byte* event_storage(std::uint32_t i) const noexcept {
    return reinterpret_cast<std::byte*>(&server_slot(i)) + sizeof(ServerSlot);
  }
  ClientCommon& client_common() const noexcept {
    return *reinterpret_cast<ClientCommon*>(base_ + layout_.client_offset);
  }
  ClientSlot& client_slot(std::uint32_t i) const noexcept {
    return *reinterpret_cast<ClientSlot*>(base_ + layout_.client_slots_offset +
                                          i * layout_.client_slot_stride);
  }
  std::byte* command_storage(std::uint32_t i) const noexcept {
    return reinterpret_cast<std::byte*>(&client_slot(i)) + sizeof(ClientSlot);
  }

 private:
  std::byte* base_ = nullptr;
  Layout layout_;
};

// Views of slot i's rings, for either side (each view keeps its own index privately):
// commands go client → server, events server → client.
inline detail::SpscRing command_ring(const SegmentView& v, std::uint32_t i) {
  return detail::SpscRing(&v.client_slot(i).commands_head, &v.server_slot(i).commands_tail,
                          v.command_storage(i), v.layout().ring_capacity, v.layout().command_slot_size);
}
inline detail::SpscRing event_ring(const SegmentView& v, std::uint32_t i) {
  return detail::SpscRing(&v.server_slot(i).events_head, &v.client_slot(i).events_tail, v.event_storage(i),
                          v.layout().ring_capacity, v.layout().event_slot_size);
}
// The same, owned (SpscRing cannot move): for views kept beside a Proxy's link or an Exporter.
inline std::unique_ptr<detail::SpscRing> make_command_ring(const SegmentView& v, std::uint32_t i) {
  return std::make_unique<detail::SpscRing>(&v.client_slot(i).commands_head, &v.server_slot(i).commands_tail,
                                            v.command_storage(i), v.layout().ring_capacity,
                                            v.layout().command_slot_size);
}
inline std::unique_ptr<detail::SpscRing> make_event_ring(const SegmentView& v, std::uint32_t i) {
  return std::make_unique<detail::SpscRing>(&v.server_slot(i).events_head, &v.client_slot(i).events_tail,
                                            v.event_storage(i), v.layout().ring_capacity,
                                            v.layout().event_slot_size);
}

// now − then for a time stamp read from the segment, whatever its bits: computed modulo 2^64
// (a stamp of INT64_MIN must not overflow); a stamp in the future gives a negative age.
inline std::int64_t elapsed(std::int64_t now, std::int64_t then) noexcept {
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(now) - static_cast<std::uint64_t>(then));
}

// Writes a fresh segment (state initializing, owner = this process) into zeroed memory.
void initialize(const SegmentView& v, std::string_view component, std::string_view interface,
                std::uint64_t interface_hash, std::int32_t owner_pid);

// Checks a mapping before anything else is read from it: "" if sound (and `out` holds its
// layout), else what is wrong, naming the values found and expected. Never reads outside
// [memory, memory + size), whatever the bytes; reads each header field once.
std::string validate(const void* memory, std::size_t size, Layout* out = nullptr);

// The state mirror: a ring of seqlocked rows (fence-free, as the state table's rows). Row n's
// block says 2n + 1 while it is written and 2n + 2 once it is. One writer, which keeps its count
// of rows written in its own memory (`rows`, incremented here).
void mirror_write(const SegmentView& v, std::uint64_t& rows, const void* data, std::size_t size) noexcept;
// The newest row (zeros before the first); false if the writer was mid-update on every try.
bool mirror_read(const SegmentView& v, void* data, std::size_t size) noexcept;
// Row `row` of the history: ok, or overwritten (more than mirror_rows rows ago, or being
// overwritten as it was read), or not written yet.
enum class RowRead { ok, overwritten, not_written };
RowRead mirror_read_row(const SegmentView& v, std::uint64_t row, void* data, std::size_t size) noexcept;

// Claims a free slot for `token` (pid for messages); returns its index or -1 if all are taken.
int claim_slot(const SegmentView& v, std::uint64_t token, std::int32_t pid, std::int64_t now) noexcept;
void release_slot(const SegmentView& v, std::uint32_t index, std::uint64_t token) noexcept;
// Frees the slots whose heartbeat is older than `timeout` at `now`; returns how many.
std::uint32_t reclaim_stale_slots(const SegmentView& v, std::int64_t now, std::int64_t timeout) noexcept;

// Whether a segment found under a name still has a live owner: its pid alive and started before
// the segment was made (a pid reused by a later process is not its owner), or (an owner in
// another pid namespace) its heartbeat moving within 200 ms. Reads only the header's first four
// fields, which never move between layout versions; a file that is not a bridge segment counts
// as owned (it is not ours to remove), one whose header was never written as not.
class ShmSegment;
bool segment_owner_alive(const ShmSegment& old) noexcept;

// A token no other claim on this host will use (pid, time and randomness).
std::uint64_t new_claim_token() noexcept;

}  // namespace saw::bridge
