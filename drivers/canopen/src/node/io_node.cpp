#include "saw/canopen/io_node.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace saw::canopen {

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
    if (find_mapped(c.pdos, PdoKind::rpdo, e.address).pdo < 0)
      fail("no RPDO maps its output " + to_string(e.address));
  for (const PdoEntry& e : c.inputs)
    if (find_mapped(c.pdos, PdoKind::tpdo, e.address).pdo < 0)
      fail("no TPDO maps its input " + to_string(e.address));
}

NodeSetup setup_of(const IoNodeConfig& c) {
  check(c);
  NodeSetup s{c.name, c.node, c.identity,
              node_writes(c.pdos, c.heartbeat_period, c.master_node, c.master_timeout, c.rpdo_deadline)};
  for (const SdoWrite& w : c.writes) s.writes.push_back({w, false});
  return s;
}

namespace {

NodeDriverOptions io_options() {
  NodeDriverOptions o;
  o.sdo_timeout = 500'000'000;
  o.sdo_capacity = 64;
  o.sdo_waits_for_reconfiguration = true;
  return o;
}

std::vector<NodeSpec> spec_of(const IoNodeConfig& c) {
  NodeSpec s;
  s.who = "I/O node '" + c.name + "'";
  s.node = c.node;
  s.pdos = c.pdos;
  s.heartbeat_timeout = c.heartbeat_timeout;
  s.writes = setup_of(c).writes;  // checks c first
  return {std::move(s)};
}

}  // namespace

IoNode::IoNode(can::Bus& bus, IoNodeConfig config)
    : NodeDriver(bus, io_options(), spec_of(config)), config_(std::move(config)) {
  for (const PdoEntry& e : config_.outputs) {
    const auto [pdo, slot] = find_mapped(config_.pdos, PdoKind::rpdo, e.address);
    outputs_.push_back({pdo, slot});
  }
  for (const PdoEntry& e : config_.inputs) {
    const auto [pdo, slot] = find_mapped(config_.pdos, PdoKind::tpdo, e.address);
    inputs_.push_back({pdo, slot});
  }
}

IoNode::~IoNode() = default;

Codec IoNode::set_output(std::size_t i, double value) noexcept {
  const MappedAt w = outputs_[i];
  const DataType t = config_.outputs[i].type;
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
  return rpdos(0)[static_cast<std::size_t>(w.pdo)].set_number(static_cast<std::size_t>(w.slot), n);
}

bool IoNode::input(std::size_t i, double& value) const noexcept {
  const MappedAt w = inputs_[i];
  const PdoUnpacker& p = tpdos(0)[static_cast<std::size_t>(w.pdo)];
  Number n;
  if (!p.has_data() || p.get_number(static_cast<std::size_t>(w.slot), n) != Codec::ok) return false;
  value = std::visit([](auto v) { return static_cast<double>(v); }, n);
  return true;
}

}  // namespace saw::canopen
