#include "saw/canopen/startup.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "saw/canopen/nmt.hpp"
#include "saw/canopen/sdo_client.hpp"

namespace saw::canopen {

std::string_view to_string(StartupPhase p) noexcept {
  switch (p) {
    case StartupPhase::reset:
      return "NMT reset communication";
    case StartupPhase::boot:
      return "waiting for boot-up";
    case StartupPhase::identify:
      return "identity";
    case StartupPhase::configure:
      return "SDO configuration";
    case StartupPhase::start:
      return "NMT start";
    case StartupPhase::operational:
      return "waiting for an operational heartbeat";
    case StartupPhase::done:
      return "done";
    case StartupPhase::failed:
      return "failed";
  }
  return "unknown";
}

std::vector<StartupWrite> node_writes(std::span<const PdoMapping> pdos, TimeNs heartbeat_period,
                                      std::uint8_t master_node, TimeNs master_timeout,
                                      const RpdoDeadline& deadline) {
  std::vector<StartupWrite> out;
  const auto watched = [&](const PdoMapping& m) {
    return deadline.time && m.kind == PdoKind::rpdo && m.enabled &&
           std::find(deadline.unwritable.begin(), deadline.unwritable.end(), m.number) ==
               deadline.unwritable.end();
  };
  for (PdoMapping m : pdos) {
    // Disabling a PDO the node may not have (the defaults disable 2..4) is allowed to fail.
    const bool optional = !m.enabled;
    // The deadline owns an RPDO's event timer: an EDS default is not written before it.
    if (watched(m)) m.event_timer = 0;
    for (const SdoWrite& w : configuration_writes(m)) out.push_back({w, optional});
  }
  // After the PDOs (CiA 301 lets the event timer change while the PDO is valid). Optional: a node
  // without sub-index 05h cannot watch, which is no reason to refuse it.
  for (const PdoMapping& m : pdos)
    if (watched(m))
      out.push_back(
          {{{m.communication_index(), 5}, DataType::unsigned16, deadline_ms(*deadline.time)}, true});
  const auto heartbeat_ms = static_cast<std::uint32_t>(heartbeat_period / 1'000'000);
  out.push_back({{{0x1017, 0}, DataType::unsigned16, heartbeat_ms}, false});
  if (master_timeout > 0) {
    const auto consumer_ms = static_cast<std::uint32_t>(master_timeout / 1'000'000);
    out.push_back(
        {{{0x1016, 1}, DataType::unsigned32, std::uint32_t{master_node} << 16 | consumer_ms}, false});
  }
  return out;
}

NodeSetup setup_of(const AxisConfig& axis) {
  check(axis);
  return {axis.name, axis.node, axis.identity, startup_writes(axis)};
}

std::vector<StartupWrite> startup_writes(const AxisConfig& axis) {
  std::vector<StartupWrite> out = node_writes(axis.pdos, axis.heartbeat_period, axis.master_node,
                                              axis.master_timeout, axis.rpdo_deadline);
  // "none" asks nothing of a drive: one without 0x6007 does nothing anyway.
  out.push_back({{cia402::object::abort_connection_option_code, DataType::integer16,
                  static_cast<std::uint32_t>(static_cast<std::uint16_t>(axis.abort_connection))},
                 axis.abort_connection == AbortConnection::none});
  for (const SdoWrite& w : axis.writes) out.push_back({w, false});
  out.push_back({{cia402::object::modes_of_operation, DataType::integer8,
                  static_cast<std::uint32_t>(static_cast<std::uint8_t>(axis.mode))},
                 false});
  return out;
}

Number startup_value(const SdoWrite& w) noexcept {
  if (type_class(w.type) != TypeClass::signed_integer) return std::uint64_t{w.value};
  switch (size_of(w.type)) {
    case 1:
      return std::int64_t{static_cast<std::int8_t>(w.value)};
    case 2:
      return std::int64_t{static_cast<std::int16_t>(w.value)};
    default:
      return std::int64_t{static_cast<std::int32_t>(w.value)};
  }
}

struct StartupSequence::Node {
  Node(NodeSetup a, TimeNs sdo_timeout)
      : axis(std::move(a)),
        sdo(SdoClientConfig{SdoChannel::of_node(axis.node), sdo_timeout, 64}),
        writes(axis.writes) {}
  NodeSetup axis;
  SdoClient sdo;
  std::vector<StartupWrite> writes;
  std::size_t next = 0;        // the write in flight (or the next one)
  bool started = false;        // `next` was handed to the SDO client
  std::size_t identified = 0;  // identity objects read and found as expected
  bool booted = false;
  bool operational = false;

