#include "test_drive.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

#include "saw/canopen/cia402.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/sync.hpp"
#include "saw/rt_context.hpp"

namespace saw::canopen::test {
namespace {

using namespace cia402;

void add_pdo_objects(LocalDictionary& d, std::uint8_t node) {
  for (std::uint16_t n = 0; n < 4; ++n) {
    for (const bool rx : {true, false}) {
      const auto comm = static_cast<std::uint16_t>((rx ? 0x1400 : 0x1800) + n);
      const auto map = static_cast<std::uint16_t>((rx ? 0x1600 : 0x1A00) + n);
      const std::uint32_t cob = default_pdo_cob_id(rx ? PdoKind::rpdo : PdoKind::tpdo, n + 1, node);
      d.add_value({comm, 0}, "highest sub-index", DataType::unsigned8, Access::const_, 5u);
      d.add_value({comm, 1}, "COB-ID", DataType::unsigned32, Access::rw, cob | pdo_invalid);
      d.add_value({comm, 2}, "transmission type", DataType::unsigned8, Access::rw, 1u);
      d.add_value({comm, 3}, "inhibit time", DataType::unsigned16, Access::rw, 0u);
      d.add_value({comm, 5}, "event timer", DataType::unsigned16, Access::rw, 0u);
      d.add_value({map, 0}, "number of entries", DataType::unsigned8, Access::rw, 0u);
      for (std::uint8_t s = 1; s <= 8; ++s)
        d.add_value({map, s}, "mapped object", DataType::unsigned32, Access::rw, 0u);
    }
  }
}

}  // namespace

TestDrive::TestDrive(RingNetwork& network, TestDriveConfig config)
    : config_(config),
      port_(network.attach("drive " + std::to_string(config.node))),
      nmt_(config.node),
      heartbeat_(config.node, 0),
      emcy_(config.node) {
  auto& d = dictionary_;
  d.add_value({0x1000, 0}, "device type", DataType::unsigned32, Access::ro, 0x00020192u);
  d.add_value({0x1001, 0}, "error register", DataType::unsigned8, Access::ro, 0u);
  d.add_value({0x1016, 0}, "highest sub-index", DataType::unsigned8, Access::const_, 1u);
  d.add_value({0x1016, 1}, "consumer heartbeat time", DataType::unsigned32, Access::rw, 0u);
  d.add_value({0x1017, 0}, "producer heartbeat time", DataType::unsigned16, Access::rw, 0u);
  d.add_value(object::abort_connection_option_code, "abort connection option code", DataType::integer16,
              Access::rw, 1);
  d.add_value(object::error_code, "error code", DataType::unsigned16, Access::ro, 0u);
  d.add_value(object::controlword, "controlword", DataType::unsigned16, Access::rww, 0u);
  d.add_value(object::statusword, "statusword", DataType::unsigned16, Access::rwr, 0u);
  d.add_value(object::modes_of_operation, "modes of operation", DataType::integer8, Access::rw, 0);
  d.add_value(object::modes_of_operation_display, "modes of operation display", DataType::integer8,
              Access::rwr, 0);
  d.add_value(object::position_actual_value, "position actual", DataType::integer32, Access::rwr,
              config.initial_position);
  d.add_value(object::velocity_actual_value, "velocity actual", DataType::integer32, Access::rwr, 0);
  d.add_value(object::torque_actual_value, "torque actual", DataType::integer16, Access::rwr, 0);
  d.add_value(object::target_position, "target position", DataType::integer32, Access::rww, 0);
  d.add_value(object::target_velocity, "target velocity", DataType::integer32, Access::rww, 0);
  d.add_value(object::target_torque, "target torque", DataType::integer16, Access::rww, 0);
  d.add_value(object::supported_drive_modes, "supported drive modes", DataType::unsigned32, Access::ro,
              supported_mode_bit(csp) | supported_mode_bit(csv) | supported_mode_bit(cst));
  add_pdo_objects(d, config.node);
  position_ = config.initial_position;
  writes_.reserve(4096);
  d.on_write([this](ObjectAddress a, std::span<const std::uint8_t> data) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < data.size() && i < 4; ++i)
      v |= static_cast<std::uint32_t>(data[i]) << (8 * i);
    if (a == object::modes_of_operation) {
      if (!drive_.request_mode(static_cast<Mode>(static_cast<std::int8_t>(data[0]))))
        return SdoAbort::invalid_value;
      (void)dictionary_.set(object::modes_of_operation_display, static_cast<std::int8_t>(data[0]));
    }
    if (writes_.size() < writes_.capacity()) writes_.push_back({a, v});
    return SdoAbort::none;
  });
  server_ = std::make_unique<SdoServer>(SdoServerConfig{SdoChannel::of_node(config.node)}, dictionary_);
  nmt_.boot();
}

