// Proxy: a local stand-in for a component exported by another process, and its resolver.
#pragma once

#include <atomic>
#include <deque>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "saw/bridge/layout.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/manager.hpp"

namespace saw::bridge {

struct ProxyOptions {
  TimeNs stale_after = 100'000'000;  // a heartbeat older than this: the server is gone
  TimeNs spin = 0;                   // qualified reads and update waits spin this long before sleeping
  TimeNs reconnect_poll = 10'000'000;
};

// A passive component with the exported interface, rebuilt from the segment's manifest:
// void/write commands go into this process's slot (an error, counted by the caller, when the
// ring is full or the server's heartbeat is older than `stale_after`); read commands copy from
// the state mirror; events arrive in the slot's event ring, drained by the client's thread.
// Its functions must be called from one thread (the slot's rings have one producer each).
//
// Reconnection: a non-RT monitor thread watches the server. When it is gone and a new server
// with the same name and interface is ready, the monitor maps it, claims a slot and offers the
// new link; the calling thread and the event-draining thread each switch to it at their next
// call (a pointer exchange: RT-safe). The old mapping is released once both have switched.
class Proxy : public Component {
 public:
  static constexpr TimeNs default_stale_after = ProxyOptions{}.stale_after;

  Proxy(ShmSegment segment, int slot_index, ProxyOptions options = {});
  ~Proxy() override;

  Mailbox* remote_events() noexcept override { return events_.get(); }
  bool is_remote() const noexcept override { return true; }
  // From the calling thread.
  bool server_alive() noexcept { return alive(link()); }
  // Commands refused because the slot's ring was full (the server is behind).
  std::uint64_t commands_refused() const noexcept {
    return commands_refused_.load(std::memory_order_relaxed);
  }
  // Times a new server was adopted (monitor's count).
  std::uint64_t reconnects() const noexcept { return reconnects_.load(std::memory_order_relaxed); }

  // Non-RT consumers (gateways, GUIs): sleeps until the server publishes a state row newer than
  // `seen` (a counter this call updates), or `timeout` passes. True if there is a new row.
  bool wait_for_update(std::uint32_t& seen, TimeNs timeout) noexcept;

 private:
  struct Link {
    ShmSegment segment;
    std::uint32_t slot;
    std::unique_ptr<SpscRing> commands, events;
  };
  Link& link() noexcept {
    if (offered_.load(std::memory_order_relaxed) != nullptr) adopt();
    return *link_;
  }
  void adopt() noexcept;
  bool alive(const Link& l) const noexcept;
  std::unique_ptr<Link> make_link(ShmSegment s, std::uint32_t slot);
  std::unique_ptr<Link> try_reconnect();
  void monitor();

  std::string path_;
  ProxyOptions options_;
  std::uint64_t interface_hash_ = 0;
  std::size_t mirror_bytes_ = 0;
  std::deque<std::string> type_names_;        // TypeInfo points into these
  std::vector<std::unique_ptr<Link>> links_;  // the monitor's; the newest is last
  Link* link_ = nullptr;                      // the calling thread's
  const Link* mailbox_on_ = nullptr;          // the monitor's: whose event ring the mailbox has
  std::atomic<Link*> offered_{nullptr};       // monitor → calling thread
  std::unique_ptr<Mailbox> events_;
  std::atomic<std::uint64_t> reconnects_{0}, commands_refused_{0};
  std::atomic<std::uint32_t> stop_{0};
  std::thread monitor_;
};

// Looks for "/saw.<name>": validates it, refuses a server whose heartbeat is stale, claims a
// slot. Connect then compares every type by name, size and layout version.
class ShmResolver : public RemoteResolver {
 public:
  explicit ShmResolver(ProxyOptions options = {}) : options_(options) {}
  std::unique_ptr<Component> resolve(std::string_view name) override;

 private:
  ProxyOptions options_;
};

}  // namespace saw::bridge
