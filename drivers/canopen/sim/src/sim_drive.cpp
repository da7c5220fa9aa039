#include "saw/canopen/sim/sim_drive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "pdo_channels.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/sim/drive_dictionary.hpp"
#include "saw/canopen/sync.hpp"

namespace saw::canopen::sim {

namespace {

constexpr double two_pi = 2 * std::numbers::pi;
constexpr TimeNs ms = 1'000'000;
constexpr TimeNs forever = std::numeric_limits<TimeNs>::max();
// Without a SYNC for this long the CSP target is read every cycle (a master using SDO only).
constexpr TimeNs sync_lapse = 100 * ms;
// Below this the motor counts as stopped: a quick stop or a fault reaction is over.
constexpr double standstill_speed = two_pi * 0.01;  // rad/s at the motor: 0.01 rev/s
constexpr std::uint32_t following_error_off = 0xFFFFFFFF;

namespace code {
constexpr std::uint16_t over_current = 0x2310;
constexpr std::uint16_t following_error = 0x8611;
constexpr std::uint16_t pdo_length = 0x8210;
constexpr std::uint16_t bus_off_recovered = 0x8140;
constexpr std::uint16_t heartbeat_error = 0x8130;  // life guard or heartbeat error
constexpr std::uint16_t rpdo_timeout = 0x8250;     // CiA 301: an RPDO's deadline passed
}  // namespace code

namespace object {
constexpr ObjectAddress error_register{0x1001, 0};
constexpr ObjectAddress error_history{0x1003, 0};
constexpr ObjectAddress sync_id{0x1005, 0};
constexpr ObjectAddress emcy_id{0x1014, 0};
constexpr ObjectAddress emcy_inhibit{0x1015, 0};
constexpr ObjectAddress heartbeat_time{0x1017, 0};
constexpr ObjectAddress consumer_heartbeat{0x1016, 1};
constexpr ObjectAddress abort_connection_option{0x6007, 0};
constexpr ObjectAddress position_demand{0x6062, 0};
constexpr ObjectAddress following_error_timeout{0x6066, 0};
constexpr ObjectAddress min_position_limit{0x607D, 1};
constexpr ObjectAddress max_position_limit{0x607D, 2};
constexpr ObjectAddress following_error_actual{0x60F4, 0};
}  // namespace object

std::uint8_t checked_node(std::uint8_t node) {
  if (!valid_node_id(node))
    throw std::invalid_argument("simulated drive: node-ID " + std::to_string(node) + " is not 1..127");
  return node;
}

// The encoder's 32-bit counter: positions wrap as on a real drive's 0x6064.
std::int32_t wrap32(double counts) noexcept {
  if (!std::isfinite(counts)) return 0;
  const long long r = std::llround(std::fmod(counts, 4294967296.0));
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(r));
}

template <class T>
T saturate(double v) noexcept {
  if (!std::isfinite(v)) return 0;
  const double lo = static_cast<double>(std::numeric_limits<T>::min());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  return static_cast<T>(std::llround(std::clamp(v, lo, hi)));
}

bool motion_mode(cia402::Mode m) noexcept { return m == cia402::csp || m == cia402::csv || m == cia402::cst; }

}  // namespace

// ---- the SDO server's view -----------------------------------------------------------------

SdoAbort SimDrive::SdoView::check_download(ObjectAddress address, std::optional<std::size_t> size) noexcept {
  if (const SdoAbort a = drive_.injected_abort(address); a != SdoAbort::none) return a;
  return drive_.dictionary_.check_download(address, size);
}

SdoAbort SimDrive::SdoView::read(ObjectAddress address, std::span<std::uint8_t> out,
                                 std::size_t& size) noexcept {
  if (const SdoAbort a = drive_.injected_abort(address); a != SdoAbort::none) return a;
  return drive_.dictionary_.read(address, out, size);
}

SdoAbort SimDrive::SdoView::write(ObjectAddress address, std::span<const std::uint8_t> data,
                                  bool size_indicated) noexcept {
  if (const SdoAbort a = drive_.injected_abort(address); a != SdoAbort::none) return a;
  const SdoAbort a = drive_.dictionary_.write(address, data, size_indicated);
  if (a == SdoAbort::none) drive_.written(address);
  return a;
}