void TestDrive::reboot() noexcept {
  for (std::uint16_t n = 0; n < 4; ++n)
    for (const bool rx : {true, false}) {
      const auto kind = rx ? PdoKind::rpdo : PdoKind::tpdo;
      const std::uint32_t cob = default_pdo_cob_id(kind, static_cast<std::uint16_t>(n + 1), config_.node);
      (void)dictionary_.set({static_cast<std::uint16_t>((rx ? 0x1400 : 0x1800) + n), 1}, cob | pdo_invalid);
      (void)dictionary_.set({static_cast<std::uint16_t>((rx ? 0x1600 : 0x1A00) + n), 0}, std::uint8_t{0});
      (void)dictionary_.set({static_cast<std::uint16_t>((rx ? 0x1400 : 0x1800) + n), 5}, std::uint16_t{0});
    }
  (void)dictionary_.set({0x1017, 0}, std::uint16_t{0});
  (void)dictionary_.set({0x1016, 1}, std::uint32_t{0});
  (void)dictionary_.set(object::modes_of_operation, std::int8_t{0});
  (void)dictionary_.set(object::modes_of_operation_display, std::int8_t{0});
  drive_ = cia402::Drive{};
  fault_ = false;
  velocity_ = 0;
  rpdos_.clear();
  tpdos_.clear();
  rpdo_objects_.clear();
  tpdo_objects_.clear();
  rpdo_deadlines_.clear();
  rpdo_seen_.clear();
  rpdo_fired_.clear();
  nmt_ = NmtNode(config_.node);
  nmt_.boot();
}

std::int32_t TestDrive::target_position() const noexcept {
  std::int32_t v = 0;
  (void)dictionary_.get(object::target_position, v);
  return v;
}
std::int16_t TestDrive::target_torque() const noexcept {
  std::int16_t v = 0;
  (void)dictionary_.get(object::target_torque, v);
  return v;
}
std::int32_t TestDrive::target_velocity() const noexcept {
  std::int32_t v = 0;
  (void)dictionary_.get(object::target_velocity, v);
  return v;
}

void TestDrive::raise_fault(std::uint16_t code) noexcept {
  fault_ = true;
  (void)dictionary_.set(object::error_code, code);
  (void)emcy_.raise(code, error_register::generic | error_register::current);
}

void TestDrive::clear_fault() noexcept {
  fault_ = false;
  (void)emcy_.clear();
}

void TestDrive::send(const can::Frame& f) noexcept {
  if (!silent_) port_.send(std::span(&f, 1));
}

// Set-up (at NMT start): the PDOs as the master configured them through 0x1400.. and 0x1600...
void TestDrive::build_pdos() {
  rpdos_.clear();
  tpdos_.clear();
  rpdo_objects_.clear();
  tpdo_objects_.clear();
  rpdo_deadlines_.clear();
  rpdo_seen_.clear();
  rpdo_fired_.clear();
  for (std::uint16_t n = 0; n < 4; ++n)
    for (const bool rx : {true, false}) {
      std::uint32_t cob = 0;
      std::uint8_t count = 0;
      (void)dictionary_.get({static_cast<std::uint16_t>((rx ? 0x1400 : 0x1800) + n), 1}, cob);
      const auto map = static_cast<std::uint16_t>((rx ? 0x1600 : 0x1A00) + n);
      (void)dictionary_.get({map, 0}, count);
      if ((cob & pdo_invalid) != 0 || count == 0) continue;
      PdoMapping m;
      m.kind = rx ? PdoKind::rpdo : PdoKind::tpdo;
      m.number = static_cast<std::uint16_t>(n + 1);
      m.cob_id = cob & CAN_SFF_MASK;
      std::vector<ObjectAddress> objects;
      for (std::uint8_t s = 1; s <= count; ++s) {
        std::uint32_t v = 0;
        (void)dictionary_.get({map, s}, v);
        const PdoEntry e = PdoEntry::from_u32(v);
        const Entry* entry = dictionary_.find(e.address);
        m.map(PdoEntry::from_u32(v, entry ? std::optional(entry->type) : std::nullopt));
        objects.push_back(e.address);
      }
      if (rx) {
        std::uint16_t timer = 0;
        (void)dictionary_.get({static_cast<std::uint16_t>(0x1400 + n), 5}, timer);
        rpdos_.emplace_back(m);
        rpdo_objects_.push_back(objects);
        rpdo_deadlines_.push_back(static_cast<TimeNs>(timer) * 1'000'000);
        rpdo_seen_.emplace_back();
        rpdo_fired_.push_back(false);
      } else {
        tpdos_.emplace_back(m);
        tpdo_objects_.push_back(objects);
      }
    }
}

