// One simulated generic I/O node (CiA 401 analog I/O: a gripper's controller) as a CANopen slave: NMT, SDO,
// heartbeat, EMCY, PDOs.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "saw/can/bus.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/sdo_server.hpp"
#include "saw/canopen/sim/fault.hpp"
#include "saw/clock.hpp"

namespace saw::canopen::sim {

class PdoChannels;

struct SimIoNodeConfig {
  std::uint8_t node = 10;
  std::int32_t rate = 50;                     // counts per SYNC the input moves towards the output
  std::optional<std::uint16_t> heartbeat_ms;  // the power-on 0x1017 (ms); none: 0
};

// Its dictionary, built here from CiA 301 and CiA 401: device type 0x1000 (401, analog in and
// out), 0x1001, 0x1016:01 (one consumer), 0x1017, identity 0x1018, RPDO1..4 and TPDO1..4
// (0x1400.., 0x1600.., 0x1800.., 0x1A00..; RPDO1 maps 0x6411:01, TPDO1 0x6401:01, both on SYNC;
// 2..4 not valid), 0x6401:01 "read analog input 16-bit", 0x6411:01 "write analog output 16-bit",
// 0x6443:01 "analog output error mode", 0x6444:01 "analog output error value integer".
LocalDictionary make_io_dictionary(std::uint8_t node);

// The node's cycle is step(now): every frame the bus has (each one checked with
// canopen_data_frame() first), acted on as CiA 301 allows in its NMT state; on each SYNC in
// operational the RPDOs take effect, the application runs — the input (a jaw's measured
// opening) moves towards the output (its commanded opening) by at most `rate` counts — and the
// TPDOs go out; the heartbeat when due. The heartbeat consumer (0x1016:01, from the watched
// node's first heartbeat) fires EMCY 0x8130 and, with the error mode 0x6443:01 at 1 (its default),
// the output takes the error value 0x6444:01 (default 0; clamped to the 16-bit output); so does an RPDO
// that misses its deadline (its event timer 0x1400+k:05, ms, watched from its first reception in
// operational), with EMCY 0x8250. Faults: over-current
// (EMCY 0x2310, the error register's current bit, the output held at 0 for 0.5 s, then the error reset EMCY)
// and heartbeat-loss (its heartbeat stops for the duration). step() neither allocates, locks nor throws
// (remapping a PDO rebuilds it, as on SimDrive).
class SimIoNode {
 public:
  SimIoNode(const SimIoNodeConfig& config, can::Bus& bus);
  ~SimIoNode();
  SimIoNode(const SimIoNode&) = delete;
  SimIoNode& operator=(const SimIoNode&) = delete;

  void step(TimeNs now) noexcept;
  void inject(const Fault& fault) noexcept;
  // An EMCY as the node's application raises one (CiA 301 7.2.7): the error register (0x1001)
  // set to `error_register`, then the message; code 0x0000 is the error reset.
  void raise_emcy(std::uint16_t code, std::uint8_t error_register) noexcept;

  std::uint8_t node() const noexcept { return node_; }
  NmtState nmt_state() const noexcept { return nmt_.state(); }
  std::int16_t output() const noexcept;
  std::int16_t input() const noexcept;
  std::uint64_t syncs() const noexcept { return syncs_; }
  std::uint64_t sdo_requests() const noexcept { return sdo_requests_; }
  std::uint64_t emcys() const noexcept { return emcys_; }
  std::uint64_t heartbeat_events() const noexcept { return heartbeat_events_; }
  std::uint64_t rpdo_timeouts() const noexcept { return rpdo_timeouts_; }  // RPDO deadlines missed

 private:
  class SdoView;
  void dispatch(const can::Frame& f) noexcept;
  void reset(NmtReset what) noexcept;
  void written(ObjectAddress a) noexcept;
  void refresh() noexcept;
  void apply_error_value() noexcept;
  void send(const can::Frame& f) noexcept;

  std::uint8_t node_;
  std::int32_t rate_;
  can::Bus& bus_;
  LocalDictionary dictionary_, defaults_;
  std::unique_ptr<SdoView> view_;
  std::optional<SdoServer> sdo_;
  std::unique_ptr<PdoChannels> pdos_;
  NmtNode nmt_;
  HeartbeatProducer heartbeat_;
  EmcyProducer emcy_;
  TimeNs now_ = 0;
  bool booted_ = false;
  std::uint8_t watched_ = 0;
  TimeNs consumer_time_ = 0;
  std::optional<TimeNs> watched_seen_;
  bool consumer_fired_ = false;
  bool over_current_ = false;
  TimeNs over_current_until_ = 0;
  std::optional<TimeNs> silent_until_;
  std::uint64_t syncs_ = 0, sdo_requests_ = 0, emcys_ = 0, heartbeat_events_ = 0, rpdo_timeouts_ = 0;
};

}  // namespace saw::canopen::sim