// ---- construction, configuration, resets ---------------------------------------------------

SimDrive::SimDrive(const SimDriveConfig& config, can::Bus& bus)
    : node_(checked_node(config.node)),
      bus_(bus),
      dictionary_(make_drive_dictionary(load_drive_eds(config.eds), node_)),
      view_(*this),
      nmt_(node_),
      heartbeat_(node_, 0),
      emcy_(node_, 0),
      pdos_(std::make_unique<PdoChannels>(dictionary_)),
      motor_(config.motor) {
  if (config.heartbeat_ms && dictionary_.set(object::heartbeat_time, *config.heartbeat_ms) != Codec::ok)
    throw std::invalid_argument("simulated drive: heartbeat time " + std::to_string(*config.heartbeat_ms) +
                                " ms refused by 0x1017");
  defaults_ = dictionary_;  // before the hook: restoring defaults goes around it
  dictionary_.on_write(
      [this](ObjectAddress a, std::span<const std::uint8_t> data) { return check_write(a, data); });
  sdo_.emplace(SdoServerConfig{SdoChannel::of_node(node_)}, view_);
  reset(NmtReset::application);
  booted_ = false;  // reset() booted the NMT machine; power-on is the first step()
  nmt_ = NmtNode(node_);
}

SimDrive::~SimDrive() = default;

void SimDrive::refresh_identifiers() noexcept {
  sync_id_ = get_or<std::uint32_t>(object::sync_id, cob::sync) & CAN_SFF_MASK;
  const auto emcy = get_or<std::uint32_t>(object::emcy_id, cob::emcy + node_);
  emcy_enabled_ = (emcy & 0x80000000) == 0;
  emcy_id_ = emcy & CAN_SFF_MASK;
}

