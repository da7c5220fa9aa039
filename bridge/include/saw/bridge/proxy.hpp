// Proxy: a local stand-in for a component exported by another process, and its resolver.
#pragma once

#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "saw/bridge/layout.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/manager.hpp"

namespace saw::bridge {

struct ProxyOptions {
  TimeNs stale_after = 100'000'000;    // a heartbeat older than this: the server is gone
  TimeNs spin = 0;                     // qualified reads and update waits spin this long before sleeping
  TimeNs reconnect_poll = 10'000'000;  // also how often this client's slot heartbeat is refreshed
};

// A passive component with the exported interface, rebuilt from the segment's manifest:
// void/write commands go into this process's slot (an error, counted by the caller, when the
// ring is full or the server's heartbeat is older than `stale_after`); read commands copy from
// the state mirror; events arrive in the slot's event ring, drained by the client's thread.
// Its commands and events must be used from one thread (the slot's rings have one producer and
// one consumer); reads from any.
//
// The server's region is mapped read-only; the layout is the one this process validated when
// it attached, never re-read. A monitor thread (non-RT) refreshes the slot's heartbeat, and
// watches the server: when it is gone, or has freed our slot (we stalled past its client
// timeout), and a server with the same name and interface is ready, the monitor maps it, claims
// a slot and offers the new link; the calling thread and the event-draining thread each switch
// to it at their next call (a pointer exchange: RT-safe). The old mapping is released once both
// have switched. Nothing escapes the monitor: a segment it cannot use leaves the proxy
// disconnected, with the reason in last_error().
class Proxy : public Component {
 public:
  static constexpr TimeNs default_stale_after = ProxyOptions{}.stale_after;

  // `segment` validated into `layout`, slot `slot_index` claimed with `token`.
  Proxy(ShmSegment segment, const Layout& layout, int slot_index, std::uint64_t token,
        ProxyOptions options = {});
  ~Proxy() override;

  bool is_remote() const noexcept override { return true; }
  // From the calling thread.
  bool server_alive() noexcept { return alive(link()); }
  // Commands refused because the slot's ring was full (the server is behind).
  std::uint64_t commands_refused() const noexcept {
    return commands_refused_.load(std::memory_order_relaxed);
  }
  // Times a new server was adopted (monitor's count).
  std::uint64_t reconnects() const noexcept { return reconnects_.load(std::memory_order_relaxed); }
  // Why the monitor could not reconnect the last time it tried ("" if it never failed).
  std::string last_error() const;

  // Non-RT consumers (gateways, GUIs): sleeps until the server publishes a state row newer than
  // `seen` (a counter this call updates), or `timeout` passes. True if there is a new row.
  bool wait_for_update(std::uint32_t& seen, TimeNs timeout) noexcept;

  // The state mirror's history, for a non-RT consumer that must not skip rows (a gateway's
  // full-rate topics). A row is a block of mirror_bytes(): the row's time (8 bytes), then each
  // read's value at its offset (read_slice). From the calling thread.
  std::uint64_t rows_written() noexcept;  // by the current server (0 while disconnected)
  std::uint32_t history_rows() const noexcept { return history_rows_; }
  std::size_t mirror_bytes() const noexcept { return mirror_bytes_; }
  // Row `row` into `block` (mirror_bytes() bytes); disconnected when the server is gone.
  enum class RowStatus { ok, overwritten, not_written, disconnected };
  RowStatus read_row(std::uint64_t row, void* block) noexcept;
  // Where read command `name`'s value sits in a row's block (offset, size); false if no such read.
  bool read_slice(std::string_view name, std::uint32_t& offset, std::uint32_t& size) const noexcept;

 private:
  detail::Mailbox* remote_events() noexcept override { return events_.get(); }

  struct Link {
    ShmSegment segment;
    SegmentView view;
    std::uint32_t slot;
    std::uint64_t token;
    std::unique_ptr<detail::SpscRing> commands, events;
    ClientSlot& client() const noexcept { return view.client_slot(slot); }
    ServerSlot& server() const noexcept { return view.server_slot(slot); }
  };
  Link& link() noexcept {
    if (offered_.load(std::memory_order_relaxed) != nullptr) adopt();
    return *link_;
  }
  void adopt() noexcept;
  bool alive(const Link& l) const noexcept;
  static std::unique_ptr<Link> make_link(ShmSegment s, const Layout& layout, std::uint32_t slot,
                                         std::uint64_t token);
  std::unique_ptr<Link> try_reconnect();
  void monitor();
  void monitor_once();
  void set_error(const std::string& why) noexcept;
  void build_interface(const Link& l);
  Status query(std::uint32_t index, std::uint32_t arg_size, std::uint32_t result_size, const void* q,
               void* r) noexcept;

  std::string path_;
  ProxyOptions options_;
  std::uint64_t interface_hash_ = 0, incarnation_ = 0;
  std::size_t mirror_bytes_ = 0;
  std::uint32_t history_rows_ = 1;
  struct Slice {
    std::string name;
    std::uint32_t offset, size;
  };
  std::vector<Slice> slices_;                 // the read commands' places in a row
  std::deque<std::string> type_names_;        // TypeInfo points into these
  std::vector<std::unique_ptr<Link>> links_;  // the monitor's; the newest is last
  Link* link_ = nullptr;                      // the calling thread's
  const Link* mailbox_on_ = nullptr;          // the monitor's: whose event ring the mailbox has
  std::atomic<Link*> offered_{nullptr};       // monitor → calling thread
  std::unique_ptr<detail::Mailbox> events_;
  std::atomic<std::uint64_t> reconnects_{0}, commands_refused_{0};
  std::atomic<std::uint32_t> stop_{0};
  mutable std::mutex error_mutex_;  // non-RT: the monitor writes, anyone reads
  std::string error_;
  std::thread monitor_;
};

// Looks for "/saw.<name>": validates it, refuses a server whose heartbeat is stale, claims a
// slot. Connect then compares every type by name, size and layout version.
// A manager asks its resolvers in the order they were added, and the first that finds a name
// makes its proxy: proxies with other options (a bounded spin) need a manager of their own.
class ShmResolver : public RemoteResolver {
 public:
  explicit ShmResolver(ProxyOptions options = {}) : options_(options) {}
  std::unique_ptr<Component> resolve(std::string_view name) override;

 private:
  ProxyOptions options_;
};

// Maps "/name" read-only, validates it and makes its client region writable. Throws
// BridgeError (absent) or returns the reason it is refused in `why`.
ShmSegment attach_validated(const std::string& path, Layout& layout, std::string& why);

}  // namespace saw::bridge
