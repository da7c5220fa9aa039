// CanopenArm's construction, interfaces, start-up and state commands (the cycle: arm_cycle.cpp).
#include "saw/canopen/canopen_arm.hpp"

#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>

#include "saw/canopen/pdo_text.hpp"
#include "saw/log.hpp"

namespace saw::canopen {
namespace {

std::vector<AxisConfig> axes_of(const CanopenArmConfig& c) {
  std::vector<AxisConfig> axes;
  for (const JointConfig& j : c.joints) {
    AxisConfig a;
    a.name = j.name;
    a.node = j.node;
    a.mode = c.mode;
    a.units = j.units;
    a.pdos = j.pdos.empty() ? default_pdo_mappings(c.mode, j.node) : j.pdos;
    a.heartbeat_period = c.heartbeat_period;
    a.heartbeat_timeout = c.heartbeat_timeout;
    a.master_node = c.master_node;
    a.master_timeout = c.master_heartbeat_timeout;
    a.abort_connection = c.abort_connection;
    a.rpdo_deadline = {c.rpdo_deadline, j.rpdo_deadline_unwritable};
    a.identity = j.identity;
    a.writes = j.writes;
    axes.push_back(std::move(a));
  }
  return axes;
}

}  // namespace

CanopenArmConfig checked(CanopenArmConfig c, const TaskConfig& task) {
  const TimeNs period = task.period.count();
  if (period <= 0) throw std::invalid_argument("a CANopen component's task must be periodic");
  if (c.joints.empty() || c.joints.size() > JointState::max_joints)
    throw std::invalid_argument("a CANopen component has 1 to " + std::to_string(JointState::max_joints) +
                                " joints");
  if (c.feedback_timeout == 0) c.feedback_timeout = std::max<TimeNs>(10 * period, 10'000'000);
  if (c.feedback_timeout < 2 * period)
    throw std::invalid_argument("feedback_timeout must be at least two periods");
  c.rpdo_deadline = resolve_rpdo_deadline(c.rpdo_deadline, period);
  if (c.chain && c.chain->joints.size() != c.joints.size())
    throw std::invalid_argument("the chain has " + std::to_string(c.chain->joints.size()) +
                                " joints, the arm " + std::to_string(c.joints.size()) + " drives");
  for (JointConfig& j : c.joints) {
    if (!(j.min < j.max)) throw std::invalid_argument("joint '" + j.name + "': min must be below max");
    if (!(j.max_velocity > 0))
      throw std::invalid_argument("joint '" + j.name + "': max_velocity must be above 0");
    if (j.max_torque == 0) j.max_torque = j.units.rated_torque * j.units.effort_per_motor_torque();
    if (!(j.max_torque > 0) || !(j.following_error >= 0))
      throw std::invalid_argument("joint '" + j.name +
                                  "': max_torque and following_error must not be negative");
    if (j.name.size() > JointState::max_name)
      throw std::invalid_argument("joint '" + j.name + "': a name has at most 31 characters");
  }
  const auto axes = axes_of(c);
  for (std::size_t i = 0; i < axes.size(); ++i) {
    check(axes[i]);
    for (std::size_t k = 0; k < i; ++k)
      if (axes[k].node == axes[i].node)
        throw std::invalid_argument("joints '" + axes[k].name + "' and '" + axes[i].name + "' share node " +
                                    std::to_string(axes[i].node));
  }
  return c;
}

CanopenArm::CanopenArm(std::string name, TaskConfig task, CanopenArmConfig config)
    : CanopenArm(std::move(name), task, Checked<CanopenArmConfig>{checked(std::move(config), task)},
                 nullptr) {}

CanopenArm::CanopenArm(std::string name, TaskConfig task, CanopenArmConfig config, can::Bus& bus)
    : CanopenArm(std::move(name), task, Checked<CanopenArmConfig>{checked(std::move(config), task)}, &bus) {}

namespace {

// The contract the base runs for it: drives, whose safe state is disabled (quick stop on a fault).
DeviceConfig contract_of(const CanopenArmConfig& c) {
  DeviceConfig d;
  d.settings() = c.contract;
  d.interface_name = c.interface_name;
  d.safe_state = SafeState::drive_disabled;
  d.cartesian = d.servo_cf = c.chain.has_value();
  d.servo_jp = d.servo_jv = d.servo_jf = true;  // one of them per mode: accepts() says which
  // The enable's own limits say more and come first: each transition (cia402::Progress::timeout,
  // with the state), the fault resets, the mode display (transition_timeout after switched on).
  d.enable_timeout = 4 * c.transition_timeout;
  for (const JointConfig& j : c.joints)
    d.joints.push_back({j.name, j.min, j.max, j.max_velocity, j.max_torque});
  return d;
}

}  // namespace

namespace {

// A caller's bus (tests) is known by its address: two of them may share a name. A shared bus's
// master heartbeat is its bus task's: the drives' consumers watch that one.
BusLink link_of(const std::string& name, const CanopenArmConfig& c, TimeNs period, can::Bus* bus) {
  if (bus != nullptr) return link_callers_bus(*bus, name);
  std::vector<std::uint8_t> nodes;
  std::vector<std::uint32_t> tpdos;
  for (const AxisConfig& a : axes_of(c)) {
    nodes.push_back(a.node);
    for (const PdoMapping& m : a.pdos)
      if (m.enabled && m.kind == PdoKind::tpdo) tpdos.push_back(m.cob_id & CAN_SFF_MASK);
  }
  return link_bus(c.bus, name, period, nodes, tpdos);
}

CanopenArmConfig with_bus_task(CanopenArmConfig c, const BusLink& l) {
  if (l.shared()) {
    c.master_node = l.task->config().node;
    c.master_heartbeat_period = l.task->config().heartbeat_period;
    c.master_heartbeat_timeout = l.task->config().heartbeat_timeout;
  }
  return c;
}

}  // namespace

CanopenArm::CanopenArm(std::string name, TaskConfig task, Checked<CanopenArmConfig> config, can::Bus* bus)
    // A client of a canopen_bus runs between its two phases (its offset given one if none).
    : Device(name, bus == nullptr ? client_task(config.value.bus, name, task) : task,
             contract_of(config.value)),
      config_(std::move(config.value)),
      n_(config_.joints.size()),
      link_(link_of(this->name(), config_, task.period.count(), bus)),
      bus_(*link_.bus) {
  config_ = with_bus_task(std::move(config_), link_);
  BusMasterConfig m;
  m.period = task.period.count();
  m.controller.transition_timeout = config_.transition_timeout;
  m.node = config_.master_node;
  m.heartbeat_period = config_.master_heartbeat_period;
  if (link_.shared()) {  // the bus task sends SYNC and the master's heartbeat
    m.sync = false;
    m.heartbeat_period = 0;
  }
  master_ = std::make_unique<BusMaster>(bus_, m, axes_of(config_));
  std::vector<const char*> names;  // the joints' names, in the master's keeping (they do not move)
  for (std::size_t i = 0; i < master_->size(); ++i) names.push_back(master_->axis(i).name.c_str());
  monitor_ = std::make_unique<NodeMonitor>(*master_, this->name().c_str(), std::move(names));
  if (config_.chain) kinematics_ = std::make_unique<ChainKinematics>(*config_.chain);
  setpoint_js_.size = static_cast<std::uint32_t>(n_);
  for (std::size_t i = 0; i < n_; ++i) (void)setpoint_js_.set_name(i, config_.joints[i].name);
  status_.joints = static_cast<std::uint8_t>(n_);
  status_.shared_bus = link_.shared() ? 1 : 0;
  provide_interfaces();
}

CanopenArm::~CanopenArm() = default;

void CanopenArm::provide_interfaces() {
  auto& st = state_table();
  crtk::provide(crtk_interface(), joint_space::setpoint_js, st, &setpoint_js_);
  auto& c = provide("canopen");
  c.add_command_read("status", st.add_column("status", &status_, ColumnUse::summary));
  c.add_command_qualified_read<SdoRequest, SdoReply>("sdo", [this](const SdoRequest& q, SdoReply& r) {
    r = master_->sdo_queue().transfer(q, 1'000'000'000);
  });
}

void CanopenArm::open() {
  if (config_.master_heartbeat_timeout == 0)
    saw::log(LogLevel::warning, name().c_str(),
             "master_heartbeat.timeout is 0: the drives do not watch this master; killed, it leaves them as "
             "they are");
  const std::vector<AxisConfig> axes = axes_of(config_);
  StartupSequence sequence(bus_, axes, config_.startup);
  run_startup(sequence, config_.startup_pause);
  // A drive that cannot watch the RPDO deadline still runs: said once, so nobody counts on it.
  if (config_.rpdo_deadline == 0)
    saw::log(LogLevel::warning, name().c_str(),
             "rpdo_deadline is off: a starved master whose bus still sends SYNC leaves the drives applying "
             "their last setpoints");
  for (std::size_t i = 0; i < axes.size(); ++i)
    for (const std::uint16_t n : unwatched_rpdos(axes[i].pdos, axes[i].rpdo_deadline, sequence.written()[i]))
      saw::log(LogLevel::warning, name().c_str(),
               "{} (node {}): RPDO{} has no deadline ({:x}:05 not in its EDS or refused): the drive does not "
               "see a starved master there",
               config_.joints[i].name.c_str(), unsigned{config_.joints[i].node}, unsigned{n},
               0x1400u + n - 1);
}

void CanopenArm::target_all(cia402::Target t) noexcept {
  for (std::size_t i = 0; i < n_; ++i) master_->set_state_target(i, t, now());
}

bool CanopenArm::accepts(ServoMode m) const noexcept {
  switch (config_.mode) {
    case cia402::csp:
      return m == ServoMode::jp;
    case cia402::csv:
      return m == ServoMode::jv;
    default:
      return m == ServoMode::jf || m == ServoMode::cf;
  }
}

void CanopenArm::enter_safe_state(SafeReason why) {
  enable_sent_ = operation_sent_ = false;
  // A fault the base raised itself, in CANopen's terms where there are some: a stale command,
  // an enable that never completed. Any other (a throw caught) keeps none: the base's reason says it.
  if (why == SafeReason::fault && reason_ == FaultReason::none) {
    const FaultOrigin origin = device_status().origin;
    if (origin == FaultOrigin::command_timeout)
      reason_ = FaultReason::command_stale;
    else if (origin == FaultOrigin::enable_timeout)
      reason_ = FaultReason::enable_timeout;
  }
  switch (why) {
    case SafeReason::fault:  // on the drives' quick-stop ramp; the master goes on watching
      return target_all(cia402::Target::quick_stop);
    case SafeReason::disable:  // power off; the master goes on (an enable walks them back)
      return target_all(cia402::Target::switch_on_disabled);
    case SafeReason::stop:
    case SafeReason::start_failed:
      break;
  }
  // The master stops: nothing will send the drives anything again. Zero torque or velocity,
  // disable voltage taken at one last SYNC, and the nodes out of operational. On a shared bus
  // every task's thread has ended by now (or none started): the port sends them at once.
  if (link_.shared()) link_.port->set_cycling(false);
  if (config_.mode != cia402::csp)
    for (std::size_t i = 0; i < n_; ++i) (void)master_->set_setpoint(i, 0.0);
  master_->shut_down(cia402::controlword::disable_voltage_command, now());
  if (link_.shared()) link_.port->mark_shut_down();
}

}  // namespace saw::canopen
