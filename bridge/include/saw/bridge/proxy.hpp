// Proxy: a local stand-in for a component exported by another process, and its resolver.
#pragma once

#include <deque>
#include <memory>
#include <string>

#include "saw/bridge/layout.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/manager.hpp"

namespace saw::bridge {

// A passive component with the exported interface, rebuilt from the segment's manifest:
// void/write commands go into this process's slot (an error, counted by the caller, when the
// ring is full or the server's heartbeat is older than `stale_after`); read commands copy from
// the state mirror; events arrive in the slot's event ring, drained by the client's thread.
// Its functions must be called from one thread (the slot's rings have one producer each).
class Proxy : public Component {
 public:
  static constexpr TimeNs default_stale_after = 100'000'000;

  Proxy(ShmSegment segment, int slot_index, TimeNs stale_after = default_stale_after);
  ~Proxy() override;

  Mailbox* remote_events() noexcept override { return events_.get(); }
  bool is_remote() const noexcept override { return true; }
  bool server_alive() const noexcept;

 private:
  ShmSegment segment_;
  int slot_;
  TimeNs stale_after_;
  std::deque<std::string> type_names_;  // TypeInfo points into these
  std::unique_ptr<SpscRing> commands_;
  std::unique_ptr<Mailbox> events_;
  std::size_t mirror_bytes_ = 0;
};

// Looks for "/saw.<name>": validates it, refuses a server whose heartbeat is stale, claims a slot.
class ShmResolver : public RemoteResolver {
 public:
  std::unique_ptr<Component> resolve(std::string_view name) override;
};

}  // namespace saw::bridge
