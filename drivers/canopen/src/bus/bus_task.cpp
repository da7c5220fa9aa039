#include "saw/canopen/bus_task.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "saw/canopen/cob.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/detail/spsc_ring.hpp"

namespace saw::canopen {

// The framework's single-producer single-consumer ring (saw/detail/spsc_ring.hpp, stress-tested
// under ThreadSanitizer), typed: one trivially copyable value a slot.
template <class T>
struct BusPort::Ring {
  static_assert(std::is_trivially_copyable_v<T>);
  explicit Ring(std::size_t capacity) : ring(capacity, sizeof(T)) {}
  bool push(const T& v) noexcept {
    std::byte* slot = ring.try_reserve();
    if (slot == nullptr) return false;
    std::memcpy(slot, &v, sizeof(T));
    ring.commit();
    return true;
  }
  bool pop(T& v) noexcept {
    const std::byte* slot = ring.front();
    if (slot == nullptr) return false;
    std::memcpy(&v, slot, sizeof(T));
    ring.pop();
    return true;
  }
  detail::SpscRing ring;
};

BusPort::BusPort(BusTask& task, std::string client, std::vector<std::uint8_t> nodes, std::size_t ring)
    : task_(task),
      client_(std::move(client)),
      nodes_(std::move(nodes)),
      in_(std::make_unique<Ring<can::Received>>(ring)),
      out_(std::make_unique<Ring<can::Frame>>(ring)) {}

BusPort::~BusPort() = default;

std::size_t BusPort::receive(std::span<can::Received> out) noexcept {
  std::size_t n = 0;
  // Cycling: what the bus task routed here. Not cycling (this client's start-up): first what
  // the start-ups of the clients before it routed here (older than anything on the bus now, and
  // before this start-up's NMT reset, which ignores it), then the bus itself.
  while (n < out.size() && in_->pop(out[n])) ++n;
  if (n > 0 || cycling()) return n;
  return task_.receive_for(*this, out);
}

std::size_t BusPort::send(std::span<const can::Frame> frames) noexcept {
  if (!cycling()) return task_.bus().send(frames);
  std::size_t n = 0;
  while (n < frames.size() && out_->push(frames[n])) ++n;
  return n;
}

can::BusState BusPort::state() const noexcept { return cycling() ? task_.state() : task_.bus().state(); }
can::BusCounters BusPort::counters() const noexcept { return task_.bus().counters(); }
const std::string& BusPort::name() const noexcept { return task_.bus().name(); }

BusTask::BusTask(std::unique_ptr<can::Bus> bus, BusTaskConfig config)
    : bus_(std::move(bus)),
      config_(config),
      sync_(config.period),
      heartbeat_(config.node, config.heartbeat_period) {
  if (config.heartbeat_period > 0 && !valid_node_id(config.node))
    throw std::invalid_argument("the master's node-ID " + std::to_string(config.node) + " is not 1..127");
  if (config.period <= 0) throw std::invalid_argument("a CANopen bus task must be periodic");
  if (config.send_offset != 0 && (config.route_offset < 0 || config.route_offset + 1 >= config.send_offset ||
                                  config.send_offset >= config.period))
    throw std::invalid_argument(
        "the send phase must come after the route phase, with room for a client between, within the period");
  inbox_.resize(64);
  state_.store(bus_->state(), std::memory_order_release);
}

BusTask::~BusTask() {
  for (const auto& p : ports_) {
    if (p->shut_down_) continue;
    for (const std::uint8_t node : p->nodes_) {
      const can::Frame f = nmt_frame(NmtCommand::enter_pre_operational, node);
      (void)bus_->send(std::span(&f, 1));
    }
  }
}

BusPort& BusTask::attach(const std::string& client, std::span<const std::uint8_t> nodes,
                         std::span<const std::uint32_t> tpdos) {
  if (ports_.size() >= 254) throw std::invalid_argument("at most 254 components on one bus");
  const auto index = static_cast<std::uint8_t>(ports_.size() + 1);
  std::array<std::uint8_t, 2048> routes = routes_;
  const auto take = [&](std::uint32_t id, const std::string& what) {
    if (id >= routes.size())
      throw std::invalid_argument(client + ": " + what + " is not an 11-bit identifier");
    if (routes[id] != 0)
      throw std::invalid_argument(client + ": " + what + " (identifier " + std::to_string(id) + ") is '" +
                                  ports_[routes[id] - 1u]->client_ + "''s already on bus " + bus_->name());
    routes[id] = index;
  };
  for (const std::uint8_t node : nodes) {
    const std::string n = "node " + std::to_string(node);
    if (config_.heartbeat_period > 0 && node == config_.node)
      throw std::invalid_argument(client + ": " + n + " is the master's own node-ID (its heartbeat)");
    take(cob::heartbeat + node, n);
    take(cob::emcy + node, n + "'s EMCY");
    take(cob::sdo_tx + node, n + "'s SDO channel");
  }
  for (const std::uint32_t id : tpdos) take(id, "a TPDO");
  ports_.push_back(std::unique_ptr<BusPort>(
      new BusPort(*this, client, std::vector<std::uint8_t>(nodes.begin(), nodes.end()), config_.ring)));
  routes_ = routes;
  return *ports_.back();
}

// A client's start-up reads the bus itself; a frame of another client's node (an EMCY or a
// heartbeat of a node configured by an earlier start-up) goes to that client's in-ring, as the
// cycle would route it, for its first cycle: not lost because another component was configuring
// its own nodes. No thread cycles during the start-ups (every component's start-up runs on the
// set-up thread before any task's thread is created), so this thread is then the only producer
// (and, for its own port, consumer) of every ring; the creation of the bus task's and the
// clients' threads happens after, and synchronizes with their start, so what is pushed here
// (ring indices, slots, counters) is seen by the bus task (the rings' producer from then on) and
// the clients (their consumers). Frames for no client are the caller's, as before.
std::size_t BusTask::receive_for(BusPort& port, std::span<can::Received> out) noexcept {
  std::size_t kept = 0;
  while (kept == 0) {
    const std::size_t n = bus_->receive(out);
    if (n == 0) break;
    for (std::size_t i = 0; i < n; ++i) {
      const can::Received r = out[i];
      const std::uint8_t route = canopen_data_frame(r.frame) ? routes_[r.frame.can_id() & CAN_SFF_MASK] : 0;
      BusPort* owner = route == 0 ? nullptr : ports_[route - 1u].get();
      if (owner == nullptr || owner == &port) {
        out[kept++] = r;
        continue;
      }
      if (!owner->in_->push(r)) {
        ++counters_.dropped;
        owner->dropped_.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }
  return kept;
}

void BusTask::flush(std::span<const can::Frame> frames) noexcept {
  if (frames.empty()) return;
  const std::size_t sent = bus_->send(frames);
  counters_.frames_sent += sent;
  counters_.send_refused += frames.size() - sent;
}

BusTaskCounters BusTask::counters() const noexcept {
  BusTaskCounters c = counters_;
  c.phase_skips = phase_skips_.load(std::memory_order_relaxed);
  return c;
}

// The acquire of the flag pairs with the release of the phase that held it last: what that
// phase wrote (the bus's own state, the counters, the sync and heartbeat producers) is seen by
// this one, whichever thread it runs in.
bool BusTask::enter() noexcept {
  if (!busy_.exchange(true, std::memory_order_acquire)) return true;
  phase_skips_.fetch_add(1, std::memory_order_relaxed);
  return false;
}

void BusTask::leave(BusTaskCounters* seen) noexcept {
  state_.store(bus_->state(), std::memory_order_release);
  if (seen != nullptr) *seen = counters();
  busy_.store(false, std::memory_order_release);
}

// Frames in: each to the client whose node sent it.
bool BusTask::route(TimeNs, BusTaskCounters* seen) noexcept {
  if (!enter()) return false;
  ++counters_.cycles;
  std::size_t total = 0;
  while (total < config_.max_frames) {
    const std::size_t want = std::min(inbox_.size(), config_.max_frames - total);
    const std::size_t n = bus_->receive(std::span(inbox_.data(), want));
    for (std::size_t i = 0; i < n; ++i) {
      const can::Received& r = inbox_[i];
      const std::uint8_t route = canopen_data_frame(r.frame) ? routes_[r.frame.can_id() & CAN_SFF_MASK] : 0;
      if (route == 0) {
        ++counters_.foreign_frames;
        continue;
      }
      BusPort& p = *ports_[route - 1u];
      if (!p.in_->push(r)) {
        ++counters_.dropped;
        p.dropped_.fetch_add(1, std::memory_order_relaxed);
      }
    }
    total += n;
    if (n < want) break;
  }
  if (total >= config_.max_frames) ++counters_.receive_limited;
  counters_.frames_received += total;
  leave(seen);
  return true;
}

// Frames out: every client's, in the order it queued them, then SYNC and the heartbeat.
bool BusTask::send(TimeNs now, BusTaskCounters* seen) noexcept {
  if (!enter()) return false;
  if (!started_) {
    started_ = true;
    sync_.start(now);
    heartbeat_.start(now - config_.heartbeat_period);  // the first one at once
  }
  out_count_ = 0;
  for (const auto& p : ports_) {
    can::Frame f;
    while (p->out_->pop(f)) {
      outbox_[out_count_++] = f;
      if (out_count_ == outbox_.size() - 2) {
        flush(std::span<const can::Frame>(outbox_.data(), out_count_));
        out_count_ = 0;
      }
    }
  }
  // Half a period of slack: a cycle that wakes a little early still sends its SYNC.
  if (const auto s = sync_.poll(now + config_.period / 2)) {
    outbox_[out_count_++] = *s;
    ++counters_.syncs;
  }
  if (const auto h = heartbeat_.poll(now, NmtState::operational)) {
    outbox_[out_count_++] = *h;
    ++counters_.heartbeats;
  }
  flush(std::span<const can::Frame>(outbox_.data(), out_count_));
  leave(seen);
  return true;
}

}  // namespace saw::canopen
