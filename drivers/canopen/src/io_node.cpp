#include "saw/canopen/io_node.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "saw/canopen/cob.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/log.hpp"

namespace saw::canopen {
namespace {

// Where an object sits: which enabled PDO of its kind, which slot; pdo < 0: not mapped.
struct Where {
  int pdo = -1, slot = -1;
};

Where find(const std::vector<PdoMapping>& pdos, PdoKind kind, ObjectAddress a) {
  int n = 0;
  for (const PdoMapping& m : pdos) {
    if (!m.enabled || m.kind != kind) continue;
    for (std::size_t s = 0; s < m.count; ++s)
      if (m.entries[s].address == a) return {n, static_cast<int>(s)};
    ++n;
  }
  return {};
}

}  // namespace

void check(const IoNodeConfig& c) {
  const std::string who = "I/O node '" + c.name + "' (node " + std::to_string(c.node) + ")";
  const auto fail = [&](const std::string& what) { throw std::invalid_argument(who + ": " + what); };
  if (!valid_node_id(c.node)) fail("node-ID must be 1..127");
  constexpr TimeNs ms = 1'000'000;
  if (c.heartbeat_period < ms || c.heartbeat_period > 65535 * ms)
    fail("heartbeat period must be 1 ms to 65.535 s (0x1017 holds milliseconds)");
  if (c.heartbeat_timeout <= c.heartbeat_period) fail("heartbeat timeout must be above the heartbeat period");
  if (!valid_node_id(c.master_node) || c.master_node == c.node)
    fail("the master's node-ID must be 1..127 and not the node's");
  if (c.master_timeout < 0 || c.master_timeout > 65535 * ms)
    fail("the master's heartbeat timeout must be 0 to 65.535 s (0x1016 holds milliseconds)");
  std::size_t tpdos = 0;
  for (const PdoMapping& m : c.pdos) {
    try {
      canopen::check(m);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
    if (m.enabled && m.kind == PdoKind::tpdo) ++tpdos;
  }
  if (tpdos > 32) fail("at most 32 TPDOs");
  for (std::size_t i = 0; i < c.pdos.size(); ++i)
    for (std::size_t j = i + 1; j < c.pdos.size(); ++j) {
      const PdoMapping &p = c.pdos[i], &q = c.pdos[j];
      if (p.kind == q.kind && p.number == q.number)
        fail(std::string(to_string(p.kind)) + std::to_string(p.number) + " is configured twice");
      if (p.enabled && q.enabled && p.cob_id == q.cob_id)
        fail("two PDOs on identifier " + std::to_string(p.cob_id));
    }
  for (const PdoEntry& e : c.outputs)
    if (find(c.pdos, PdoKind::rpdo, e.address).pdo < 0)
      fail("no RPDO maps its output " + to_string(e.address));
  for (const PdoEntry& e : c.inputs)
    if (find(c.pdos, PdoKind::tpdo, e.address).pdo < 0)
      fail("no TPDO maps its input " + to_string(e.address));
}

NodeSetup setup_of(const IoNodeConfig& c) {
  check(c);
  NodeSetup s{c.name, c.node, c.identity,
              node_writes(c.pdos, c.heartbeat_period, c.master_node, c.master_timeout, c.rpdo_deadline)};
  for (const SdoWrite& w : c.writes) s.writes.push_back({w, false});
  return s;
}

// One start-up write, encoded at construction: the cycle only sends it.
struct Encoded {
  ObjectAddress address;
  std::array<std::uint8_t, 8> bytes{};
  std::size_t size = 0;
  bool optional = false;
};

struct IoNode::Impl {
  Impl(can::Bus& b, IoNodeConfig c)
      : bus(b),
        config(std::move(c)),
        sdo(SdoClientConfig{SdoChannel::of_node(config.node), 500'000'000, 64}) {}
  can::Bus& bus;
  IoNodeConfig config;
  std::vector<PdoPacker> rpdos;
  std::vector<PdoUnpacker> tpdos;
  std::vector<Where> outputs, inputs;
  HeartbeatConsumer heartbeats;
  SyncProducer sync{1'000'000};  // shut_down()'s one SYNC
  AxisHealth health;
  IoEmcys emcys;
  std::uint32_t tpdo_seen = 0;
  bool fresh = false;
  TimeNs last_received = 0, first_cycle = -1;
  std::uint64_t foreign = 0;
  std::array<can::Received, 32> inbox{};
  std::vector<can::Frame> outbox;
  // Re-configuration (a node that rebooted).
  SdoClient sdo;
  std::vector<Encoded> writes;
  Reconfiguration reconfig;
  std::size_t next = 0;
  bool started = false, starting = false;
  TimeNs since = 0;

  void step_reconfiguration(std::size_t& n, TimeNs now) noexcept;
  // Runtime SDO.
  SdoQueue queue{16};
  bool transfer = false;  // a runtime transfer holds the SDO client
  std::uint32_t tag = 0;
  void service_sdo(std::size_t& n, TimeNs now) noexcept;

  void on_frame(const can::Frame& f, TimeNs now) noexcept;
  void heartbeat_events(TimeNs now) noexcept;
  void send(std::size_t n) noexcept { (void)bus.send(std::span<const can::Frame>(outbox.data(), n)); }
};

IoNode::IoNode(can::Bus& bus, IoNodeConfig config) : impl_(std::make_unique<Impl>(bus, std::move(config))) {
  Impl& m = *impl_;
  check(m.config);
  for (const PdoMapping& p : m.config.pdos) {
    if (!p.enabled) continue;
    if (p.kind == PdoKind::rpdo)
      m.rpdos.emplace_back(p);
    else
      m.tpdos.emplace_back(p);
  }
  for (const PdoEntry& e : m.config.outputs)
    m.outputs.push_back(find(m.config.pdos, PdoKind::rpdo, e.address));
  for (const PdoEntry& e : m.config.inputs) m.inputs.push_back(find(m.config.pdos, PdoKind::tpdo, e.address));
  m.heartbeats.watch(m.config.node, m.config.heartbeat_timeout);
  for (const StartupWrite& w : setup_of(m.config).writes) {
    Encoded e;
    e.address = w.write.address;
    e.size = size_of(w.write.type);
    e.optional = w.optional;
    if (e.size > e.bytes.size() ||
        encode(w.write.type, startup_value(w.write), std::span(e.bytes.data(), e.size)) != Codec::ok)
      throw std::invalid_argument("I/O node '" + m.config.name + "': value " + std::to_string(w.write.value) +
                                  " does not fit " + to_string(w.write.address));
    m.writes.push_back(e);
  }
  // The RPDOs, then room for an SDO request and NMT start (or a SYNC and NMT at the end).
  m.outbox.resize(m.rpdos.size() + 4);
}

IoNode::~IoNode() = default;

const IoNodeConfig& IoNode::config() const noexcept { return impl_->config; }
bool IoNode::fresh() const noexcept { return impl_->fresh; }
TimeNs IoNode::last_received() const noexcept { return impl_->last_received; }
const AxisHealth& IoNode::health() const noexcept { return impl_->health; }
std::uint64_t IoNode::foreign_frames() const noexcept { return impl_->foreign; }
const IoEmcys& IoNode::emcys() const noexcept { return impl_->emcys; }
bool IoNode::valid() const noexcept {
  const std::size_t n = impl_->tpdos.size();
  return impl_->tpdo_seen == (n >= 32 ? ~0u : (1u << n) - 1);
}

void IoNode::Impl::on_frame(const can::Frame& f, TimeNs now) noexcept {
  if (!canopen_data_frame(f)) {
    ++foreign;
    return;
  }
  const std::uint32_t id = f.can_id() & CAN_SFF_MASK;
  const std::uint8_t node = config.node;
  if (id == cob::heartbeat + node) return heartbeats.on_frame(f, now);
  if (id == cob::emcy + node) {
    const auto e = parse_emcy(f);
    if (!e) {
      ++foreign;
      return;
    }
    health.error_register = e->error_register;
    switch (emcy_severity(*e)) {
      case EmcySeverity::reset:
        ++emcys.resets;
        return;
      case EmcySeverity::warning:
        ++emcys.warnings;
        emcys.last_warning = *e;
        break;
      case EmcySeverity::fault:
        ++emcys.faults;
        emcys.last_fault = *e;
        break;
    }
    ++health.emcy_count;
    health.last_emcy = e->code;
    return;
  }
  for (std::size_t p = 0; p < tpdos.size(); ++p) {
    if (tpdos[p].layout().cob_id() != id) continue;
    if (tpdos[p].receive(f) != PdoReceive::ok) {
      ++health.bad_pdos;
      return;
    }
    tpdo_seen |= 1u << p;
    fresh = true;
    last_received = now;
    return;
  }
  if (id == cob::sdo_tx + node) return sdo.on_frame(f, now);
  ++foreign;
}

void IoNode::Impl::heartbeat_events(TimeNs now) noexcept {
  while (const auto e = heartbeats.poll(now)) {
    note_heartbeat(health, *e);
  }
  // A node silent from the start is lost all the same once its timeout has passed.
  if (!health.heartbeat_seen && !health.heartbeat_lost && now - first_cycle > config.heartbeat_timeout) {
    health.heartbeat_lost = true;
    health.silent_for = now - first_cycle;
    ++health.heartbeat_losses;
  }
}

void IoNode::receive(TimeNs now) noexcept {
  Impl& m = *impl_;
  if (m.first_cycle < 0) m.first_cycle = now;
  m.fresh = false;
  for (std::size_t total = 0; total < 256;) {
    const std::size_t n = m.bus.receive(m.inbox);
    for (std::size_t i = 0; i < n; ++i) m.on_frame(m.inbox[i].frame, now);
    total += n;
    if (n < m.inbox.size()) break;
  }
  m.heartbeat_events(now);
}

Codec IoNode::set_output(std::size_t i, double value) noexcept {
  Impl& m = *impl_;
  const Where w = m.outputs[i];
  const DataType t = m.config.outputs[i].type;
  if (!std::isfinite(value)) return Codec::invalid;
  Number n;
  switch (type_class(t)) {
    case TypeClass::real:
      n = value;
      break;
    case TypeClass::signed_integer:
      if (std::abs(value) > 9.2e18) return value > 0 ? Codec::too_high : Codec::too_low;
      n = static_cast<std::int64_t>(std::llround(value));
      break;
    default:
      if (value < -0.5) return Codec::too_low;
      if (value > 1.8e19) return Codec::too_high;
      n = static_cast<std::uint64_t>(std::llround(value));
      break;
  }
  return m.rpdos[static_cast<std::size_t>(w.pdo)].set_number(static_cast<std::size_t>(w.slot), n);
}

bool IoNode::input(std::size_t i, double& value) const noexcept {
  const Impl& m = *impl_;
  const Where w = m.inputs[i];
  const PdoUnpacker& p = m.tpdos[static_cast<std::size_t>(w.pdo)];
  Number n;
  if (!p.has_data() || p.get_number(static_cast<std::size_t>(w.slot), n) != Codec::ok) return false;
  value = std::visit([](auto v) { return static_cast<double>(v); }, n);
  return true;
}

void IoNode::transmit(TimeNs now) noexcept {
  Impl& m = *impl_;
  std::size_t n = 0;
  for (const PdoPacker& p : m.rpdos) m.outbox[n++] = p.frame();
  m.step_reconfiguration(n, now);
  m.service_sdo(n, now);
  m.send(n);
}

SdoQueue& IoNode::sdo_queue() noexcept { return impl_->queue; }

void IoNode::Impl::service_sdo(std::size_t& n, TimeNs now) noexcept {
  if (!transfer) {
    if (reconfig.state == Reconfiguration::State::busy) return;  // the client is the re-configuration's
    const SdoRequest* r = queue.front();
    if (r == nullptr) return;
    const SdoRequest request = *r;
    queue.pop();
    SdoReply reply;
    reply.tag = request.tag;
    const ObjectAddress address{request.index, request.subindex};
    const bool bad = request.node != config.node ||
                     (request.write && (request.size == 0 || request.size > request.data.size()));
    const bool begun =
        !bad && (request.write ? sdo.download(address, std::span(request.data.data(), request.size), now)
                               : sdo.upload(address, now));
    if (!begun) {
      reply.status = bad ? Status::invalid : Status::busy;
      (void)queue.reply(reply);
      return;
    }
    transfer = true;
    tag = request.tag;
  }
  while (const auto f = sdo.poll(now))
    if (n < outbox.size()) outbox[n++] = *f;
  if (sdo.busy()) return;
  const SdoResult& result = sdo.result();
  SdoReply reply;
  reply.tag = tag;
  reply.abort = static_cast<std::uint32_t>(result.abort);
  reply.remote = result.remote;
  if (result.status == SdoStatus::done) {
    const auto data = sdo.data();
    reply.total = static_cast<std::uint32_t>(data.size());
    reply.size = static_cast<std::uint8_t>(std::min(data.size(), reply.data.size()));
    std::copy_n(data.begin(), reply.size, reply.data.begin());
  }
  (void)queue.reply(reply);
  transfer = false;
}

void IoNode::reconfigure(TimeNs now) noexcept {
  Impl& m = *impl_;
  m.reconfig = {};
  m.reconfig.state = Reconfiguration::State::busy;
  m.next = 0;
  m.started = m.starting = false;
  m.since = now;
  m.tpdo_seen = 0;  // its TPDOs, once it sends them again, decide
}

const Reconfiguration& IoNode::reconfiguration() const noexcept { return impl_->reconfig; }

void IoNode::Impl::step_reconfiguration(std::size_t& n, TimeNs now) noexcept {
  if (reconfig.state != Reconfiguration::State::busy || transfer) return;  // a runtime transfer first
  if (starting) {
    if (health.nmt_state == NmtState::operational)
      reconfig.state = Reconfiguration::State::done;
    else if (now - since > 2'000'000'000)
      reconfig.state = Reconfiguration::State::failed;  // no operational heartbeat within 2 s
    return;
  }
  if (started && !sdo.busy()) {
    const Encoded& w = writes[next];
    const SdoResult& r = sdo.result();
    const bool missing = r.abort == SdoAbort::no_object || r.abort == SdoAbort::no_subindex;
    if (r.status != SdoStatus::done && !(w.optional && missing)) {
      reconfig.state = Reconfiguration::State::failed;
      reconfig.object = w.address;
      reconfig.abort = r.abort;
      return;
    }
    ++next;
    started = false;
  }
  if (!started && next < writes.size()) {
    const Encoded& w = writes[next];
    started = sdo.download(w.address, std::span(w.bytes.data(), w.size), now);
  }
  while (const auto f = sdo.poll(now))
    if (n < outbox.size()) outbox[n++] = *f;
  if (!started && next >= writes.size() && n < outbox.size()) {
    outbox[n++] = nmt_frame(NmtCommand::start, config.node);
    starting = true;
    since = now;
  }
}

void IoNode::shut_down(TimeNs) noexcept {
  Impl& m = *impl_;
  std::size_t n = 0;
  for (const PdoPacker& p : m.rpdos) m.outbox[n++] = p.frame();
  m.outbox[n++] = m.sync.extra();
  m.outbox[n++] = nmt_frame(NmtCommand::enter_pre_operational, m.config.node);
  m.send(n);
}

}  // namespace saw::canopen