void TestDrive::on_sync(TimeNs now) noexcept {
  ++syncs_;
  const double dt = last_sync_ == 0 ? 0.001 : static_cast<double>(now - last_sync_) * 1e-9;
  last_sync_ = now;
  (void)dictionary_.get(object::controlword, controlword_);
  drive_.update({controlword_, fault_, std::abs(velocity_) < 1.0, true});
  if (!drive_.following()) {
    velocity_ = 0;
  } else if (drive_.mode_display() == csp) {
    const auto target = static_cast<double>(target_position());
    const double step = std::clamp(target - position_, -config_.csp_max_step, config_.csp_max_step);
    velocity_ = step / dt;
    position_ += step;
  } else if (drive_.mode_display() == csv) {
    velocity_ = target_velocity();
    position_ += velocity_ * dt;
  } else if (drive_.mode_display() == cst) {
    velocity_ += (config_.torque_gain * target_torque() - config_.damping * velocity_) * dt;
    position_ += velocity_ * dt;
  }
  (void)dictionary_.set(object::statusword, drive_.statusword());
  (void)dictionary_.set(object::position_actual_value, static_cast<std::int32_t>(std::lround(position_)));
  (void)dictionary_.set(object::velocity_actual_value, static_cast<std::int32_t>(std::lround(velocity_)));
  (void)dictionary_.set(object::torque_actual_value, drive_.following() && drive_.mode_display() == cst
                                                         ? target_torque()
                                                         : std::int16_t{0});
  for (std::size_t p = 0; p < tpdos_.size(); ++p) {
    for (std::size_t s = 0; s < tpdo_objects_[p].size(); ++s) {
      const Entry* e = dictionary_.find(tpdo_objects_[p][s]);
      Number n;
      if (e != nullptr && decode(e->type, e->value, n) == Codec::ok) (void)tpdos_[p].set_number(s, n);
    }
    send(tpdos_[p].frame());
  }
}

// The heartbeat consumer (CiA 301 0x1016:01: bits 16..23 the watched node, 0..15 its time in ms;
// 0 or node 0: not used). A new value starts over: monitoring begins with the watched node's
// next heartbeat. On expiry the heartbeat event: EMCY 0x8130 and 0x6007 (abort_connection), then
// CiA 301's error behaviour for a communication error (0x1029's default: operational to
// pre-operational).
void TestDrive::watch_master(TimeNs now) noexcept {
  std::uint32_t c = 0;
  (void)dictionary_.get({0x1016, 1}, c);
  if (c != consumer_entry_) {
    consumer_entry_ = c;
    consumer_time_ = static_cast<TimeNs>(c & 0xFFFF) * 1'000'000;
    consumer_node_ = consumer_time_ > 0 ? static_cast<std::uint8_t>((c >> 16) & 0x7F) : 0;
    consumer_seen_.reset();
    consumer_fired_ = false;
  }
  if (consumer_node_ == 0 || !consumer_seen_ || consumer_fired_ || now - *consumer_seen_ <= consumer_time_)
    return;
  consumer_fired_ = true;
  ++heartbeat_events_;
  abort_connection(0x8130);
  if (nmt_.state() == NmtState::operational) set_nmt(NmtCommand::enter_pre_operational);
}

// CiA 301's RPDO deadline (an RPDO's event timer, 0x1400+k:05, ms; 0: off): monitoring starts
// with the RPDO's first reception in operational and restarts after leaving it. On expiry EMCY
// 0x8250 (RPDO timeout) and 0x6007's reaction, once per silence; the drive stays operational (its
// master is alive: only its RPDOs stopped), so the master hears the EMCY and its heartbeat.
void TestDrive::watch_rpdos(TimeNs now) noexcept {
  for (std::size_t p = 0; p < rpdo_seen_.size(); ++p) {
    if (nmt_.state() != NmtState::operational) rpdo_seen_[p].reset();
    if (rpdo_deadlines_[p] == 0 || !rpdo_seen_[p] || rpdo_fired_[p] ||
        now - *rpdo_seen_[p] <= rpdo_deadlines_[p])
      continue;
    rpdo_fired_[p] = true;
    ++rpdo_timeouts_;
    abort_connection(0x8250);
  }
}