  std::string who() const { return "node " + std::to_string(axis.node) + " ('" + axis.name + "')"; }
};

namespace {
std::vector<NodeSetup> setups_of(std::span<const AxisConfig> axes) {
  std::vector<NodeSetup> out;
  for (const AxisConfig& a : axes) out.push_back(setup_of(a));
  return out;
}
}  // namespace

StartupSequence::StartupSequence(can::Bus& bus, std::span<const AxisConfig> axes, StartupConfig config)
    : StartupSequence(bus, setups_of(axes), config) {}

StartupSequence::StartupSequence(can::Bus& bus, std::vector<NodeSetup> nodes, StartupConfig config)
    : bus_(bus), config_(config) {
  for (NodeSetup& n : nodes) nodes_.push_back(std::make_unique<Node>(std::move(n), config.sdo_timeout));
  written_.resize(nodes_.size());
}

StartupSequence::~StartupSequence() = default;

void StartupSequence::send(const can::Frame& f) {
  if (bus_.send(std::span(&f, 1)) != 1)
    fail("the bus refused a frame (state " + std::string(can::to_string(bus_.state())) + ")");
}

void StartupSequence::fail(const std::string& what) {
  if (phase_ == StartupPhase::failed) return;
  error_ = "CANopen start-up on " + bus_.name() + " (" + std::string(to_string(phase_)) + "): " + what;
  phase_ = StartupPhase::failed;
}

void StartupSequence::receive(TimeNs now) {
  can::Received in[64];
  for (std::size_t n; (n = bus_.receive(in)) > 0;) {
    for (std::size_t i = 0; i < n; ++i) {
      const can::Frame& f = in[i].frame;
      const auto hb = parse_heartbeat(f);
      for (auto& node : nodes_) {
        node->sdo.on_frame(f, now);
        if (!hb || hb->node != node->axis.node) continue;
        // Only what follows our reset counts: a heartbeat from before it says nothing.
        if (hb->boot_up() && phase_ == StartupPhase::boot) node->booted = true;
        if (hb->state == NmtState::operational && phase_ == StartupPhase::operational)
          node->operational = true;
      }
    }
  }
}

namespace {
std::string hex(std::uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08X", v);
  return b;
}
}  // namespace

// The drive is the one its EDS/DCF describes, before anything is written to it: a wrong file
// or a wrong drive on the node would take PDO maps and a mode meant for another device.
bool StartupSequence::identify(TimeNs now) {
  struct Check {
    ObjectAddress address;
    const char* what;
    std::uint32_t DriveIdentity::*expected;
  };
  static constexpr Check checks[] = {{{0x1000, 0}, "device type (0x1000)", &DriveIdentity::device_type},
                                     {{0x1018, 1}, "vendor-ID (0x1018:01)", &DriveIdentity::vendor_id},
                                     {{0x1018, 2}, "product code (0x1018:02)", &DriveIdentity::product_code}};
  bool all_done = true;
  for (auto& node : nodes_) {
    Node& n = *node;
    if (!n.axis.identity) continue;
    const DriveIdentity& id = *n.axis.identity;
    if (n.started && !n.sdo.busy()) {
      const Check& c = checks[n.identified];
      const SdoResult& r = n.sdo.result();
      std::uint32_t value = 0;
      if (r.status != SdoStatus::done || n.sdo.value(DataType::unsigned32, value) != Codec::ok) {
        fail(n.who() + ": reading its " + c.what + " failed: " +
             (r.status == SdoStatus::done ? std::string("not 4 bytes") : std::string(to_string(r.abort))));
        return false;
      }
      if (value != id.*c.expected) {
        fail(n.who() + ": " + c.what + " " + hex(value) + ", but " + id.file + " says " +
             hex(id.*c.expected));
        return false;
      }
      ++n.identified;
      n.started = false;
    }
    if (!n.started && n.identified < std::size(checks)) {
      (void)n.sdo.upload(checks[n.identified].address, now);
      n.started = true;
    }
    while (auto f = n.sdo.poll(now)) send(*f);
    all_done = all_done && n.identified >= std::size(checks);
  }
  return all_done;
}

bool StartupSequence::configure(TimeNs now) {
  bool all_done = true;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    Node& n = *nodes_[i];
    if (n.started && !n.sdo.busy()) {
      const StartupWrite& w = n.writes[n.next];
      const SdoResult& r = n.sdo.result();
      const bool missing = r.abort == SdoAbort::no_object || r.abort == SdoAbort::no_subindex;
      if (r.status == SdoStatus::failed && !(w.optional && missing)) {
        fail(n.who() + ": writing " + std::to_string(w.write.value) + " to " + to_string(w.write.address) +
             " failed: " + std::string(to_string(r.abort)) + (r.remote ? " (the drive's abort)" : ""));
        return false;
      }
      if (r.status == SdoStatus::done) written_[i].push_back(w.write);
      ++n.next;
      n.started = false;
    }
    if (!n.started && n.next < n.writes.size()) {
      const SdoWrite& w = n.writes[n.next].write;
      std::uint8_t bytes[8];
      const std::span<std::uint8_t> span(bytes, size_of(w.type));
      const Number value = startup_value(w);
      if (encode(w.type, value, span) != Codec::ok || !n.sdo.download(w.address, span, now)) {
        fail(n.who() + ": value " + std::to_string(w.value) + " does not fit " + to_string(w.address));
        return false;
      }
      n.started = true;
    }
    while (auto f = n.sdo.poll(now)) send(*f);
    all_done = all_done && n.next >= n.writes.size();
  }
  return all_done;
}

