#include "saw/canopen/bus_master.hpp"

#include <stdexcept>
#include <string>

#include "bus_master_impl.hpp"
#include "saw/canopen/startup.hpp"

namespace saw::canopen {

using detail::Axis;
using detail::Slot;

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

NodeDriverOptions options_of(const BusMasterConfig& c) {
  NodeDriverOptions o;
  o.sdo_timeout = c.sdo_timeout;
  o.sdo_capacity = 256;
  o.sdo_queue = c.sdo_queue;
  o.max_frames = c.max_frames;
  o.log_emcy = true;
  return o;
}

// Every axis checked before the node driver routes any of them.
std::vector<NodeSpec> specs_of(const BusMasterConfig& config, const std::vector<AxisConfig>& axes) {
  if (axes.empty()) throw std::invalid_argument("a CANopen master needs at least one drive");
  if (axes.size() > 64) throw std::invalid_argument("at most 64 drives per bus");
  if (config.heartbeat_period > 0 && !valid_node_id(config.node))
    throw std::invalid_argument("the master's node-ID " + std::to_string(config.node) + " is not 1..127");
  std::vector<NodeSpec> specs;
  for (const AxisConfig& a : axes) {
    check(a);
    if (config.heartbeat_period > 0 && a.node == config.node)
      throw std::invalid_argument("drive '" + a.name + "': node " + std::to_string(config.node) +
                                  " is the master's own node-ID (its heartbeat)");
    specs.push_back({"drive '" + a.name + "' (node " + std::to_string(a.node) + ")", a.node, a.pdos,
                     a.heartbeat_timeout, startup_writes(a)});
  }
  return specs;
}

}  // namespace

BusMaster::BusMaster(can::Bus& bus, BusMasterConfig config, std::vector<AxisConfig> axes)
    : NodeDriver(bus, options_of(config), specs_of(config, axes)), impl_(std::make_unique<Impl>(config)) {
  impl_->axes.reserve(axes.size());
  // Slots by address: the mapping order is the layout's slot order.
  for (AxisConfig& c : axes) {
    Axis& a = impl_->axes.emplace_back(std::move(c), config);
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
  }
}

BusMaster::~BusMaster() = default;

const AxisConfig& BusMaster::axis(std::size_t i) const noexcept { return impl_->axes[i].config; }
const AxisFeedback& BusMaster::feedback(std::size_t i) const noexcept { return impl_->axes[i].feedback; }
const cia402::ControllerOutput& BusMaster::control(std::size_t i) const noexcept {
  return impl_->axes[i].control;
}
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
    PdoPacker& pdo = rpdos(i)[static_cast<std::size_t>(s.pdo)];
    const auto slot = static_cast<std::size_t>(s.slot);
    c = a.config.mode == cia402::cst ? pdo.set(slot, per_mille) : pdo.set(slot, counts);
  }
  if (c == Codec::ok) a.setpoint = si;
  return c;
}

void BusMaster::on_first_cycle(TimeNs now) noexcept {
  impl_->sync.start(now);
  impl_->heartbeat.start(now - impl_->config.heartbeat_period);  // the first one at once
}

void BusMaster::on_received(std::size_t i, TimeNs now) noexcept {
  Axis& a = impl_->axes[i];
  AxisFeedback& fb = a.feedback;
  fb.fresh = fresh(i);
  if (!fb.fresh) return;
  fb.last_received = last_received(i);
  fb.valid = tpdos_valid(i);
  const auto read = [&](Slot s, auto& out) {
    return s.mapped() &&
           tpdos(i)[static_cast<std::size_t>(s.pdo)].get(static_cast<std::size_t>(s.slot), out) == Codec::ok;
  };
  (void)read(a.statusword, fb.statusword);
  fb.state = cia402::decode_state(fb.statusword);
  (void)read(a.mode_display, fb.mode_display);
  (void)read(a.error_code, fb.error_code);
  const DriveUnits& u = a.config.units;
  if (read(a.position, fb.position_counts)) fb.position = u.counts_to_position(fb.position_counts);
  std::int32_t velocity = 0;
  if (read(a.velocity, velocity)) {
    fb.velocity = u.counts_to_velocity(velocity);
  } else if (a.previous_time != 0 && now > a.previous_time) {
    fb.velocity = u.counts_to_position(fb.position_counts - a.previous_counts) /
                  (static_cast<double>(now - a.previous_time) * 1e-9);
  }
  a.previous_time = now;
  a.previous_counts = fb.position_counts;
  std::int16_t torque = 0;
  if (read(a.torque, torque)) fb.torque = u.per_mille_to_effort(torque);
}

void BusMaster::before_rpdos(std::size_t i, TimeNs now) noexcept {
  Axis& a = impl_->axes[i];
  a.control = a.controller.update(a.feedback.statusword, now);
  for (const Slot& s : a.controlwords)
    (void)rpdos(i)[static_cast<std::size_t>(s.pdo)].set(static_cast<std::size_t>(s.slot),
                                                        a.control.controlword);
}

void BusMaster::after_rpdos(TimeNs now) noexcept {
  Impl& m = *impl_;
  // SYNC after every RPDO, so that each drive has its own before the SYNC that applies it. Half a
  // period of slack: a cycle that wakes a little early still sends its SYNC.
  if (const auto s = m.config.sync ? m.sync.poll(now + m.config.period / 2) : std::nullopt) {
    out(*s);
    ++counters_for_profile().syncs;
  }
  if (const auto h = m.heartbeat.poll(now, NmtState::operational)) {
    out(*h);
    ++counters_for_profile().heartbeats;
  }
}

void BusMaster::shut_down(std::uint16_t controlword, TimeNs now) noexcept {
  impl_->shut_down_controlword = controlword;
  NodeDriver::shut_down(now);
}

void BusMaster::before_shut_down(std::size_t i, TimeNs now) noexcept {
  Axis& a = impl_->axes[i];
  a.controller.set_target(cia402::Target::switch_on_disabled, now);
  for (const Slot& s : a.controlwords)
    (void)rpdos(i)[static_cast<std::size_t>(s.pdo)].set(static_cast<std::size_t>(s.slot),
                                                        impl_->shut_down_controlword);
}

can::Frame BusMaster::shut_down_sync() noexcept { return impl_->sync.extra(); }

void BusMaster::on_reconfigure(std::size_t i) noexcept { impl_->axes[i].feedback.valid = false; }

void BusMaster::on_reconfigured(std::size_t i, TimeNs now) noexcept {
  impl_->axes[i].feedback.watch_from = now;
}

}  // namespace saw::canopen