void SimDrive::refresh_producers() noexcept {
  heartbeat_.set_period(get_or<std::uint16_t>(object::heartbeat_time, 0) * ms, now_);
  emcy_ = EmcyProducer(node_, get_or<std::uint16_t>(object::emcy_inhibit, 0) * TimeNs{100'000});
  refresh_consumer();
}

void SimDrive::refresh_consumer() noexcept {
  const auto v = get_or<std::uint32_t>(object::consumer_heartbeat, 0);
  const auto node = static_cast<std::uint8_t>((v >> 16) & 0x7F);
  consumer_time_ = static_cast<TimeNs>(v & 0xFFFF) * ms;
  watched_node_ = consumer_time_ > 0 ? node : 0;
  watched_seen_.reset();  // CiA 301: monitoring starts with the next heartbeat
  consumer_fired_ = false;
}

// CiA 301's heartbeat event: the watched node silent for its consumer time. EMCY 0x8130, then
// what 0x6007 says (CiA 402): a drive whose master is gone stops by itself.
void SimDrive::watch_consumer() noexcept {
  if (watched_node_ == 0 || !watched_seen_ || consumer_fired_) return;
  if (now_ - *watched_seen_ <= consumer_time_) return;
  consumer_fired_ = true;
  ++counters_.heartbeat_events;
  raise(code::heartbeat_error, error_register::communication);
  abort_connection(code::heartbeat_error);
}

// CiA 301's RPDO deadline: an RPDO's event timer (0x1400 + n - 1 sub 05h) passed since it last
// came, in operational (watched from its first reception). EMCY 0x8250, then what 0x6007 says, as
// at a heartbeat event; the node stays operational (the master's heartbeat may well go on).
void SimDrive::watch_rpdos() noexcept {
  if (nmt_.state() != NmtState::operational) return;
  while (pdos_->expired_rpdo(now_) != 0) {
    ++counters_.rpdo_timeouts;
    raise(code::rpdo_timeout, error_register::communication);
    abort_connection(code::rpdo_timeout);
  }
}

void SimDrive::restore(std::uint16_t first, std::uint16_t last) noexcept {
  for (const auto& [address, entry] : defaults_.entries()) {
    if (address.index < first || address.index > last) continue;
    Number n;
    if (get_number(entry, n) == Codec::ok) {
      (void)set_number(dictionary_, address, n);
    } else if (writable(entry.access)) {
      (void)dictionary_.write(address, entry.value, true);  // strings: within their capacity
    }
  }
}

void SimDrive::reset(NmtReset what) noexcept {
  if (what == NmtReset::application) {
    restore(0x0000, 0xFFFF);
    drive_config_.quick_stop_option = get_or<std::int16_t>(cia402::object::quick_stop_option_code, 2);
    drive_config_.supported_modes =
        get_or<std::uint32_t>(cia402::object::supported_drive_modes, 0) &
        (cia402::supported_mode_bit(cia402::csp) | cia402::supported_mode_bit(cia402::csv) |
         cia402::supported_mode_bit(cia402::cst));
    drive_ = cia402::Drive(drive_config_);
    requested_mode_ = 0;
    loop_ = ServoCommand::Loop::off;
    command_ = ServoCommand{};
    motor_.reset_servo();
    error_code_ = 0;
    error_register_ = 0;
    fault_input_ = false;
    forced_command_.reset();
    bus_off_fault_ = false;
    following_error_since_.reset();
    pending_[index(FaultKind::over_current)].reset();
    pending_[index(FaultKind::following_error)].reset();
  } else {
    restore(0x1000, 0x1FFF);
  }
  refresh_identifiers();
  refresh_producers();
  pdos_->rebuild_all();
  // A transfer in progress dies with the reset, as the client's own timeout will tell it.
  sdo_.emplace(SdoServerConfig{SdoChannel::of_node(node_)}, view_);
  last_sync_.reset();
  last_sync_reference_.reset();
  pdo_length_error_ = false;
  boot();
}

void SimDrive::boot() noexcept {
  nmt_.boot();
  heartbeat_.start(now_);
}

SdoAbort SimDrive::check_write(ObjectAddress a, std::span<const std::uint8_t> data) const noexcept {
  const Entry* e = dictionary_.find(a);
  Number n;
  if (e == nullptr || !is_numeric(type_class(e->type)) || decode(e->type, data, n) != Codec::ok)
    return SdoAbort::none;  // the dictionary's own checks have answered already
  std::uint64_t u = 0;
  std::int64_t i = 0;
  const bool is_unsigned = to_value(n, u) == Codec::ok;
  const bool is_signed = to_value(n, i) == Codec::ok;
  if (PdoChannels::is_pdo_parameter(a.index))
    return is_unsigned ? pdos_->check_write(a, u) : SdoAbort::invalid_value;
  if (a == object::sync_id) {
    // Bit 30 would make this node the SYNC producer; bit 29 a 29-bit SYNC. Neither is simulated.
    return (u & 0x60000000) != 0 ? SdoAbort::invalid_value : SdoAbort::none;
  }
  if (a == object::emcy_id) return (u & 0x20000000) != 0 ? SdoAbort::invalid_value : SdoAbort::none;
  if (a == object::error_history)
    return u != 0 ? SdoAbort::invalid_value : SdoAbort::none;  // CiA 301: 0 clears
  if (a == cia402::object::modes_of_operation) {
    const auto bit = cia402::supported_mode_bit(static_cast<cia402::Mode>(is_signed ? i : 0));
    return (bit & drive_config_.supported_modes) == 0 ? SdoAbort::invalid_value : SdoAbort::none;
  }
  if (a == injection_object::inject)
    return u == 0 || fault_kind_from_code(static_cast<unsigned>(u)) ? SdoAbort::none
                                                                    : SdoAbort::invalid_value;
  return SdoAbort::none;
}

void SimDrive::written(ObjectAddress a) noexcept {
  if (PdoChannels::is_pdo_parameter(a.index)) {
    pdos_->written(a);
  } else if (a == object::heartbeat_time) {
    heartbeat_.set_period(get_or<std::uint16_t>(a, 0) * ms, now_);
  } else if (a == object::consumer_heartbeat) {
    refresh_consumer();
  } else if (a == object::emcy_inhibit) {
    emcy_ = EmcyProducer(node_, get_or<std::uint16_t>(a, 0) * TimeNs{100'000});
  } else if (a == object::sync_id || a == object::emcy_id) {
    refresh_identifiers();
  } else if (a == object::error_history) {
    for (std::uint16_t k = 1; k <= 0xFE && dictionary_.find({0x1003, static_cast<std::uint8_t>(k)}); ++k)
      (void)dictionary_.set(ObjectAddress{0x1003, static_cast<std::uint8_t>(k)}, std::uint32_t{0});
  } else if (a == injection_object::inject) {
    const auto code = get_or<std::uint8_t>(a, 0);
    const auto kind = fault_kind_from_code(code);
    if (!kind) {
      clear_all();
      return;
    }
    Fault f;
    f.kind = *kind;
    f.duration = get_or<std::uint32_t>(injection_object::duration, 0) * ms;
    const auto target = get_or<std::uint32_t>(injection_object::object, 0);
    f.object = {static_cast<std::uint16_t>(target >> 16), static_cast<std::uint8_t>(target >> 8)};
    f.abort = static_cast<SdoAbort>(get_or<std::uint32_t>(injection_object::code, 0x06060000));
    inject(f);
  }
}

SdoAbort SimDrive::injected_abort(ObjectAddress address) const noexcept {
  return until_[index(FaultKind::sdo_abort)] && sdo_abort_.object == address ? sdo_abort_.abort
                                                                             : SdoAbort::none;
}

// ---- faults --------------------------------------------------------------------------------

void SimDrive::inject(const Fault& fault) noexcept {
  if (fault_kind_from_code(static_cast<unsigned>(fault.kind))) pending_[index(fault.kind)] = fault;
}

void SimDrive::end_fault(FaultKind kind) noexcept {
  if (!until_[index(kind)]) return;
  until_[index(kind)].reset();
  if (kind == FaultKind::bus_off) {
    if (bus_off_fault_) {
      bus_off_fault_ = false;  // its EMCY waited in the queue; the drive's fault stays until reset
      return;
    }
    // CANopenNode's behaviour: the event is reported once the node can talk again, and reset.
    push_history(code::bus_off_recovered);
    (void)emcy_.raise(code::bus_off_recovered,
                      error_register_ | error_register::communication | error_register::generic);
    (void)emcy_.clear(error_register_);
  }
}

void SimDrive::clear(FaultKind kind) noexcept {
  if (!fault_kind_from_code(static_cast<unsigned>(kind))) return;
  pending_[index(kind)].reset();
  end_fault(kind);
}

void SimDrive::clear_all() noexcept {
  for (unsigned k = 1; k <= fault_kind_count; ++k) clear(static_cast<FaultKind>(k));
}

void SimDrive::abort_connection(std::uint16_t code) noexcept {
  // CiA 402's abort connection (0x6007) acts on a drive that is driving; a bus-off, a heartbeat
  // event and an RPDO timeout are its events. Absent 0x6007, nothing happens (the drive keeps its last
  // setpoints).
  if (!drive_.following() && drive_.state() != cia402::State::quick_stop_active) return;
  switch (get_or<std::int16_t>(object::abort_connection_option, 0)) {
    case 1:  // fault signal (a bus-off's EMCY waits in the queue until the bus is back)
      if (code == code::bus_off_recovered) raise(code, error_register::communication);
      fault_input_ = true;
      bus_off_fault_ = code == code::bus_off_recovered;
      break;
    case 2:
      forced_command_ = cia402::controlword::disable_voltage_command;
      break;
    case 3:
      forced_command_ = cia402::controlword::quick_stop_command;
      break;
    default:
      break;
  }
}

std::uint8_t SimDrive::active_faults() const noexcept {
  std::uint8_t bits = 0;
  for (unsigned k = 1; k <= fault_kind_count; ++k)
    if (until_[k - 1]) bits |= fault_bit(static_cast<FaultKind>(k));
  return bits;
}

void SimDrive::update_faults() noexcept {
  for (unsigned k = 1; k <= fault_kind_count; ++k) {
    const auto kind = static_cast<FaultKind>(k);
    auto& pending = pending_[k - 1];
    if (pending) {
      const Fault f = *pending;
      pending.reset();
      switch (kind) {
        case FaultKind::over_current:
          raise(code::over_current, error_register::current);
          fault_input_ = true;
          break;
        case FaultKind::following_error:
          raise(code::following_error, error_register::device_profile);
          fault_input_ = true;
          break;
        case FaultKind::heartbeat_loss:
        case FaultKind::bus_off:
        case FaultKind::sdo_abort: {
          const TimeNs d = f.duration > 0               ? f.duration
                           : kind == FaultKind::bus_off ? default_bus_off_duration
                                                        : 0;
          until_[k - 1] = d > 0 ? now_ + d : forever;
          if (kind == FaultKind::sdo_abort) sdo_abort_ = f;
          if (kind == FaultKind::bus_off) abort_connection(code::bus_off_recovered);
          break;
        }
      }
    }
    if (until_[k - 1] && now_ >= *until_[k - 1]) end_fault(kind);
  }
}

void SimDrive::raise(std::uint16_t code, std::uint8_t register_bits) noexcept {
  error_code_ = code;
  error_register_ |= register_bits | error_register::generic;
  push_history(code);
  (void)emcy_.raise(code, error_register_);
}

void SimDrive::clear_errors() noexcept {
  error_code_ = 0;
  error_register_ = 0;
  (void)emcy_.clear(0);
}

void SimDrive::push_history(std::uint16_t code) noexcept {
  // 0x1003: newest at sub-index 1, older ones shifted down, sub-index 0 the count.
  std::uint8_t slots = 0;
  while (slots < 0xFE && dictionary_.find({0x1003, static_cast<std::uint8_t>(slots + 1)}) != nullptr) ++slots;
  if (slots == 0) return;
  for (std::uint8_t k = slots; k >= 2; --k) {
    const auto older = get_or<std::uint32_t>({0x1003, static_cast<std::uint8_t>(k - 1)}, 0);
    (void)dictionary_.set(ObjectAddress{0x1003, k}, older);
  }
  (void)dictionary_.set(ObjectAddress{0x1003, 1}, std::uint32_t{code});
  const auto count = get_or<std::uint8_t>(object::error_history, 0);
  (void)dictionary_.set(object::error_history,
                        static_cast<std::uint8_t>(std::min<unsigned>(count + 1u, slots)));
}

// ---- the cycle -----------------------------------------------------------------------------

void SimDrive::step(TimeNs now) noexcept {
  now_ = now;
  if (!booted_) {  // power-on
    booted_ = true;
    last_step_ = now;
    boot();
  }
  if (last_step_ && now > *last_step_) motor_.advance(command_, now - *last_step_);
  last_step_ = now;
  update_faults();
  publish_actuals();  // what a SYNC in this step's frames samples
  receive_all();
  watch_consumer();
  watch_rpdos();
  control();
  produce();
  flush();
}

void SimDrive::receive_all() noexcept {
  can::Received rx[32];
  // Bounded: a flooded bus costs at most this many frames per step; the rest wait.
  for (int batch = 0; batch < 32; ++batch) {
    const std::size_t n = bus_.receive(rx);
    counters_.frames_in += n;
    if (bus_off()) {
      counters_.lost_bus_off += n;
    } else {
      for (std::size_t i = 0; i < n; ++i) dispatch(rx[i].frame);
    }
    if (n < std::size(rx)) break;
  }
}

void SimDrive::dispatch(const can::Frame& f) noexcept {
  if (!canopen_data_frame(f)) {
    ++counters_.not_canopen;
    return;
  }
  const std::uint32_t id = f.can_id();
  if (id == cob::nmt) {
    const auto request = parse_nmt(f);
    if (!request || !request->addresses(node_)) return;
    ++counters_.nmt;
    const NmtState before = nmt_.state();
    const NmtReset r = nmt_.on_frame(f);
    if (r != NmtReset::none) {
      reset(r);
    } else if (nmt_.state() == NmtState::operational && before != NmtState::operational) {
      pdos_->start(now_);
    }
    return;
  }
  if (watched_node_ != 0 && id == cob::heartbeat + watched_node_ && parse_heartbeat(f)) {
    watched_seen_ = now_;  // the consumer listens in every NMT state (error control)
    consumer_fired_ = false;
    return;
  }
  const NmtState state = nmt_.state();
  if (state != NmtState::pre_operational && state != NmtState::operational) return;  // stopped: NMT only
  if (id == SdoChannel::of_node(node_).request) {
    ++counters_.sdo_requests;
    sdo_->on_frame(f, now_);
    while (auto response = sdo_->poll(now_)) queue(*response);  // one request, one response
    return;
  }
  if (state != NmtState::operational) return;
  if (id == sync_id_) {
    can::Frame sync = f;
    sync.id = cob::sync;  // parse_sync knows the default identifier only; 0x1005 may move it
    if (parse_sync(sync)) on_sync();
    return;
  }
  switch (pdos_->on_frame(f)) {
    case PdoChannels::Receive::applied:
    case PdoChannels::Receive::latched:
      ++counters_.rpdos;
      if (pdo_length_error_) {
        pdo_length_error_ = false;
        (void)emcy_.clear(error_register_);
      }
      break;
    case PdoChannels::Receive::wrong_length:
      ++counters_.pdo_length_errors;
      if (!pdo_length_error_) {  // once, not once per frame
        pdo_length_error_ = true;
        push_history(code::pdo_length);
        (void)emcy_.raise(code::pdo_length,
                          error_register_ | error_register::communication | error_register::generic);
      }
      break;
    case PdoChannels::Receive::not_rpdo:
    case PdoChannels::Receive::refused:
      break;
  }
}

void SimDrive::on_sync() noexcept {
  ++counters_.sync;
  pdos_->on_sync(now_);  // synchronous RPDOs take effect; TPDOs sample the values published this step
  if (last_sync_) sync_interval_ = now_ - *last_sync_;
  last_sync_ = now_;
  if (loop_ != ServoCommand::Loop::position) {
    last_sync_reference_.reset();
    return;
  }
  // CSP: SYNC is the setpoint clock. The reference moves from this target at the speed the
  // last two targets imply, as a drive interpolates between the master's cycles.
  std::int32_t target = get_or<std::int32_t>(cia402::object::target_position, 0);
  const auto lo = get_or<std::int32_t>(object::min_position_limit, std::numeric_limits<std::int32_t>::min());
  const auto hi = get_or<std::int32_t>(object::max_position_limit, std::numeric_limits<std::int32_t>::max());
  limit_active_ = lo < hi && (target < lo || target > hi);
  if (lo < hi) target = std::clamp(target, lo, hi);
  const double actual = motor_.position() * counts_per_revolution_ / two_pi;
  const double reference = actual + static_cast<std::int32_t>(static_cast<std::uint32_t>(target) -
                                                              static_cast<std::uint32_t>(position_counts_));
  feed_forward_ = last_sync_reference_ && sync_interval_ > 0 && sync_interval_ < sync_lapse
                      ? (reference - *last_sync_reference_) / (static_cast<double>(sync_interval_) * 1e-9)
                      : 0.0;
  reference_ = reference;
  reference_time_ = now_;
  last_sync_reference_ = reference;
}

void SimDrive::publish_actuals() noexcept {
  const double counts = motor_.position() * counts_per_revolution_ / two_pi;
  position_counts_ = wrap32(counts);
  const double rated = get_or<std::uint32_t>(cia402::object::motor_rated_torque, 0) * 1e-3;  // mN·m
  (void)dictionary_.set(cia402::object::position_actual_value, position_counts_);
  (void)dictionary_.set(cia402::object::velocity_actual_value,
                        saturate<std::int32_t>(motor_.velocity() * counts_per_revolution_ / two_pi));
  (void)dictionary_.set(cia402::object::torque_actual_value,
                        rated > 0 ? saturate<std::int16_t>(motor_.torque() / rated * 1000) : std::int16_t{0});
}

void SimDrive::control() noexcept {
  // Units, read each cycle as a drive does (a master may write them in pre-operational).
  const auto increments = get_or<std::uint32_t>(cia402::object::position_encoder_resolution_increments, 4096);
  const auto revolutions = get_or<std::uint32_t>(cia402::object::position_encoder_resolution_revolutions, 1);
  if (increments > 0 && revolutions > 0)
    counts_per_revolution_ = static_cast<double>(increments) / revolutions;
  const auto motor_turns = get_or<std::uint32_t>(cia402::object::gear_ratio_motor_revolutions, 1);
  const auto shaft_turns = get_or<std::uint32_t>(cia402::object::gear_ratio_shaft_revolutions, 1);
  const double ratio =
      motor_turns > 0 && shaft_turns > 0 ? static_cast<double>(motor_turns) / shaft_turns : 1.0;
  if (ratio != gear_ratio_) {
    gear_ratio_ = ratio;
    motor_.set_gear_ratio(ratio);
  }
  const double rated = get_or<std::uint32_t>(cia402::object::motor_rated_torque, 0) * 1e-3;
  const double max_torque = rated * get_or<std::uint16_t>(cia402::object::max_torque, 1000) * 1e-3;
  const double rad_per_count = two_pi / counts_per_revolution_;
  const double actual = motor_.position() / rad_per_count;  // counts, unwrapped

  const auto mode = get_or<std::int8_t>(cia402::object::modes_of_operation, 0);
  if (mode != requested_mode_) {
    requested_mode_ = mode;
    (void)drive_.request_mode(static_cast<cia402::Mode>(mode));  // refused: 0x6061 stays
  }

  // Following error (CSP), before this cycle's controlword acts.
  const bool sync_driven = last_sync_ && now_ - *last_sync_ < sync_lapse;
  const TimeNs horizon = sync_driven ? sync_interval_ : 0;
  const double reference_now =
      reference_ +
      feed_forward_ * static_cast<double>(std::clamp<TimeNs>(now_ - reference_time_, 0, horizon)) * 1e-9;
  const auto window = get_or<std::uint32_t>(cia402::object::following_error_window, following_error_off);
  bool beyond_window = false;
  if (loop_ == ServoCommand::Loop::position) {
    following_error_ = reference_now - actual;
    beyond_window = window != following_error_off && std::abs(following_error_) > window;
    if (beyond_window) {
      if (!following_error_since_) following_error_since_ = now_;
      const TimeNs timeout = get_or<std::uint16_t>(object::following_error_timeout, 0) * ms;
      if (now_ - *following_error_since_ >= timeout) {
        raise(code::following_error, error_register::device_profile);
        fault_input_ = true;
        following_error_since_.reset();
      }
    } else {
      following_error_since_.reset();
    }
  } else {
    following_error_ = 0;
    following_error_since_.reset();
  }

  const cia402::State before = drive_.state();
  const bool standstill = std::abs(motor_.velocity()) < standstill_speed;
  const std::uint16_t controlword =
      forced_command_.value_or(get_or<std::uint16_t>(cia402::object::controlword, 0));
  forced_command_.reset();
  const cia402::State state = drive_.update({controlword, fault_input_, standstill, true});
  fault_input_ = false;
  if (before == cia402::State::fault && state == cia402::State::switch_on_disabled) clear_errors();  // 15

  // The servo command until the next step.
  using Loop = ServoCommand::Loop;
  ServoCommand c;
  c.max_torque = max_torque;
  const auto lo = get_or<std::int32_t>(object::min_position_limit, std::numeric_limits<std::int32_t>::min());
  const auto hi = get_or<std::int32_t>(object::max_position_limit, std::numeric_limits<std::int32_t>::max());
  const bool limits = lo < hi;
  bool limited = false;
  if (state == cia402::State::operation_enabled) {
    switch (drive_.mode_display()) {
      case cia402::Mode::cyclic_synchronous_position:
        c.loop = Loop::position;
        break;
      case cia402::Mode::cyclic_synchronous_velocity:
        c.loop = Loop::velocity;
        c.velocity = get_or<std::int32_t>(cia402::object::target_velocity, 0) * rad_per_count;
        break;
      case cia402::Mode::cyclic_synchronous_torque:
        c.loop = Loop::torque;
        c.torque = get_or<std::int16_t>(cia402::object::target_torque, 0) * rated * 1e-3;
        break;
      default:
        c.loop = Loop::velocity;  // no motion mode: hold still
        break;
    }
    // Software limits in CSV and CST: a push beyond a limit becomes a stop there.
    const bool outward =
        (c.loop == Loop::velocity &&
         ((position_counts_ >= hi && c.velocity > 0) || (position_counts_ <= lo && c.velocity < 0))) ||
        (c.loop == Loop::torque &&
         ((position_counts_ >= hi && c.torque > 0) || (position_counts_ <= lo && c.torque < 0)));
    if (limits && outward) {
      c.loop = Loop::velocity;
      c.velocity = 0;
      c.torque = 0;
      limited = true;
    }
  } else if (state == cia402::State::quick_stop_active || state == cia402::State::fault_reaction_active) {
    c.loop = Loop::velocity;  // stopping at the torque limit (the quick-stop ramp is not modelled)
  }
  if (c.loop != loop_) {
    motor_.reset_servo();
    if (c.loop == Loop::position) {  // enabled in CSP: start from the target as it stands
      std::int32_t target = get_or<std::int32_t>(cia402::object::target_position, 0);
      if (limits) target = std::clamp(target, lo, hi);
      reference_ = actual + static_cast<std::int32_t>(static_cast<std::uint32_t>(target) -
                                                      static_cast<std::uint32_t>(position_counts_));
      feed_forward_ = 0;
      reference_time_ = now_;
      last_sync_reference_.reset();
    }
    loop_ = c.loop;
  }
  if (c.loop == Loop::position) {
    if (!sync_driven) {  // no SYNC: the target as it stands, every cycle
      std::int32_t target = get_or<std::int32_t>(cia402::object::target_position, 0);
      limited = limits && (target < lo || target > hi);
      if (limits) target = std::clamp(target, lo, hi);
      reference_ = actual + static_cast<std::int32_t>(static_cast<std::uint32_t>(target) -
                                                      static_cast<std::uint32_t>(position_counts_));
      feed_forward_ = 0;
      reference_time_ = now_;
    } else {
      limited = limit_active_;
    }
    const double from =
        reference_ + feed_forward_ *
                         static_cast<double>(std::clamp<TimeNs>(now_ - reference_time_, 0, sync_interval_)) *
                         1e-9;
    c.position = from * rad_per_count;
    c.velocity = feed_forward_ * rad_per_count;
  }
  command_ = c;

  std::uint16_t bits = 0;
  if (state == cia402::State::operation_enabled && motion_mode(drive_.mode_display()))
    bits |= cia402::statusword::mode_specific_12;  // the drive follows the command value
  if (loop_ == Loop::position && beyond_window) bits |= cia402::statusword::mode_specific_13;
  if (limited) bits |= cia402::statusword::internal_limit_active;
  drive_.set_status_bits(bits);
  statusword_ = drive_.statusword();

  (void)dictionary_.set(cia402::object::statusword, statusword_);
  (void)dictionary_.set(cia402::object::modes_of_operation_display,
                        static_cast<std::int8_t>(drive_.mode_display()));
  (void)dictionary_.set(cia402::object::error_code, error_code_);
  (void)dictionary_.set(object::error_register, error_register_);
  (void)dictionary_.set(injection_object::active, active_faults());
  (void)dictionary_.set(object::position_demand, wrap32(reference_now));
  (void)dictionary_.set(object::following_error_actual, saturate<std::int32_t>(following_error_));
}

void SimDrive::produce() noexcept {
  if (auto f = nmt_.poll()) queue(*f);  // boot-up
  if (auto f = heartbeat_.poll(now_, nmt_.state())) {
    if (until_[index(FaultKind::heartbeat_loss)]) {
      // The fault: the producer keeps its schedule and its frames go nowhere.
    } else {
      ++counters_.heartbeats;
      queue(*f);
    }
  }
  const NmtState state = nmt_.state();
  if (state != NmtState::pre_operational && state != NmtState::operational) return;
  while (auto f = sdo_->poll(now_)) queue(*f);  // a segmented transfer's timeout abort
  // A controller in bus-off keeps what it has to send; EMCYs wait for the bus (the producer
  // queues 8), cyclic traffic is lost.
  while (auto f = bus_off() ? std::nullopt : emcy_.poll(now_)) {
    if (!emcy_enabled_) continue;  // 0x1014 bit 31: EMCY switched off
    f->id = emcy_id_;
    ++counters_.emcys;
    queue(*f);
  }
  if (state != NmtState::operational) return;
  while (auto f = pdos_->poll(now_)) {
    ++counters_.tpdos;
    queue(*f);
  }
}

void SimDrive::queue(const can::Frame& f) noexcept {
  if (out_count_ == out_.size()) flush();
  out_[out_count_++] = f;
}

void SimDrive::flush() noexcept {
  if (out_count_ == 0) return;
  if (bus_off()) {
    counters_.lost_bus_off += out_count_;
  } else {
    const std::size_t sent = bus_.send(std::span<const can::Frame>(out_.data(), out_count_));
    counters_.frames_out += sent;
    counters_.send_refused += out_count_ - sent;
  }
  out_count_ = 0;
}

}  // namespace saw::canopen::sim
