#include "saw/canopen/axis.hpp"

#include <stdexcept>
#include <string>

#include "saw/canopen/cob.hpp"

namespace saw::canopen {
namespace {

bool maps(const AxisConfig& a, PdoKind kind, ObjectAddress object) {
  return find_mapped(a.pdos, kind, object).pdo >= 0;
}

}  // namespace

ObjectAddress mode_target(cia402::Mode mode) noexcept {
  using namespace cia402;
  return mode == csv   ? object::target_velocity
         : mode == cst ? object::target_torque
                       : object::target_position;
}

void check(const AxisConfig& a) {
  const std::string who = "drive '" + a.name + "' (node " + std::to_string(a.node) + ")";
  const auto fail = [&](const std::string& what) { throw std::invalid_argument(who + ": " + what); };
  if (!valid_node_id(a.node)) fail("node-ID must be 1..127");
  if (a.mode != cia402::csp && a.mode != cia402::csv && a.mode != cia402::cst)
    fail("mode must be cyclic synchronous position, velocity or torque (csp, csv, cst)");
  try {
    a.units.check();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  constexpr TimeNs ms = 1'000'000;
  if (a.heartbeat_period < ms || a.heartbeat_period > 65535 * ms)
    fail("heartbeat period must be 1 ms to 65.535 s (0x1017 holds milliseconds)");
  if (a.heartbeat_timeout <= a.heartbeat_period) fail("heartbeat timeout must be above the heartbeat period");
  if (!valid_node_id(a.master_node)) fail("the master's node-ID must be 1..127");
  if (a.master_node == a.node) fail("the master's node-ID is the drive's");
  if (a.master_timeout < 0 || a.master_timeout > 65535 * ms)
    fail("the master's heartbeat timeout must be 0 to 65.535 s (0x1016 holds milliseconds)");
  if (static_cast<std::int16_t>(a.abort_connection) < 0 || static_cast<std::int16_t>(a.abort_connection) > 3)
    fail("abort connection option code (0x6007) must be 0..3");
  for (const PdoMapping& m : a.pdos) {
    try {
      canopen::check(m);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  }
  for (std::size_t i = 0; i < a.pdos.size(); ++i)
    for (std::size_t j = i + 1; j < a.pdos.size(); ++j) {
      const PdoMapping &p = a.pdos[i], &q = a.pdos[j];
      if (p.kind == q.kind && p.number == q.number)
        fail(std::string(to_string(p.kind)) + std::to_string(p.number) + " is configured twice");
      if (p.enabled && q.enabled && p.cob_id == q.cob_id)
        fail("two PDOs on identifier " + std::to_string(p.cob_id));
    }
  const auto need = [&](PdoKind kind, ObjectAddress object, const char* name) {
    if (!maps(a, kind, object))
      fail(std::string("no ") + std::string(to_string(kind)) + " maps " + name + " (" + to_string(object) +
           ")");
  };
  need(PdoKind::rpdo, cia402::object::controlword, "the controlword");
  need(PdoKind::rpdo, mode_target(a.mode), "the mode's target");
  need(PdoKind::tpdo, cia402::object::statusword, "the statusword");
  need(PdoKind::tpdo, cia402::object::position_actual_value, "the position actual value");
}

void note_heartbeat(AxisHealth& h, const HeartbeatEvent& e) noexcept {
  h.nmt_state = e.state;
  switch (e.kind) {
    case HeartbeatEvent::Kind::appeared:
    case HeartbeatEvent::Kind::back:
      h.heartbeat_seen = true;
      h.heartbeat_lost = false;
      break;
    case HeartbeatEvent::Kind::lost:
      h.heartbeat_lost = true;
      h.silent_for = e.silent_for;
      ++h.heartbeat_losses;
      break;
    case HeartbeatEvent::Kind::boot_up:
      ++h.boot_ups;
      break;
    case HeartbeatEvent::Kind::state_changed:
      break;
  }
}

}  // namespace saw::canopen
