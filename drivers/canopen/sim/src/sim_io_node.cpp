#include "saw/canopen/sim/sim_io_node.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "pdo_channels.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/sync.hpp"

namespace saw::canopen::sim {
namespace {

constexpr TimeNs ms = 1'000'000;
constexpr ObjectAddress heartbeat_time{0x1017, 0};
constexpr ObjectAddress consumer{0x1016, 1};
constexpr ObjectAddress analog_input{0x6401, 1};
constexpr ObjectAddress analog_output{0x6411, 1};
constexpr ObjectAddress error_mode{0x6443, 1}, error_value{0x6444, 1};
constexpr std::uint16_t emcy_heartbeat = 0x8130, emcy_over_current = 0x2310, emcy_rpdo_timeout = 0x8250;

void add_count(LocalDictionary& d, std::uint16_t index, std::string name, std::uint8_t n,
               Access a = Access::ro) {
  d.add_value(ObjectAddress{index, 0}, std::move(name), DataType::unsigned8, a, n);
}

}  // namespace

LocalDictionary make_io_dictionary(std::uint8_t node) {
  LocalDictionary d;
  d.add_value(ObjectAddress{0x1000, 0}, "Device type", DataType::unsigned32, Access::ro,
              std::uint32_t{0x000C0191});  // CiA 401, analog inputs and outputs
  d.add_value(ObjectAddress{0x1001, 0}, "Error register", DataType::unsigned8, Access::ro, std::uint8_t{0});
  add_count(d, 0x1016, "Consumer heartbeat time", 1);
  d.add_value(consumer, "Consumer heartbeat time 1", DataType::unsigned32, Access::rw, std::uint32_t{0});
  d.add_value(heartbeat_time, "Producer heartbeat time", DataType::unsigned16, Access::rw, std::uint16_t{0});
  add_count(d, 0x1018, "Identity", 2);
  d.add_value(ObjectAddress{0x1018, 1}, "Vendor-ID", DataType::unsigned32, Access::ro, std::uint32_t{0x5A5});
  d.add_value(ObjectAddress{0x1018, 2}, "Product code", DataType::unsigned32, Access::ro, std::uint32_t{401});
  for (std::uint16_t n = 1; n <= 4; ++n) {
    const bool first = n == 1;
    const auto rpdo = static_cast<std::uint16_t>(0x1400 + n - 1),
               tpdo = static_cast<std::uint16_t>(0x1800 + n - 1);
    add_count(d, rpdo, "RPDO communication", 5);
    d.add_value(ObjectAddress{rpdo, 1}, "COB-ID", DataType::unsigned32, Access::rw,
                default_pdo_cob_id(PdoKind::rpdo, n, node) | (first ? 0u : 0x80000000u));
    d.add_value(ObjectAddress{rpdo, 2}, "Transmission type", DataType::unsigned8, Access::rw,
                std::uint8_t{1});
    d.add_value(ObjectAddress{rpdo, 5}, "Event timer", DataType::unsigned16, Access::rw, std::uint16_t{0});
    add_count(d, tpdo, "TPDO communication", 5);
    d.add_value(ObjectAddress{tpdo, 1}, "COB-ID", DataType::unsigned32, Access::rw,
                default_pdo_cob_id(PdoKind::tpdo, n, node) | (first ? 0u : 0x80000000u));
    d.add_value(ObjectAddress{tpdo, 2}, "Transmission type", DataType::unsigned8, Access::rw,
                std::uint8_t{1});
    d.add_value(ObjectAddress{tpdo, 3}, "Inhibit time", DataType::unsigned16, Access::rw, std::uint16_t{0});
    d.add_value(ObjectAddress{tpdo, 5}, "Event timer", DataType::unsigned16, Access::rw, std::uint16_t{0});
    for (const std::uint16_t map :
         {static_cast<std::uint16_t>(0x1600 + n - 1), static_cast<std::uint16_t>(0x1A00 + n - 1)}) {
      const std::uint32_t entry = !first ? 0u : map == 0x1600 ? 0x64110110u : 0x64010110u;
      add_count(d, map, "PDO mapping", first ? 1 : 0, Access::rw);
      for (std::uint8_t k = 1; k <= 8; ++k)
        d.add_value(ObjectAddress{map, k}, "Mapped object " + std::to_string(k), DataType::unsigned32,
                    Access::rw, k == 1 ? entry : 0u);
    }
  }
  add_count(d, 0x6401, "Read analog input 16-bit", 1);
  Entry in{"Analog input 1", DataType::integer16, Access::ro, {0, 0}, {}, {}, 0, true};
  d.add(analog_input, in);
  add_count(d, 0x6411, "Write analog output 16-bit", 1);
  Entry out{"Analog output 1", DataType::integer16, Access::rww, {0, 0}, {}, {}, 0, true};
  d.add(analog_output, out);
  // CiA 401's error behaviour of the analog output: mode 1 takes the error value on a device
  // failure or a communication loss (0: the output keeps its value); the error value is an
  // INTEGER32 in the output's counts. Both default as CiA 401 says (1, 0).
  add_count(d, 0x6443, "Analog output error mode", 1);
  d.add_value(error_mode, "Analog output 1 error mode", DataType::unsigned8, Access::rw, std::uint8_t{1});
  add_count(d, 0x6444, "Analog output error value integer", 1);
  d.add_value(error_value, "Analog output 1 error value", DataType::integer32, Access::rw, std::int32_t{0});
  return d;
}

// The SDO server's view: the dictionary, then what a stored write changes.
class SimIoNode::SdoView final : public ObjectDictionary {
 public:
  explicit SdoView(SimIoNode& n) : node_(n) {}
  SdoAbort check_download(ObjectAddress a, std::optional<std::size_t> size) noexcept override {
    return node_.dictionary_.check_download(a, size);
  }
  SdoAbort read(ObjectAddress a, std::span<std::uint8_t> out, std::size_t& size) noexcept override {
    return node_.dictionary_.read(a, out, size);
  }
  SdoAbort write(ObjectAddress a, std::span<const std::uint8_t> data, bool size_indicated) noexcept override {
    const SdoAbort r = node_.dictionary_.write(a, data, size_indicated);
    if (r == SdoAbort::none) node_.written(a);
    return r;
  }

