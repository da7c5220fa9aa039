#include "saw/canopen/bus_master.hpp"

#include <stdexcept>
#include <string>

#include "bus_master_impl.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/log.hpp"

namespace saw::canopen {

namespace {
// The entries of the enabled mappings of one kind, in PDO order: the layouts' slot order.
std::vector<std::vector<ObjectAddress>> addresses(const AxisConfig& a, PdoKind kind) {
  std::vector<std::vector<ObjectAddress>> out;
  for (const PdoMapping& m : a.pdos) {
    if (!m.enabled || m.kind != kind) continue;
    auto& v = out.emplace_back();
    for (std::size_t i = 0; i < m.count; ++i) v.push_back(m.entries[i].address);
  }
  return out;
}
}  // namespace

BusMaster::BusMaster(can::Bus& bus, BusMasterConfig config, std::vector<AxisConfig> axes)
    : impl_(std::make_unique<Impl>(bus, config)) {
  if (axes.empty()) throw std::invalid_argument("a CANopen master needs at least one drive");
  if (axes.size() > 64) throw std::invalid_argument("at most 64 drives per bus");
  if (config.heartbeat_period > 0 && !valid_node_id(config.node))
    throw std::invalid_argument("the master's node-ID " + std::to_string(config.node) + " is not 1..127");
  impl_->axes.reserve(axes.size());
  for (std::size_t i = 0; i < axes.size(); ++i) {
    check(axes[i]);
    if (config.heartbeat_period > 0 && axes[i].node == config.node)
      throw std::invalid_argument("drive '" + axes[i].name + "': node " + std::to_string(config.node) +
                                  " is the master's own node-ID (its heartbeat)");
    const std::string who = "drive '" + axes[i].name + "' (node " + std::to_string(axes[i].node) + ")";
    Axis& a = impl_->axes.emplace_back(std::move(axes[i]), config);
    const auto node = a.config.node;
    const auto index = static_cast<std::uint8_t>(i);
    impl_->route(cob::emcy + node, {Route::emcy, index, 0}, who);
    impl_->route(cob::heartbeat + node, {Route::heartbeat, index, 0}, who);
    impl_->route(cob::sdo_tx + node, {Route::sdo_response, index, 0}, who);
    for (std::size_t p = 0; p < a.tpdos.size(); ++p)
      impl_->route(a.tpdos[p].layout().cob_id(), {Route::tpdo, index, static_cast<std::uint8_t>(p)}, who);
    impl_->heartbeats.watch(node, a.config.heartbeat_timeout);
    for (const StartupWrite& w : startup_writes(a.config)) {
      EncodedWrite e;
      e.address = w.write.address;
      e.size = size_of(w.write.type);
      e.optional = w.optional;
      if (e.size > e.bytes.size() ||
          encode(w.write.type, startup_value(w.write), std::span(e.bytes.data(), e.size)) != Codec::ok)
        throw std::invalid_argument(who + ": value " + std::to_string(w.write.value) + " does not fit " +
                                    to_string(w.write.address));
      a.writes.push_back(e);
    }
  }
  // Slots by address: the mapping order is the layout's slot order.
  for (Axis& a : impl_->axes) {
    const auto find = [](const std::vector<std::vector<ObjectAddress>>& pdos, ObjectAddress object) {
      for (std::size_t p = 0; p < pdos.size(); ++p)
        for (std::size_t s = 0; s < pdos[p].size(); ++s)
          if (pdos[p][s] == object) return Slot{static_cast<int>(p), static_cast<int>(s)};
      return Slot{};
    };
    const auto r = addresses(a.config, PdoKind::rpdo), t = addresses(a.config, PdoKind::tpdo);
    for (std::size_t p = 0; p < r.size(); ++p)
      for (std::size_t k = 0; k < r[p].size(); ++k) {
        const Slot slot{static_cast<int>(p), static_cast<int>(k)};
        if (r[p][k] == cia402::object::controlword) a.controlwords.push_back(slot);
        if (r[p][k] == mode_target(a.config.mode)) a.targets.push_back(slot);
      }
    a.statusword = find(t, cia402::object::statusword);
    a.position = find(t, cia402::object::position_actual_value);
    a.velocity = find(t, cia402::object::velocity_actual_value);
    a.torque = find(t, cia402::object::torque_actual_value);
    a.mode_display = find(t, cia402::object::modes_of_operation_display);
    a.error_code = find(t, cia402::object::error_code);
    a.feedback.has_mode_display = a.mode_display.mapped();
    a.feedback.has_error_code = a.error_code.mapped();
    a.feedback.has_velocity = a.velocity.mapped();
    a.feedback.has_torque = a.torque.mapped();
    if (a.tpdos.size() > 32) throw std::invalid_argument("at most 32 TPDOs per drive");
  }
  std::size_t rpdos = 0;
  for (const Axis& a : impl_->axes) rpdos += a.rpdos.size();
  // The RPDOs, an SDO request, SYNC, the heartbeat, room to spare, an NMT command per node
  // (shut_down()), and per drive a re-configuration's SDO request and NMT start.
  impl_->outbox.resize(rpdos + 5 + 3 * impl_->axes.size());
  impl_->inbox.resize(64);
}

BusMaster::~BusMaster() = default;

can::Bus& BusMaster::bus() noexcept { return impl_->bus; }
std::size_t BusMaster::size() const noexcept { return impl_->axes.size(); }
const AxisConfig& BusMaster::axis(std::size_t i) const noexcept { return impl_->axes[i].config; }
const AxisFeedback& BusMaster::feedback(std::size_t i) const noexcept { return impl_->axes[i].feedback; }
const AxisHealth& BusMaster::health(std::size_t i) const noexcept { return impl_->axes[i].health; }
const cia402::ControllerOutput& BusMaster::control(std::size_t i) const noexcept {
  return impl_->axes[i].control;
}
const MasterCounters& BusMaster::counters() const noexcept { return impl_->counters; }
SdoQueue& BusMaster::sdo_queue() noexcept { return impl_->queue; }
double BusMaster::setpoint(std::size_t i) const noexcept { return impl_->axes[i].setpoint; }

void BusMaster::set_state_target(std::size_t i, cia402::Target t, TimeNs now) noexcept {
  impl_->axes[i].controller.set_target(t, now);
}

void BusMaster::request_fault_reset(std::size_t i, TimeNs now) noexcept {
  impl_->axes[i].controller.request_fault_reset(now);
}

Codec BusMaster::set_setpoint(std::size_t i, double si) noexcept {
  Axis& a = impl_->axes[i];
  const DriveUnits& u = a.config.units;
  // The value in drive units first: nothing is packed unless it converts.
  std::int16_t per_mille = 0;
  std::int32_t counts = 0;
  Codec c = a.config.mode == cia402::cst   ? u.effort_to_per_mille(si, per_mille)
            : a.config.mode == cia402::csv ? u.velocity_to_counts(si, counts)
                                           : u.position_to_counts(si, counts);
  for (const Slot& s : a.targets) {
    if (c != Codec::ok) break;
    PdoPacker& pdo = a.rpdos[static_cast<std::size_t>(s.pdo)];
    const auto slot = static_cast<std::size_t>(s.slot);
    c = a.config.mode == cia402::cst ? pdo.set(slot, per_mille) : pdo.set(slot, counts);
  }
  if (c == Codec::ok) a.setpoint = si;
  return c;
}

void BusMaster::Impl::on_tpdo(Axis& a, std::size_t pdo, const can::Frame& f, TimeNs now) noexcept {
  if (a.tpdos[pdo].receive(f) != PdoReceive::ok) {
    ++a.health.bad_pdos;
    return;
  }
  a.tpdo_seen |= 1u << pdo;
  a.tpdo_this_cycle = true;
  a.feedback.last_received = now;
}

void BusMaster::Impl::on_emcy(Axis& a, const can::Frame& f) noexcept {
  const auto e = parse_emcy(f);
  if (!e) {
    ++counters.foreign_frames;
    return;
  }
  ++counters.emcy;
  a.health.error_register = e->error_register;
  if (e->is_reset()) return;
  ++a.health.emcy_count;
  a.health.last_emcy = e->code;
  // The names are literals: the RT log keeps their pointers. Whether it is an error or a warning
  // is the component's to say (the drive's statusword decides): here it is what was heard.
  saw::log(LogLevel::info, bus.name().c_str(), "EMCY from node {}: error code {:x} ({}), error register {:x}",
           unsigned{a.config.node}, unsigned{e->code}, emcy_name(e->code).data(),
           unsigned{e->error_register});
}

void BusMaster::Impl::on_frame(const can::Frame& f, TimeNs now) noexcept {
  if (!canopen_data_frame(f)) {
    ++counters.foreign_frames;
    return;
  }
  const RouteEntry& r = routes[f.can_id() & CAN_SFF_MASK];
  Axis* a = r.route == Route::none ? nullptr : &axes[r.axis];
  switch (r.route) {
    case Route::none:
      ++counters.foreign_frames;
      return;
    case Route::tpdo:
      return on_tpdo(*a, r.pdo, f, now);
    case Route::emcy:
      return on_emcy(*a, f);
    case Route::heartbeat:
      return heartbeats.on_frame(f, now);
    case Route::sdo_response:
      return a->sdo.on_frame(f, now);
  }
}

void BusMaster::Impl::heartbeat_events(TimeNs now) noexcept {
  while (const auto e = heartbeats.poll(now)) {
    Axis* a = by_node(e->node);
    if (a == nullptr) continue;
    AxisHealth& h = a->health;
    note_heartbeat(h, *e);
  }
  counters.heartbeat_events_dropped = heartbeats.dropped_events();
  // Monitoring starts with a node's first heartbeat (CiA 301); a node silent from the start is
  // lost all the same once its timeout has passed since our first cycle.
  for (Axis& a : axes) {
    if (a.health.heartbeat_seen || a.health.heartbeat_lost) continue;
    if (now - first_cycle > a.config.heartbeat_timeout) {
      a.health.heartbeat_lost = true;
      a.health.silent_for = now - first_cycle;
      ++a.health.heartbeat_losses;
    }
  }
}

void BusMaster::Impl::update_feedback(Axis& a, TimeNs now) noexcept {
  AxisFeedback& fb = a.feedback;
  fb.fresh = a.tpdo_this_cycle;
  a.tpdo_this_cycle = false;
  if (!fb.fresh) return;
  fb.valid = a.tpdo_seen == (a.tpdos.size() >= 32 ? ~0u : (1u << a.tpdos.size()) - 1);
  (void)a.read(a.statusword, fb.statusword);
  fb.state = cia402::decode_state(fb.statusword);
  (void)a.read(a.mode_display, fb.mode_display);
  (void)a.read(a.error_code, fb.error_code);
  const DriveUnits& u = a.config.units;
  if (a.read(a.position, fb.position_counts)) fb.position = u.counts_to_position(fb.position_counts);
  std::int32_t velocity = 0;
  if (a.read(a.velocity, velocity)) {
    fb.velocity = u.counts_to_velocity(velocity);
  } else if (a.previous_time != 0 && now > a.previous_time) {
    fb.velocity = u.counts_to_position(fb.position_counts - a.previous_counts) /
                  (static_cast<double>(now - a.previous_time) * 1e-9);
  }
  a.previous_time = now;
  a.previous_counts = fb.position_counts;
  std::int16_t torque = 0;
  if (a.read(a.torque, torque)) fb.torque = u.per_mille_to_effort(torque);
}

void BusMaster::receive(TimeNs now) noexcept {
  Impl& m = *impl_;
  if (!m.started) {
    m.started = true;
    m.first_cycle = now;
    m.sync.start(now);
    m.heartbeat.start(now - m.config.heartbeat_period);  // the first one at once
  }
  ++m.counters.cycles;
  std::size_t total = 0;
  while (total < m.config.max_frames) {
    const std::size_t want = std::min(m.inbox.size(), m.config.max_frames - total);
    const std::size_t n = m.bus.receive(std::span(m.inbox.data(), want));
    for (std::size_t i = 0; i < n; ++i) m.on_frame(m.inbox[i].frame, now);
    total += n;
    if (n < want) break;
  }
  if (total >= m.config.max_frames) ++m.counters.receive_limited;
  m.counters.frames_received += total;
  m.heartbeat_events(now);
  for (Axis& a : m.axes) m.update_feedback(a, now);
}

void BusMaster::Impl::service_sdo(TimeNs now) noexcept {
  if (sdo_axis < 0) {
    const SdoRequest* r = queue.front();
    if (r == nullptr) return;
    const SdoRequest request = *r;
    queue.pop();
    SdoReply reply;
    reply.tag = request.tag;
    Axis* a = by_node(request.node);
    const ObjectAddress address{request.index, request.subindex};
    const bool bad_size = request.write && (request.size == 0 || request.size > request.data.size());
    if (a == nullptr || bad_size) {
      reply.status = Status::invalid;
      (void)queue.reply(reply);
      return;
    }
    const bool begun = request.write
                           ? a->sdo.download(address, std::span(request.data.data(), request.size), now)
                           : a->sdo.upload(address, now);
    if (!begun) {
      reply.status = Status::busy;
      (void)queue.reply(reply);
      return;
    }
    sdo_axis = static_cast<int>(a - axes.data());
    sdo_tag = request.tag;
  }
  Axis& a = axes[static_cast<std::size_t>(sdo_axis)];
  while (const auto f = a.sdo.poll(now)) out(*f);
  if (a.sdo.busy()) return;
  const SdoResult& result = a.sdo.result();
  SdoReply reply;
  reply.tag = sdo_tag;
  reply.abort = static_cast<std::uint32_t>(result.abort);
  reply.remote = result.remote;
  if (result.status == SdoStatus::done) {
    ++counters.sdo_done;
    const auto data = a.sdo.data();
    reply.total = static_cast<std::uint32_t>(data.size());
    reply.size = static_cast<std::uint8_t>(std::min(data.size(), reply.data.size()));
    std::copy_n(data.begin(), reply.size, reply.data.begin());
  } else {
    ++counters.sdo_failed;
  }
  (void)queue.reply(reply);
  sdo_axis = -1;
}

void BusMaster::transmit(TimeNs now) noexcept {
  Impl& m = *impl_;
  m.out_count = 0;
  for (Axis& a : m.axes) {
    a.control = a.controller.update(a.feedback.statusword, now);
    for (const Slot& s : a.controlwords)
      (void)a.rpdos[static_cast<std::size_t>(s.pdo)].set(static_cast<std::size_t>(s.slot),
                                                         a.control.controlword);
    for (const PdoPacker& p : a.rpdos) m.out(p.frame());
  }
  m.service_sdo(now);
  for (Axis& a : m.axes) m.step_reconfiguration(a, now);
  // Half a period of slack: a cycle that wakes a little early still sends its SYNC.
  if (const auto s = m.config.sync ? m.sync.poll(now + m.config.period / 2) : std::nullopt) {
    m.out(*s);
    ++m.counters.syncs;
  }
  if (const auto h = m.heartbeat.poll(now, NmtState::operational)) {
    m.out(*h);
    ++m.counters.heartbeats;
  }
  const std::size_t sent = m.bus.send(std::span<const can::Frame>(m.outbox.data(), m.out_count));
  m.counters.frames_sent += sent;
  m.counters.send_refused += m.out_count - sent;
}

void BusMaster::shut_down(std::uint16_t controlword, TimeNs now) noexcept {
  Impl& m = *impl_;
  m.out_count = 0;
  for (Axis& a : m.axes) {
    a.controller.set_target(cia402::Target::switch_on_disabled, now);
    for (const Slot& s : a.controlwords)
      (void)a.rpdos[static_cast<std::size_t>(s.pdo)].set(static_cast<std::size_t>(s.slot), controlword);
    for (const PdoPacker& p : a.rpdos) m.out(p.frame());
  }
  m.out(m.sync.extra());
  ++m.counters.syncs;
  for (const Axis& a : m.axes) m.out(nmt_frame(NmtCommand::enter_pre_operational, a.config.node));
  const std::size_t sent = m.bus.send(std::span<const can::Frame>(m.outbox.data(), m.out_count));
  m.counters.frames_sent += sent;
  m.counters.send_refused += m.out_count - sent;
}

}  // namespace saw::canopen