// A communication error's EMCY, then CiA 402's abort connection option 0x6007 (1 fault, 2 disable
// voltage, 3 quick stop; 0 and others: nothing) taken at once, without waiting for a SYNC.
void TestDrive::abort_connection(std::uint16_t code) noexcept {
  (void)emcy_.raise(code, error_register::generic | error_register::communication);
  std::int16_t option = 0;
  (void)dictionary_.get(object::abort_connection_option_code, option);
  const bool moving =
      drive_.state() == State::operation_enabled || drive_.state() == State::quick_stop_active;
  if (moving && (option == 1 || option == 2 || option == 3)) {
    // The drive acts as if its controlword had said so (disable voltage, quick stop) or as at a
    // fault condition; a quick stop or fault reaction ends at standstill (no motion without SYNC).
    const std::uint16_t local = option == 2 ? 0x0000 : option == 3 ? 0x0002 : controlword_;
    velocity_ = 0;
    drive_.update({local, option == 1, true, true});
    drive_.update({local, false, true, true});
    if (option == 1) (void)dictionary_.set(object::error_code, code);
    (void)dictionary_.set(object::statusword, drive_.statusword());
  }
}

void TestDrive::step(TimeNs now) noexcept {
  port_.now = now;
  can::Received in[64];
  for (std::size_t n; (n = port_.receive(in)) > 0;) {
    for (std::size_t i = 0; i < n; ++i) {
      const can::Frame& f = in[i].frame;
      if (consumer_node_ != 0 && f.can_id() == cob::heartbeat + consumer_node_ && parse_heartbeat(f)) {
        consumer_seen_ = now;  // CiA 301: monitoring starts with the first heartbeat
        consumer_fired_ = false;
        continue;
      }
      switch (nmt_.on_frame(f)) {
        case NmtReset::communication:
        case NmtReset::application:
          rpdos_.clear();  // the PDOs are built again at the next NMT start
          tpdos_.clear();
          rpdo_objects_.clear();
          tpdo_objects_.clear();
          rpdo_deadlines_.clear();
          rpdo_seen_.clear();
          rpdo_fired_.clear();
          nmt_.boot();
          heartbeat_.start(now);
          continue;
        case NmtReset::none:
          break;
      }
      if (parse_nmt(f)) {
        if (nmt_.state() == NmtState::operational && rpdos_.empty() && tpdos_.empty()) {
          // The drive's own set-up at NMT start (it allocates): another device's, not the master's
          // RT path, also when the master's cycle steps it (a drive configured again mid-run).
          const bool rt = saw::detail::in_rt_context;
          saw::detail::in_rt_context = false;
          build_pdos();
          saw::detail::in_rt_context = rt;
        }
        continue;
      }
      if (nmt_.state() == NmtState::stopped) continue;
      server_->on_frame(f, now);
      // A SYNC acts where it stands in the stream: on the RPDOs received before it (a master's
      // last SYNC before its NMT pre-operational still takes effect).
      if (parse_sync(f)) {
        if (nmt_.state() == NmtState::operational) on_sync(now);
        continue;
      }
      if (nmt_.state() != NmtState::operational) continue;
      for (std::size_t p = 0; p < rpdos_.size(); ++p) {
        if (rpdos_[p].receive(f) != PdoReceive::ok) continue;
        ++rpdo_frames_;
        rpdo_seen_[p] = now;
        rpdo_fired_[p] = false;
        for (std::size_t s = 0; s < rpdo_objects_[p].size(); ++s) {
          Number v;
          if (rpdos_[p].get_number(s, v) == Codec::ok)
            std::visit([&](auto x) { (void)dictionary_.set(rpdo_objects_[p][s], x); }, v);
        }
      }
    }
  }
  std::uint16_t hb = 0;
  (void)dictionary_.get({0x1017, 0}, hb);
  if (hb != heartbeat_ms_) {
    heartbeat_ms_ = hb;
    heartbeat_.set_period(static_cast<TimeNs>(hb) * 1'000'000, now);
  }
  watch_master(now);
  watch_rpdos(now);
  if (auto f = nmt_.poll()) send(*f);
  if (auto f = server_->poll(now)) send(*f);
  if (auto f = emcy_.poll(now)) send(*f);
  if (auto f = heartbeat_.poll(now, nmt_.state()); f && !heartbeat_silent_) send(*f);
}

}  // namespace saw::canopen::test