 private:
  SimIoNode& node_;
};

SimIoNode::SimIoNode(const SimIoNodeConfig& config, can::Bus& bus)
    : node_(config.node),
      rate_(config.rate),
      bus_(bus),
      dictionary_(make_io_dictionary(config.node)),
      view_(std::make_unique<SdoView>(*this)),
      pdos_(std::make_unique<PdoChannels>(dictionary_)),
      nmt_(config.node),
      heartbeat_(config.node, 0),
      emcy_(config.node, 0) {
  if (!valid_node_id(config.node)) throw std::invalid_argument("simulated I/O node: node-ID must be 1..127");
  if (config.rate <= 0) throw std::invalid_argument("simulated I/O node: rate must be above 0");
  if (config.heartbeat_ms) (void)dictionary_.set(heartbeat_time, *config.heartbeat_ms);
  defaults_ = dictionary_;  // before the hook: restoring defaults goes around it
  dictionary_.on_write([this](ObjectAddress a, std::span<const std::uint8_t> data) {
    if (!PdoChannels::is_pdo_parameter(a.index)) return SdoAbort::none;
    Number n;
    std::uint64_t u = 0;
    const Entry* e = dictionary_.find(a);
    if (e == nullptr || decode(e->type, data, n) != Codec::ok || to_value(n, u) != Codec::ok)
      return SdoAbort::none;  // the dictionary's own checks answer
    return pdos_->check_write(a, u);
  });
  reset(NmtReset::application);
  booted_ = false;  // power-on is the first step()
  nmt_ = NmtNode(node_);
}

SimIoNode::~SimIoNode() = default;

std::int16_t SimIoNode::output() const noexcept {
  std::int16_t v = 0;
  (void)dictionary_.get(analog_output, v);
  return v;
}

std::int16_t SimIoNode::input() const noexcept {
  std::int16_t v = 0;
  (void)dictionary_.get(analog_input, v);
  return v;
}

void SimIoNode::refresh() noexcept {
  std::uint16_t hb = 0;
  (void)dictionary_.get(heartbeat_time, hb);
  heartbeat_.set_period(hb * ms, now_);
  std::uint32_t c = 0;
  (void)dictionary_.get(consumer, c);
  consumer_time_ = static_cast<TimeNs>(c & 0xFFFF) * ms;
  watched_ = consumer_time_ > 0 ? static_cast<std::uint8_t>((c >> 16) & 0x7F) : 0;
  watched_seen_.reset();  // CiA 301: monitoring starts with the next heartbeat
  consumer_fired_ = false;
}

void SimIoNode::reset(NmtReset what) noexcept {
  const std::uint16_t first = what == NmtReset::application ? 0x0000 : 0x1000;
  const std::uint16_t last = what == NmtReset::application ? 0xFFFF : 0x1FFF;
  for (const auto& [address, entry] : defaults_.entries()) {
    if (address.index < first || address.index > last) continue;
    Number n;
    if (decode(entry.type, entry.value, n) == Codec::ok) (void)set_number(dictionary_, address, n);
  }
  if (what == NmtReset::application) over_current_ = false;
  refresh();
  pdos_->rebuild_all();
  sdo_.emplace(SdoServerConfig{SdoChannel::of_node(node_)}, *view_);  // a transfer dies with the reset
  nmt_.boot();
  heartbeat_.start(now_);
}

void SimIoNode::written(ObjectAddress a) noexcept {
  if (PdoChannels::is_pdo_parameter(a.index))
    pdos_->written(a);
  else if (a == heartbeat_time || a == consumer)
    refresh();
}

void SimIoNode::inject(const Fault& f) noexcept {
  switch (f.kind) {
    case FaultKind::over_current:
      over_current_ = true;
      over_current_until_ = now_ + 500 * ms;  // an event: the output cut for 0.5 s
      (void)dictionary_.set(ObjectAddress{0x1001, 0}, std::uint8_t{0x03});  // generic, current
      (void)dictionary_.set(analog_output, std::int16_t{0});
      ++emcys_;
      (void)emcy_.raise(emcy_over_current, 0x03);
      break;
    case FaultKind::heartbeat_loss:
      silent_until_ = f.duration > 0 ? now_ + f.duration : std::numeric_limits<TimeNs>::max();
      break;
    default:  // the drive's kinds (following error, bus-off, SDO aborts) are not simulated here
      break;
  }
}

void SimIoNode::raise_emcy(std::uint16_t code, std::uint8_t error_register) noexcept {
  (void)dictionary_.set(ObjectAddress{0x1001, 0}, error_register);
  ++emcys_;
  (void)(code == 0 ? emcy_.clear(error_register) : emcy_.raise(code, error_register));
}

void SimIoNode::apply_error_value() noexcept {
  std::uint8_t mode = 0;
  std::int32_t value = 0;
  if (dictionary_.get(error_mode, mode) != Codec::ok || mode != 1 ||
      dictionary_.get(error_value, value) != Codec::ok)
    return;
  const std::int32_t held = std::clamp<std::int32_t>(value, std::numeric_limits<std::int16_t>::min(),
                                                     std::numeric_limits<std::int16_t>::max());
  (void)dictionary_.set(analog_output, static_cast<std::int16_t>(held));
}

void SimIoNode::send(const can::Frame& f) noexcept { (void)bus_.send(std::span(&f, 1)); }

void SimIoNode::dispatch(const can::Frame& f) noexcept {
  if (!canopen_data_frame(f)) return;
  const std::uint32_t id = f.can_id();
  if (id == cob::nmt) {
    const auto request = parse_nmt(f);
    if (!request || !request->addresses(node_)) return;
    const NmtState before = nmt_.state();
    const NmtReset r = nmt_.on_frame(f);
    if (r != NmtReset::none)
      reset(r);
    else if (nmt_.state() == NmtState::operational && before != NmtState::operational)
      pdos_->start(now_);
    return;
  }
  if (watched_ != 0 && id == cob::heartbeat + watched_ && parse_heartbeat(f)) {
    watched_seen_ = now_;
    consumer_fired_ = false;
    return;
  }
  const NmtState state = nmt_.state();
  if (state != NmtState::pre_operational && state != NmtState::operational) return;
  if (id == SdoChannel::of_node(node_).request) {
    ++sdo_requests_;
    sdo_->on_frame(f, now_);
    while (const auto r = sdo_->poll(now_)) send(*r);
    return;
  }
  if (state != NmtState::operational) return;
  if (id == cob::sync && parse_sync(f)) {
    ++syncs_;
    pdos_->on_sync(now_);  // RPDOs take effect; TPDOs sample what the application publishes below
    if (over_current_) (void)dictionary_.set(analog_output, std::int16_t{0});
    const std::int32_t in = input(), out = output();
    (void)dictionary_.set(analog_input, static_cast<std::int16_t>(in + std::clamp(out - in, -rate_, rate_)));
    return;
  }
  (void)pdos_->on_frame(f);
}

void SimIoNode::step(TimeNs now) noexcept {
  now_ = now;
  if (!booted_) {  // power-on
    booted_ = true;
    nmt_.boot();
    heartbeat_.start(now);
  }
  can::Received rx[32];
  for (int batch = 0; batch < 32; ++batch) {
    const std::size_t n = bus_.receive(rx);
    for (std::size_t i = 0; i < n; ++i) dispatch(rx[i].frame);
    if (n < std::size(rx)) break;
  }
  // The heartbeat consumer: the watched node (the master) silent for its time.
  if (watched_ != 0 && watched_seen_ && !consumer_fired_ && now - *watched_seen_ > consumer_time_) {
    consumer_fired_ = true;
    ++heartbeat_events_;
    ++emcys_;
    (void)emcy_.raise(emcy_heartbeat, 0x11);  // generic, communication
    apply_error_value();
  }
  // CiA 301's RPDO deadline (0x1400:05, from the first RPDO in operational): the same error
  // values, EMCY 0x8250 (RPDO timeout); the next RPDO carries the outputs again.
  if (nmt_.state() == NmtState::operational)
    while (pdos_->expired_rpdo(now) != 0) {
      ++rpdo_timeouts_;
      ++emcys_;
      (void)emcy_.raise(emcy_rpdo_timeout, 0x11);
      apply_error_value();
    }
  if (silent_until_ && now >= *silent_until_) silent_until_.reset();
  if (over_current_ && now >= over_current_until_) {  // the cause gone: error reset, outputs again
    over_current_ = false;
    (void)dictionary_.set(ObjectAddress{0x1001, 0}, std::uint8_t{0});
    (void)emcy_.clear(0);
  }
  if (const auto b = nmt_.poll()) send(*b);
  if (const auto h = heartbeat_.poll(now, nmt_.state()); h && !silent_until_) send(*h);
  while (const auto e = emcy_.poll(now)) send(*e);
  if (nmt_.state() == NmtState::operational)
    while (const auto t = pdos_->poll(now)) send(*t);
}

}  // namespace saw::canopen::sim
