// CanopenIo: the start-up, the cycle and the safe state of a generic I/O node (RT code in the cycle).
#include "saw/canopen/canopen_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>
#include <variant>

#include "saw/canopen/emcy.hpp"
#include "saw/log.hpp"

namespace saw::canopen {
namespace {

CanopenIoConfig checked(CanopenIoConfig c, const TaskConfig& task) {
  const TimeNs period = task.period.count();
  if (period <= 0) throw std::invalid_argument("a CANopen component's task must be periodic");
  if (c.channels.empty() || c.channels.size() > JointState::max_joints)
    throw std::invalid_argument("a CANopen I/O component has 1 to 8 channels");
  if (c.feedback_timeout == 0) c.feedback_timeout = std::max<TimeNs>(10 * period, 10'000'000);
  c.rpdo_deadline = resolve_rpdo_deadline(c.rpdo_deadline, period);
  c.node.rpdo_deadline.time = c.rpdo_deadline;
  if (c.eds) c.node.rpdo_deadline.unwritable = rpdos_without_event_timer(*c.eds, c.node.pdos);
  c.node.outputs.clear();
  c.node.inputs.clear();
  for (const IoChannel& ch : c.channels) {
    if (!ch.output) throw std::invalid_argument("channel '" + ch.name + "': no output object");
    if (!(ch.scale != 0) || !std::isfinite(ch.scale) || !(ch.min < ch.max) || ch.safe < ch.min ||
        ch.safe > ch.max)
      throw std::invalid_argument("channel '" + ch.name +
                                  "': scale must not be 0, min below max, safe within");
    c.node.outputs.push_back(*ch.output);
    if (ch.input) c.node.inputs.push_back(*ch.input);
  }
  return c;
}

DeviceConfig contract_of(const CanopenIoConfig& c) {
  DeviceConfig d;
  d.interface_name = c.interface_name;
  d.safe_state = SafeState::hold;
  d.cartesian = d.servo_cf = false;
  d.servo_jp = true;
  d.settings() = c.contract;
  for (const IoChannel& ch : c.channels) d.joints.push_back({ch.name, ch.min, ch.max, ch.max_velocity});
  return d;
}

// CiA 401's error behaviour for a channel whose output is a CiA 401 output object: what the node
// puts out by itself on a device failure or a communication loss (its heartbeat consumer fires
// when the controller dies). Analog 0x6411:n: error mode 0x6443:n = 1 (take the error value),
// error value 0x6444:n (INTEGER32); digital 8-bit 0x6200:n: error mode mask 0x6206:n = 0xFF (every
// bit), error value 0x6207:n. The value is the channel's safe value in the output's counts.
// Vendors type these objects differently (a strict node aborts a write of another length): with an
// EDS each object's type is the EDS's, and an object the EDS does not list is not written.
struct ErrorWrites {
  std::vector<SdoWrite> writes;
  std::vector<const IoChannel*> unsupported;  // no CiA 401 output object: no standard error value
  std::vector<std::pair<const IoChannel*, ObjectAddress>> unlisted;  // the EDS lacks the object
};

// `value` as a write of `a`, typed by the EDS when there is one; a type that cannot hold it (or is
// no integer of up to 32 bits) is refused naming the channel.
void add_error_write(ErrorWrites& out, const IoChannel& ch, const Eds* eds, ObjectAddress a,
                     DataType standard, double value, const char* what) {
  DataType type = standard;
  if (eds) {
    const EdsEntry* e = eds->find(a);
    if (!e) {
      out.unlisted.emplace_back(&ch, a);
      return;
    }
    type = e->type;
  }
  const TypeClass k = type_class(type);
  const bool integral =
      (k == TypeClass::boolean || k == TypeClass::signed_integer || k == TypeClass::unsigned_integer) &&
      size_of(type) <= 4;
  const auto as_double = [](const Number& n) { return std::visit([](auto v) { return double(v); }, n); };
  if (!integral)
    throw std::invalid_argument("channel '" + ch.name + "': " + to_string(a) + " is " +
                                std::string(to_string(type)) + (eds ? " in " + eds->file : std::string()) +
                                ", not an integer of up to 32 bits: set error_value: false");
  if (!(value >= as_double(type_min(type)) && value <= as_double(type_max(type)))) {
    char shown[400];  // any double, in full
    std::snprintf(shown, sizeof shown, "%.0f", value);
    throw std::invalid_argument("channel '" + ch.name + "': " + what + " is " + shown + ", which " +
                                to_string(a) + " (" + std::string(to_string(type)) + ") cannot hold");
  }
  const auto bits = k == TypeClass::signed_integer
                        ? static_cast<std::uint32_t>(static_cast<std::int32_t>(value))
                        : static_cast<std::uint32_t>(value);
  out.writes.push_back({a, type, bits});
}

ErrorWrites error_value_writes(const std::vector<IoChannel>& channels, const Eds* eds) {
  ErrorWrites out;
  for (const IoChannel& ch : channels) {
    if (!ch.error_value) continue;  // the deployment opted out: the device's own behaviour
    const ObjectAddress a = ch.output->address;
    const bool analog = a.index == 0x6411, digital = a.index == 0x6200;
    if ((!analog && !digital) || a.subindex == 0) {
      out.unsupported.push_back(&ch);
      continue;
    }
    const double count = std::round((ch.safe - ch.offset) / ch.scale);
    if (analog) {
      add_error_write(out, ch, eds, {0x6443, a.subindex}, DataType::unsigned8, 1, "its error mode");
      add_error_write(out, ch, eds, {0x6444, a.subindex}, DataType::integer32, count,
                      "its safe value in counts");
    } else {
      add_error_write(out, ch, eds, {0x6206, a.subindex}, DataType::unsigned8, 0xFF, "its error mode mask");
      add_error_write(out, ch, eds, {0x6207, a.subindex}, DataType::unsigned8, count,
                      "its safe value in counts");
    }
  }
  return out;
}

std::vector<std::uint32_t> tpdo_ids(const IoNodeConfig& n) {
  std::vector<std::uint32_t> ids;
  for (const PdoMapping& m : n.pdos)
    if (m.enabled && m.kind == PdoKind::tpdo) ids.push_back(m.cob_id & CAN_SFF_MASK);
  return ids;
}

}  // namespace

CanopenIo::CanopenIo(std::string name, TaskConfig task, CanopenIoConfig config)
    : CanopenIo(std::move(name), task, Checked<CanopenIoConfig>{checked(std::move(config), task)}, nullptr) {}

CanopenIo::CanopenIo(std::string name, TaskConfig task, CanopenIoConfig config, can::Bus& bus)
    : CanopenIo(std::move(name), task, Checked<CanopenIoConfig>{checked(std::move(config), task)}, &bus) {}

CanopenIo::CanopenIo(std::string name, TaskConfig task, Checked<CanopenIoConfig> config, can::Bus* bus)
    : Device(std::move(name), task, contract_of(config.value)), config_(std::move(config.value)) {
  // The node's own safe state when the controller dies: before the deployment's writes (which may
  // set them otherwise), so the start-up and every re-configuration after a reboot write them.
  // The log keeps the name's pointer until it is drained: the channel's own, in config_.
  const ErrorWrites errors = error_value_writes(config_.channels, config_.eds ? &*config_.eds : nullptr);
  config_.node.writes.insert(config_.node.writes.begin(), errors.writes.begin(), errors.writes.end());
  for (const IoChannel* ch : errors.unsupported)
    saw::log(LogLevel::warning, this->name().c_str(),
             "channel '{}': its output is no CiA 401 output object (0x6411 or 0x6200): the node has no "
             "standard error value, so its output when the controller dies is the device's own",
             ch->name.c_str());
  for (const auto& [ch, a] : errors.unlisted)
    saw::log(LogLevel::warning, this->name().c_str(),
             "channel '{}': the EDS lists no {:x}:{}, not written: the node has no standard error value "
             "there, so its output when the controller dies is the device's own",
             ch->name.c_str(), unsigned{a.index}, unsigned{a.subindex});
  check(config_.node);
  const std::uint8_t nodes[] = {config_.node.node};
  const auto tpdos = tpdo_ids(config_.node);
  link_ = bus != nullptr ? link_callers_bus(*bus, this->name())
                         : link_bus(config_.bus, this->name(), task.period.count(), nodes, tpdos);
  if (!link_.shared()) {  // its own bus: it runs the bus task in its own cycle
    BusTaskConfig k;
    k.period = task.period.count();
    k.node = config_.master_node;
    k.heartbeat_period = config_.master_heartbeat_period;
    k.heartbeat_timeout = config_.master_heartbeat_timeout;
    own_task_ = std::make_shared<BusTask>(std::move(link_.owned), k);
    link_.port = &own_task_->attach(this->name(), nodes, tpdos);
    link_.bus = link_.port;
  }
  const BusTaskConfig& k = own_task_ ? own_task_->config() : link_.task->config();
  config_.node.master_node = k.node;
  config_.node.master_timeout = k.heartbeat_timeout;
  config_.node.name = this->name();
  io_ = std::make_unique<IoNode>(*link_.bus, config_.node);
  monitor_ = std::make_unique<NodeMonitor>(*io_, this->name().c_str(), std::vector<const char*>{nullptr});
  set_safe_outputs();
  status_.node = config_.node.node;
  auto& c = provide("canopen");
  c.add_command_read("status", state_table().add_column("status", &status_, ColumnUse::summary));
  c.add_command_qualified_read<SdoRequest, SdoReply>(
      "sdo", [this](const SdoRequest& q, SdoReply& r) { r = io_->sdo_queue().transfer(q, 1'000'000'000); });
}

CanopenIo::~CanopenIo() = default;

void CanopenIo::open() {
  StartupSequence sequence(*link_.bus, std::vector<NodeSetup>{setup_of(io_->config())}, config_.startup);
  run_startup(sequence, config_.startup_pause);
  const IoNodeConfig& n = io_->config();
  for (const std::uint16_t rpdo : unwatched_rpdos(n.pdos, n.rpdo_deadline, sequence.written()[0]))
    saw::log(LogLevel::warning, name().c_str(),
             "node {}: RPDO{} has no deadline ({:x}:05 not in its EDS or refused): the node does not see a "
             "starved master there",
             unsigned{n.node}, unsigned{rpdo}, 0x1400u + rpdo - 1);
}

void CanopenIo::set_safe_outputs() noexcept {
  for (std::size_t i = 0; i < config_.channels.size(); ++i) {
    const IoChannel& ch = config_.channels[i];
    if (io_->set_output(i, (ch.safe - ch.offset) / ch.scale) == Codec::ok) target_[i] = ch.safe;
  }
}

Outcome CanopenIo::failure(const char* why, FaultCode code, std::uint32_t detail, TimeNs age) noexcept {
  return Outcome::failed(code, why, name(), detail, age);
}

Outcome CanopenIo::read() {
  const TimeNs t = now();
  if (start_time_ < 0) {
    start_time_ = t;
    link_.port->set_cycling(true);  // from now on the bus task carries its frames
  }
  if (own_task_) (void)own_task_->route(t);  // frames in; this cycle's RPDOs and SYNC go in write()
  io_->receive(t);
  JointState& js = measured().js;
  std::size_t in = 0;
  for (std::size_t i = 0; i < config_.channels.size(); ++i) {
    const IoChannel& ch = config_.channels[i];
    double v = 0;
    if (!ch.input)
      js.position[i] = target_[i];
    else if (io_->input(in++, v))
      js.position[i] = v * ch.scale + ch.offset;
  }
  return check_node();
}

Outcome CanopenIo::check_node() noexcept {
  const AxisHealth& h = io_->health();
  const bool says = operating_state().state != OperatingStateValue::fault;
  const can::BusState bus = link_.port->state();
  if (bus == can::BusState::bus_off || bus == can::BusState::down)
    return failure("bus off", FaultCode::device_lost, static_cast<std::uint32_t>(bus));
  monitor_->look(0, enabling());
  if (monitor_->rebooted(0)) {
    if (enabling()) return Outcome::done();  // the enable configures it again
    if (says) monitor_->say_rebooted(0);
    return failure("node rebooted", FaultCode::device_lost);
  }
  if (const Outcome o = check_emcy(); o.is_failed()) return o;
  if (h.heartbeat_lost) return failure("heartbeat lost", FaultCode::device_lost, 0, h.silent_for);
  if (monitor_->left_operational(0, says))
    return failure("left NMT operational", FaultCode::device_lost, static_cast<std::uint32_t>(h.nmt_state));
  const TimeNs age = now() - (io_->valid() ? io_->last_received() : std::max(start_time_, watch_from_));
  if (age > config_.feedback_timeout) return failure("feedback stale", FaultCode::input_stale, 0, age);
  return Outcome::done();
}

// An I/O node has no statusword that says whether it faulted: the EMCY's code and error register
// decide (emcy_severity). A warning is logged once and shown in status; a fault is a FAULT.
Outcome CanopenIo::check_emcy() noexcept {
  const IoEmcys& e = io_->emcys();
  const unsigned node = config_.node.node;
  if (e.warnings != emcy_warnings_seen_) {
    const std::uint64_t n = e.warnings - emcy_warnings_seen_;
    emcy_warnings_seen_ = e.warnings;
    status_.warnings = e.warnings;
    status_.last_warning = e.last_warning.code;
    status_.last_warning_register = e.last_warning.error_register;
    saw::log(LogLevel::warning, name().c_str(), "node {}: EMCY {:x} ({}), error register {:x}: a warning{}",
             node, unsigned{e.last_warning.code}, emcy_name(e.last_warning.code).data(),
             unsigned{e.last_warning.error_register}, n > 1 ? " (the newest of several)" : "");
  }
  if (e.faults == emcy_faults_seen_) return Outcome::done();
  emcy_faults_seen_ = e.faults;
  saw::log(LogLevel::error, name().c_str(), "node {}: EMCY {:x} ({}), error register {:x}", node,
           unsigned{e.last_fault.code}, emcy_name(e.last_fault.code).data(),
           unsigned{e.last_fault.error_register});
  return failure("emergency message", FaultCode::device_error, e.last_fault.code);
}

// A node that rebooted lost its PDO maps and heartbeats: the enable runs its configuration again
// (the start-up's writes, NMT start) before waiting for its TPDOs.
Outcome CanopenIo::enable() {
  switch (monitor_->reconfigure(*io_, 0, now())) {
    case NodeMonitor::Step::busy:
      return Outcome::pending();
    case NodeMonitor::Step::done:
      ++status_.reconfigurations;
      watch_from_ = now();  // its TPDOs come from the next SYNC on
      break;
    case NodeMonitor::Step::failed:
      return failure("node rebooted", FaultCode::device_lost,
                     static_cast<std::uint32_t>(io_->reconfiguration().abort));
    case NodeMonitor::Step::not_rebooted:
      break;
  }
  return io_->valid() ? Outcome::done() : Outcome::pending();
}

Outcome CanopenIo::write(const Setpoint& s) {
  if (!following()) {
    set_safe_outputs();
  } else if (s.mode == ServoMode::jp) {
    for (std::size_t i = 0; i < config_.channels.size(); ++i) {
      const IoChannel& ch = config_.channels[i];
      if (io_->set_output(i, (s.joints[i] - ch.offset) / ch.scale) == Codec::ok) target_[i] = s.joints[i];
    }
  }  // following without a fresh command: the last outputs stay
  io_->transmit(now());
  // Its own bus: this cycle's RPDOs, then SYNC, in the same period as the TPDOs they answer.
  if (own_task_) (void)own_task_->send(now());
  const AxisHealth& h = io_->health();
  status_.state = operating_state().state;
  status_.nmt_state = static_cast<std::uint8_t>(h.nmt_state);
  status_.bus_state = static_cast<std::uint8_t>(link_.port->state());
  status_.emcy = h.emcy_count;
  status_.last_emcy = h.last_emcy;
  status_.error_register = h.error_register;
  status_.heartbeat_losses = h.heartbeat_losses;
  status_.boot_ups = h.boot_ups;
  status_.bad_pdos = h.bad_pdos;
  return Outcome::done();
}

void CanopenIo::enter_safe_state(SafeReason why) {
  set_safe_outputs();
  if (why == SafeReason::fault || why == SafeReason::disable) return;  // sent by the next write()
  // Stop, or a failed start: every thread has ended; the frames go out at once.
  link_.port->set_cycling(false);
  io_->shut_down(now());
  link_.port->mark_shut_down();
}

}  // namespace saw::canopen