StartupPhase StartupSequence::step(TimeNs now) {
  if (phase_ == StartupPhase::done || phase_ == StartupPhase::failed) return phase_;
  receive(now);
  const TimeNs in_phase = now - phase_start_;
  const auto ms = [](TimeNs t) { return std::to_string(t / 1'000'000) + " ms"; };
  switch (phase_) {
    case StartupPhase::reset:
      for (auto& n : nodes_) send(nmt_frame(NmtCommand::reset_communication, n->axis.node));
      phase_ = StartupPhase::boot;
      phase_start_ = now;
      break;
    case StartupPhase::boot: {
      bool all = true;
      for (auto& n : nodes_) all = all && n->booted;
      if (all) {
        phase_ = StartupPhase::identify;
        phase_start_ = now;
        if (identify(now)) phase_ = StartupPhase::configure;
      } else if (in_phase > config_.boot_timeout) {
        for (auto& n : nodes_)
          if (!n->booted)
            fail(n->who() + ": no boot-up within " + ms(config_.boot_timeout) + " of the reset");
      }
      break;
    }
    case StartupPhase::identify:
      if (identify(now)) phase_ = StartupPhase::configure;
      break;
    case StartupPhase::configure:
      if (configure(now)) phase_ = StartupPhase::start;
      break;
    case StartupPhase::start:
      for (auto& n : nodes_) send(nmt_frame(NmtCommand::start, n->axis.node));
      phase_ = StartupPhase::operational;
      phase_start_ = now;
      break;
    case StartupPhase::operational: {
      bool all = true;
      for (auto& n : nodes_) all = all && n->operational;
      if (all) {
        phase_ = StartupPhase::done;
      } else if (in_phase > config_.operational_timeout) {
        for (auto& n : nodes_)
          if (!n->operational)
            fail(n->who() + ": no operational heartbeat within " + ms(config_.operational_timeout) +
                 " of NMT start");
      }
      break;
    }
    case StartupPhase::done:
    case StartupPhase::failed:
      break;
  }
  return phase_;
}

void run_startup(StartupSequence& sequence, const StartupPause& pause) {
  const auto sleep = [] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return monotonic_now();
  };
  TimeNs now = pause ? pause() : monotonic_now();
  while (true) {
    const StartupPhase p = sequence.step(now);
    if (p == StartupPhase::done) return;
    if (p == StartupPhase::failed) throw std::runtime_error(sequence.error());
    now = pause ? pause() : sleep();
  }
}

}  // namespace saw::canopen
