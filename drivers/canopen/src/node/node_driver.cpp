#include "saw/canopen/node_driver.hpp"

#include <algorithm>
#include <stdexcept>

#include "saw/canopen/cob.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/log.hpp"

namespace saw::canopen {

NodeDriver::Node::Node(NodeSpec s, const NodeDriverOptions& o)
    : spec(std::move(s)),
      sdo(SdoClientConfig{SdoChannel::of_node(spec.node), o.sdo_timeout, o.sdo_capacity}) {
  for (const PdoMapping& m : spec.pdos) {
    if (!m.enabled) continue;
    if (m.kind == PdoKind::rpdo)
      rpdos.emplace_back(m);
    else
      tpdos.emplace_back(m);
  }
}

NodeDriver::NodeDriver(can::Bus& bus, NodeDriverOptions options, std::vector<NodeSpec> nodes)
    : bus_(bus), options_(options), routes_(CAN_SFF_MASK + 1), queue_(options.sdo_queue) {
  by_node_.fill(-1);
  nodes_.reserve(nodes.size());
  for (NodeSpec& spec : nodes) {
    const std::string who = spec.who;
    Node& n = nodes_.emplace_back(std::move(spec), options_);
    const std::uint8_t id = n.spec.node;
    const auto index = static_cast<std::uint8_t>(nodes_.size() - 1);
    if (n.tpdos.size() > 32) throw std::invalid_argument(who + ": at most 32 TPDOs");
    route(cob::emcy + id, {Route::emcy, index, 0}, who);
    route(cob::heartbeat + id, {Route::heartbeat, index, 0}, who);
    route(cob::sdo_tx + id, {Route::sdo_response, index, 0}, who);
    for (std::size_t p = 0; p < n.tpdos.size(); ++p)
      route(n.tpdos[p].layout().cob_id(), {Route::tpdo, index, static_cast<std::uint8_t>(p)}, who);
    by_node_[id & 0x7F] = static_cast<std::int8_t>(index);
    heartbeats_.watch(id, n.spec.heartbeat_timeout);
    for (const StartupWrite& w : n.spec.writes) {
      Encoded e;
      e.address = w.write.address;
      e.size = size_of(w.write.type);
      e.optional = w.optional;
      if (e.size > e.bytes.size() ||
          encode(w.write.type, startup_value(w.write), std::span(e.bytes.data(), e.size)) != Codec::ok)
        throw std::invalid_argument(who + ": value " + std::to_string(w.write.value) + " does not fit " +
                                    to_string(w.write.address));
      n.writes.push_back(e);
    }
  }
  std::size_t rpdos = 0;
  for (const Node& n : nodes_) rpdos += n.rpdos.size();
  // The RPDOs, an SDO request, SYNC, the heartbeat, room to spare, an NMT command per node
  // (shut_down()), and per node a re-configuration's SDO request and NMT start.
  outbox_.resize(rpdos + 5 + 3 * nodes_.size());
  inbox_.resize(64);
}

NodeDriver::~NodeDriver() = default;

void NodeDriver::route(std::uint32_t id, RouteEntry e, const std::string& who) {
  if (routes_[id].route != Route::none)
    throw std::invalid_argument(who + ": identifier " + std::to_string(id) + " is used twice on this bus");
  routes_[id] = e;
}

bool NodeDriver::tpdos_valid(std::size_t i) const noexcept {
  const Node& n = nodes_[i];
  return n.tpdo_seen == (n.tpdos.size() >= 32 ? ~0u : (1u << n.tpdos.size()) - 1);
}

void NodeDriver::on_emcy(Node& n, const can::Frame& f) noexcept {
  const auto e = parse_emcy(f);
  if (!e) {
    ++counters_.foreign_frames;
    return;
  }
  ++counters_.emcy;
  n.health.error_register = e->error_register;
  switch (emcy_severity(*e)) {
    case EmcySeverity::reset:
      ++n.emcys.resets;
      return;
    case EmcySeverity::warning:
      ++n.emcys.warnings;
      n.emcys.last_warning = *e;
      break;
    case EmcySeverity::fault:
      ++n.emcys.faults;
      n.emcys.last_fault = *e;
      break;
  }
  ++n.health.emcy_count;
  n.health.last_emcy = e->code;
  // The names are literals: the RT log keeps their pointers. Whether it is an error or a warning
  // is the profile's to say (a drive's statusword decides): here it is what was heard.
  if (options_.log_emcy)
    saw::log(LogLevel::info, bus_.name().c_str(),
             "EMCY from node {}: error code {:x} ({}), error register {:x}", unsigned{n.spec.node},
             unsigned{e->code}, emcy_name(e->code).data(), unsigned{e->error_register});
}

void NodeDriver::on_frame(const can::Frame& f, TimeNs now) noexcept {
  if (!canopen_data_frame(f)) {
    ++counters_.foreign_frames;
    return;
  }
  const RouteEntry& r = routes_[f.can_id() & CAN_SFF_MASK];
  if (r.route == Route::none) {
    ++counters_.foreign_frames;
    return;
  }
  Node& n = nodes_[r.node];
  switch (r.route) {
    case Route::none:
      return;
    case Route::tpdo:
      if (n.tpdos[r.pdo].receive(f) != PdoReceive::ok) {
        ++n.health.bad_pdos;
        return;
      }
      n.tpdo_seen |= 1u << r.pdo;
      n.fresh = true;
      n.last_received = now;
      return;
    case Route::emcy:
      return on_emcy(n, f);
    case Route::heartbeat:
      return heartbeats_.on_frame(f, now);
    case Route::sdo_response:
      return n.sdo.on_frame(f, now);
  }
}

void NodeDriver::heartbeat_events(TimeNs now) noexcept {
  while (const auto e = heartbeats_.poll(now)) {
    const int i = index_of(e->node);
    if (i >= 0) note_heartbeat(nodes_[static_cast<std::size_t>(i)].health, *e);
  }
  counters_.heartbeat_events_dropped = heartbeats_.dropped_events();
  // Monitoring starts with a node's first heartbeat (CiA 301); a node silent from the start is
  // lost all the same once its timeout has passed since our first cycle.
  for (Node& n : nodes_) {
    if (n.health.heartbeat_seen || n.health.heartbeat_lost) continue;
    if (now - first_cycle_ > n.spec.heartbeat_timeout) {
      n.health.heartbeat_lost = true;
      n.health.silent_for = now - first_cycle_;
      ++n.health.heartbeat_losses;
    }
  }
}

void NodeDriver::receive(TimeNs now) noexcept {
  if (!started_) {
    started_ = true;
    first_cycle_ = now;
    on_first_cycle(now);
  }
  ++counters_.cycles;
  for (Node& n : nodes_) n.fresh = false;
  std::size_t total = 0;
  while (total < options_.max_frames) {
    const std::size_t want = std::min(inbox_.size(), options_.max_frames - total);
    const std::size_t got = bus_.receive(std::span(inbox_.data(), want));
    for (std::size_t i = 0; i < got; ++i) on_frame(inbox_[i].frame, now);
    total += got;
    if (got < want) break;
  }
  if (total >= options_.max_frames) ++counters_.receive_limited;
  counters_.frames_received += total;
  heartbeat_events(now);
  for (std::size_t i = 0; i < nodes_.size(); ++i) on_received(i, now);
}

void NodeDriver::service_sdo(TimeNs now) noexcept {
  if (sdo_node_ < 0) {
    const SdoRequest* r = queue_.front();
    if (r == nullptr) return;
    const int i = index_of(r->node);
    if (options_.sdo_waits_for_reconfiguration && i >= 0 &&
        nodes_[static_cast<std::size_t>(i)].reconfig.state == Reconfiguration::State::busy)
      return;  // the node's SDO client is its re-configuration's
    const SdoRequest request = *r;
    queue_.pop();
    SdoReply reply;
    reply.tag = request.tag;
    const ObjectAddress address{request.index, request.subindex};
    const bool bad_size = request.write && (request.size == 0 || request.size > request.data.size());
    if (i < 0 || bad_size) {
      reply.status = Status::invalid;
      (void)queue_.reply(reply);
      return;
    }
    Node& n = nodes_[static_cast<std::size_t>(i)];
    const bool begun = request.write
                           ? n.sdo.download(address, std::span(request.data.data(), request.size), now)
                           : n.sdo.upload(address, now);
    if (!begun) {
      reply.status = Status::busy;
      (void)queue_.reply(reply);
      return;
    }
    sdo_node_ = i;
    sdo_tag_ = request.tag;
  }
  Node& n = nodes_[static_cast<std::size_t>(sdo_node_)];
  while (const auto f = n.sdo.poll(now)) out(*f);
  if (n.sdo.busy()) return;
  const SdoResult& result = n.sdo.result();
  SdoReply reply;
  reply.tag = sdo_tag_;
  reply.abort = static_cast<std::uint32_t>(result.abort);
  reply.remote = result.remote;
  if (result.status == SdoStatus::done) {
    ++counters_.sdo_done;
    const auto data = n.sdo.data();
    reply.total = static_cast<std::uint32_t>(data.size());
    reply.size = static_cast<std::uint8_t>(std::min(data.size(), reply.data.size()));
    std::copy_n(data.begin(), reply.size, reply.data.begin());
  } else {
    ++counters_.sdo_failed;
  }
  (void)queue_.reply(reply);
  sdo_node_ = -1;
}

void NodeDriver::reconfigure(std::size_t i, TimeNs now) noexcept {
  Node& n = nodes_[i];
  n.reconfig = {};
  n.reconfig.state = Reconfiguration::State::busy;
  n.next = 0;
  n.started = n.starting = false;
  n.since = now;
  n.tpdo_seen = 0;  // its TPDOs, once it sends them again, decide
  on_reconfigure(i);
}

void NodeDriver::step_reconfiguration(std::size_t i, TimeNs now) noexcept {
  Node& n = nodes_[i];
  if (n.reconfig.state != Reconfiguration::State::busy) return;
  if (n.starting) {
    if (n.health.nmt_state == NmtState::operational) {
      n.reconfig.state = Reconfiguration::State::done;
      on_reconfigured(i, now);
    } else if (now - n.since > 2'000'000'000) {
      n.reconfig.state = Reconfiguration::State::failed;  // no operational heartbeat within 2 s
    }
    return;
  }
  if (sdo_node_ == static_cast<int>(i)) return;  // a runtime transfer on its channel: next cycle
  if (n.started && !n.sdo.busy()) {
    const Encoded& w = n.writes[n.next];
    const SdoResult& r = n.sdo.result();
    const bool missing = r.abort == SdoAbort::no_object || r.abort == SdoAbort::no_subindex;
    if (r.status != SdoStatus::done && !(w.optional && missing)) {
      n.reconfig.state = Reconfiguration::State::failed;
      n.reconfig.object = w.address;
      n.reconfig.abort = r.abort;
      return;
    }
    ++n.next;
    n.started = false;
  }
  if (!n.started && n.next < n.writes.size()) {
    const Encoded& w = n.writes[n.next];
    n.started = n.sdo.download(w.address, std::span(w.bytes.data(), w.size), now);
  }
  while (const auto f = n.sdo.poll(now)) out(*f);
  if (!n.started && n.next >= n.writes.size()) {
    out(nmt_frame(NmtCommand::start, n.spec.node));
    n.starting = true;
    n.since = now;
  }
}

void NodeDriver::send() noexcept {
  const std::size_t sent = bus_.send(std::span<const can::Frame>(outbox_.data(), out_count_));
  counters_.frames_sent += sent;
  counters_.send_refused += out_count_ - sent;
}

void NodeDriver::transmit(TimeNs now) noexcept {
  out_count_ = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    before_rpdos(i, now);
    for (const PdoPacker& p : nodes_[i].rpdos) out(p.frame());
  }
  service_sdo(now);
  for (std::size_t i = 0; i < nodes_.size(); ++i) step_reconfiguration(i, now);
  after_rpdos(now);
  send();
}

void NodeDriver::shut_down(TimeNs now) noexcept {
  out_count_ = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    before_shut_down(i, now);
    for (const PdoPacker& p : nodes_[i].rpdos) out(p.frame());
  }
  out(shut_down_sync());
  ++counters_.syncs;
  for (const Node& n : nodes_) out(nmt_frame(NmtCommand::enter_pre_operational, n.spec.node));
  send();
}

}  // namespace saw::canopen
