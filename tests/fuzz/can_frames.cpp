// Fuzz target: every reader of CAN input. The CANopen consumers get what any node on the bus, or
// a virtual-bus peer writing whole slots, could hand them: any identifier, length and flags, bytes
// past the length, in any order, at any time. The text parsers get what a candump log or a
// socketcand client could hold. Each consumer must refuse what is malformed and keep its promises
// on the rest (abort on violation):
//   - no crash and no undefined behaviour (ASan + UBSan in the `fuzz` preset);
//   - each parse_*() accepts exactly the frames its header describes, and what it decodes
//     round-trips to the same frame;
//   - decoded numbers are in their type's range (a REAL finite, a BOOLEAN 0 or 1);
//   - an SDO transfer never reports more bytes than its buffer (or the value it sends) holds, and
//     a finished download moved every byte; the server's dictionary keeps its types, limits,
//     capacities and read-only values whatever the client sent;
//   - every frame a consumer sends is a CANopen data frame on its own identifier;
//   - the heartbeat consumer's events follow the node's story (appeared, lost, back, ...);
//   - the text parsers refuse a line with a reason or yield a well_formed() frame that formats
//     and parses back to itself; the socketcand framer cuts a stream the same way however TCP
//     splits it;
//   - the bus task of a shared bus hands each client only CANopen data frames on identifiers of
//     its own nodes, and a generic I/O node reads values of its types from them;
//   - what a consumer does depends on the frame's identifier, length, flags and payload only:
//     the same run with the bytes past the length and the reserved bytes zeroed gives the same
//     trace (a peer's leftovers in a slot must not change what a node does).
//
// Input: byte 0 picks the consumer (below, modulo their count), byte 1 configures it; the rest is
// text for the text parsers, or frames, one record each:
//   ctl  id(4 bytes, little-endian, with the EFF/RTR/ERR flags)  len  flags  data[min(len, 64)]
// ctl bits 0..2 advance the clock before the frame (steps[]); bit 3 fills the bytes past the
// length and the reserved bytes with garbage. A record cut short at the end takes zeros.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "saw/can/candump.hpp"
#include "saw/can/frame.hpp"
#include "saw/can/socketcand.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/emcy.hpp"
#include "saw/canopen/heartbeat.hpp"
#include "saw/canopen/io_node.hpp"
#include "saw/canopen/nmt.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/canopen/pdo_text.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sdo_server.hpp"
#include "saw/canopen/sync.hpp"

namespace {

namespace co = saw::canopen;
using co::DataType;
using co::Number;
using co::ObjectAddress;
using saw::TimeNs;
using saw::can::Frame;

constexpr TimeNs ms = 1'000'000;
// Around the timeouts below (SDO 100 ms, heartbeats 50 ms .. 1 s): each step can beat or miss them.
constexpr TimeNs steps[8] = {0, 1 * ms, 5 * ms, 20 * ms, 60 * ms, 120 * ms, 600 * ms, 2000 * ms};
constexpr std::uint8_t node = 5;  // the node the SDO, PDO and NMT consumers are or talk to

[[noreturn]] void defect(const char* consumer, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", consumer, what.c_str());
  std::abort();
}

void check(bool ok, const char* consumer, const char* what) {
  if (!ok) defect(consumer, what);
}

std::string describe(const Frame& f) {
  char s[64];
  std::snprintf(s, sizeof s, "id %08X len %u flags %02X", f.id, static_cast<unsigned>(f.len),
                static_cast<unsigned>(f.flags));
  return s;
}

// A frame a CANopen node may act on: the one check every consumer must make first.
bool canopen(const Frame& f) { return co::canopen_data_frame(f); }

// The observable output of a run, compared between the garbage and the zeroed run.
struct Out {
  std::string trace;
  std::vector<Frame> sent;  // what the consumers sent this step (the loopback bus delivers it)

  void put(std::uint64_t v) { trace.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void put(const Frame& f) {
    put(f.id);
    put(std::uint64_t{f.len} << 8 | f.flags);
    const std::size_t n = std::min<std::size_t>(f.len, CANFD_MAX_DLEN);
    trace.append(reinterpret_cast<const char*>(f.data), n);
  }
  void put(const Number& n) {
    if (const auto* d = std::get_if<double>(&n))
      put(std::bit_cast<std::uint64_t>(*d));
    else
      std::visit([this](auto v) { put(static_cast<std::uint64_t>(v)); }, n);
  }
  void send(const Frame& f) {
    put(f);
    sent.push_back(f);
  }
};

// Every consumer: a frame, then a poll at the same time.
class Consumer {
 public:
  virtual ~Consumer() = default;
  virtual void on_frame(const Frame& f, TimeNs now, Out& out) = 0;
  virtual void poll(TimeNs now, Out& out) = 0;
};

// Whether a number decoded as `t` is a value of `t`.
void check_number(const char* who, DataType t, const Number& n) {
  if (co::type_class(t) == co::TypeClass::real) {
    const double* d = std::get_if<double>(&n);
    check(d != nullptr && std::isfinite(*d), who, "a decoded REAL is not a finite double");
  }
  if (co::compare(n, co::type_min(t)) < 0 || co::compare(n, co::type_max(t)) > 0)
    defect(who, "a decoded " + std::string(co::to_string(t)) + " is outside the type's range");
}

// An upload's bytes read as each numeric type: those of its size decode to a value of the type,
// the others are refused as the wrong length.
void check_decodes(const char* who, std::span<const std::uint8_t> bytes) {
  static constexpr DataType types[] = {
      DataType::boolean,    DataType::integer8,   DataType::unsigned8,  DataType::integer16,
      DataType::unsigned16, DataType::integer24,  DataType::unsigned24, DataType::integer32,
      DataType::unsigned32, DataType::real32,     DataType::integer40,  DataType::unsigned40,
      DataType::integer48,  DataType::unsigned48, DataType::integer56,  DataType::unsigned56,
      DataType::integer64,  DataType::unsigned64, DataType::real64};
  for (const DataType t : types) {
    Number n;
    const co::Codec c = co::decode(t, bytes, n);
    if (bytes.size() != co::size_of(t)) {
      check(c == co::Codec::wrong_length, who, "decode() accepted bytes of another length");
      continue;
    }
    if (c == co::Codec::ok) check_number(who, t, n);
    double d = 0;
    if (co::decode_value(t, bytes, d) == co::Codec::ok)
      check(std::isfinite(d), who, "decoded to a non-finite double");
  }
}

// ---- SDO client --------------------------------------------------------------------------------

// Uploads 0x1008:00 and downloads 0x2000:00 one after the other, forever, against whatever answers.
// param bit 0: download first; bit 1: segmented downloads; bits 2..3: capacity; bits 4..7: size.
class SdoClientUser final : public Consumer {
 public:
  static constexpr ObjectAddress upload_address{0x1008, 0};
  static constexpr ObjectAddress download_address{0x2000, 0};

  SdoClientUser(std::uint8_t param, TimeNs now)
      : capacity_(capacities[(param >> 2) & 3]),
        client_(co::SdoClientConfig{co::SdoChannel::of_node(node), 100 * ms, capacity_}),
        downloading_((param & 1) != 0),
        mode_((param & 2) != 0 ? co::SdoMode::segmented : co::SdoMode::automatic),
        size_(sizes[param >> 4]) {
    for (std::size_t i = 0; i < sizeof value_; ++i) value_[i] = static_cast<std::uint8_t>(7 * i + 1);
    start(now);
  }

  void on_frame(const Frame& f, TimeNs now, Out&) override { client_.on_frame(f, now); }

  void poll(TimeNs now, Out& out) override {
    send(now, out);
    check_result();
    if (client_.busy()) return;
    finished();
    downloading_ = !downloading_;
    start(now);
    send(now, out);
  }

 private:
  static constexpr std::size_t capacities[4] = {8, 21, 64, 1024};
  static constexpr std::size_t sizes[16] = {0, 1, 2, 3, 4, 5, 7, 8, 13, 14, 15, 21, 28, 40, 64, 100};

  std::size_t buffer_size() const { return std::max<std::size_t>(capacity_, 8); }

  void start(TimeNs now) {
    if (downloading_) {
      const bool started = client_.download(download_address, {value_, size_}, now, mode_);
      check(started == (size_ <= buffer_size()), "sdo client",
            "download() refused what fits or took what does not");
      if (started) return;
      downloading_ = false;
    }
    check(client_.upload(upload_address, now), "sdo client", "an idle client refused an upload");
  }

  void send(TimeNs now, Out& out) {
    const auto f = client_.poll(now);
    if (!f) return;
    check(canopen(*f) && f->can_id() == co::cob::sdo_rx + node && f->len == 8, "sdo client",
          "sent something other than an SDO request on its channel");
    if ((f->data[0] >> 5) == 4)
      check(client_.result().status == co::SdoStatus::failed && !client_.result().remote, "sdo client",
            "sent an abort without failing the transfer itself");
    out.send(*f);
  }

  void check_result() {
    const co::SdoResult& r = client_.result();
    check(r.size <= buffer_size(), "sdo client", "reported more bytes than its buffer holds");
    check(client_.data().size() == r.size, "sdo client", "data() disagrees with the reported size");
    if (downloading_) check(r.size <= size_, "sdo client", "reported more bytes sent than the value has");
  }

  void finished() {
    const co::SdoResult& r = client_.result();
    check(r.status == co::SdoStatus::done || r.status == co::SdoStatus::failed, "sdo client",
          "idle without an outcome");
    if (r.status != co::SdoStatus::done) return;
    if (downloading_) {
      check(r.size == size_, "sdo client", "a finished download did not send every byte");
      return;
    }
    check_decodes("sdo client upload", client_.data());
  }

  std::size_t capacity_;
  co::SdoClient client_;
  bool downloading_;
  co::SdoMode mode_;
  std::size_t size_;
  std::uint8_t value_[100];
};

// ---- SDO server --------------------------------------------------------------------------------

co::LocalDictionary server_dictionary() {
  co::LocalDictionary d;
  using co::Access;
  d.add_value({0x1000, 0}, "Device type", DataType::unsigned32, Access::ro, 0x00020192u);
  d.add_value({0x1001, 0}, "Error register", DataType::unsigned8, Access::ro, 0u);
  co::Entry name{"Device name", DataType::visible_string, Access::const_, {}, {}, {}, 0, false};
  const std::string text = "sawrt fuzz drive";  // 16 bytes: a segmented upload
  name.value.assign(text.begin(), text.end());
  d.add({0x1008, 0}, name);
  d.add_value({0x1017, 0}, "Producer heartbeat time", DataType::unsigned16, Access::rw, 100u);
  d.add({0x2000, 0}, co::Entry{"Blob", DataType::domain, Access::rw, {}, {}, {}, 40, false});
  d.add_value({0x2001, 0}, "Command", DataType::unsigned32, Access::wo, 0u);
  d.add_value({0x2002, 0}, "Flag", DataType::boolean, Access::rw, false);
  d.add_value({0x2003, 0}, "Gain", DataType::real32, Access::rw, 1.5f);
  co::Entry label{"Label", DataType::visible_string, Access::rw, {}, {}, {}, 12, false};
  label.value = {'a', 'b', 'c'};
  d.add({0x2004, 0}, label);
  d.add_value({0x2005, 0}, "Counter", DataType::unsigned64, Access::rw, std::uint64_t{1} << 40);
  d.add_value({0x2006, 0}, "Offset", DataType::integer16, Access::rw, 0, Number{std::int64_t{-100}},
              Number{std::int64_t{100}});
  d.add_value({0x2007, 1}, "Limit", DataType::real64, Access::rw, 10.0, Number{0.0}, Number{1000.0});
  d.add_value({0x6060, 0}, "Modes of operation", DataType::integer8, Access::rw, 8);
  d.add_value({0x607A, 0}, "Target position", DataType::integer32, Access::rww, 0,
              Number{std::int64_t{-1000000}}, Number{std::int64_t{1000000}});
  // The drive supports CSP, CSV and CST only (a hook's refusal is an abort too).
  d.on_write([](ObjectAddress a, std::span<const std::uint8_t> bytes) {
    if (a == ObjectAddress{0x6060, 0} && (bytes.size() != 1 || bytes[0] < 8 || bytes[0] > 10))
      return co::SdoAbort::invalid_value;
    return co::SdoAbort::none;
  });
  return d;
}

// param bit 0: no expedited uploads; bits 1..2: the server's capacity.
class SdoServerUser final : public Consumer {
 public:
  explicit SdoServerUser(std::uint8_t param)
      : dictionary_(server_dictionary()),
        server_(co::SdoServerConfig{co::SdoChannel::of_node(node), 100 * ms, capacities[(param >> 1) & 3],
                                    (param & 1) == 0},
                dictionary_),
        initial_(dictionary_.entries()) {
    for (const auto& [a, e] : dictionary_.entries()) reserved_[a] = e.value.capacity();
  }

  void on_frame(const Frame& f, TimeNs now, Out&) override {
    server_.on_frame(f, now);
    check_dictionary();
  }

  void poll(TimeNs now, Out& out) override {
    const auto f = server_.poll(now);
    if (!f) return;
    check(canopen(*f) && f->can_id() == co::cob::sdo_tx + node && f->len == 8, "sdo server",
          "sent something other than an SDO response on its channel");
    check((f->data[0] >> 5) <= 4, "sdo server", "sent an unknown command specifier");
    if ((f->data[0] >> 5) == 4) {
      const std::uint32_t code =
          f->data[4] | f->data[5] << 8 | f->data[6] << 16 | static_cast<std::uint32_t>(f->data[7]) << 24;
      check(co::sdo_abort_name(code) != co::sdo_abort_name(0xFFFFFFFF), "sdo server",
            "aborted with a code that is not a standard one");
    }
    out.send(*f);
  }

 private:
  static constexpr std::size_t capacities[4] = {8, 16, 32, 1024};

  // What an SDO client may never change: the objects, their types and limits, what is read-only;
  // and what the server promises: values of their type, within their limits and capacities,
  // stored without allocating.
  void check_dictionary() const {
    const auto& now = dictionary_.entries();
    check(now.size() == initial_.size(), "sdo server", "the dictionary gained or lost objects");
    for (const auto& [a, e] : now) {
      const auto it = initial_.find(a);
      check(it != initial_.end() && it->second.type == e.type && it->second.access == e.access, "sdo server",
            "an object changed its address, type or access");
      if (!co::writable(e.access))
        check(e.value == it->second.value, "sdo server", "a read-only object changed");
      if (co::is_numeric(co::type_class(e.type))) {
        Number n;
        check(co::decode(e.type, e.value, n) == co::Codec::ok, "sdo server",
              "an object holds no value of its type");
        check_number("sdo server", e.type, n);
        check(!e.low || co::compare(n, *e.low) >= 0, "sdo server", "a value below its LowLimit was stored");
        check(!e.high || co::compare(n, *e.high) <= 0, "sdo server",
              "a value above its HighLimit was stored");
      } else {
        check(e.value.size() <= e.capacity, "sdo server", "a string beyond its capacity was stored");
        check(e.value.capacity() == reserved_.at(a), "sdo server", "storing a string allocated");
        if (e.type == DataType::visible_string)
          for (const std::uint8_t b : e.value)
            check(b == 0 || (b >= 0x20 && b < 0x7F), "sdo server",
                  "an unprintable VISIBLE_STRING was stored");
      }
    }
    std::int8_t mode = 0;
    check(dictionary_.get(ObjectAddress{0x6060, 0}, mode) == co::Codec::ok && mode >= 8 && mode <= 10,
          "sdo server", "a write the hook refused was stored");
  }

  co::LocalDictionary dictionary_;
  co::SdoServer server_;
  std::map<ObjectAddress, co::Entry> initial_;
  std::map<ObjectAddress, std::size_t> reserved_;
};

// ---- EMCY, SYNC, NMT, heartbeat parsing ----------------------------------------------------------

bool same_frame(const Frame& a, const Frame& b) {
  return a.id == b.id && a.len == b.len && a.flags == b.flags &&
         std::memcmp(a.data, b.data, std::min<std::size_t>(a.len, CANFD_MAX_DLEN)) == 0;
}

class EmcyUser final : public Consumer {
 public:
  void on_frame(const Frame& f, TimeNs, Out& out) override {
    const auto e = co::parse_emcy(f);
    const bool valid = canopen(f) && f.len == 8 && f.can_id() > 0x080 && f.can_id() <= 0x0FF;
    if (valid != e.has_value()) defect("emcy", "parse_emcy() got it wrong: " + describe(f));
    if (!e) return;
    check(co::valid_node_id(e->node), "emcy", "a node-ID outside 1..127");
    check(same_frame(co::emcy_frame(*e), f), "emcy", "does not round-trip through emcy_frame()");
    check(!co::emcy_name(e->code).empty() && !co::emcy_class_name(e->code).empty(), "emcy",
          "an unnamed code");
    check(!co::describe_error_register(e->error_register).empty(), "emcy", "an undescribed error register");
    out.put(std::uint64_t{e->node} << 32 | std::uint64_t{e->code} << 8 | e->error_register);
    out.trace.append(co::emcy_name(e->code));
  }
  void poll(TimeNs, Out&) override {}
};

class SyncUser final : public Consumer {
 public:
  void on_frame(const Frame& f, TimeNs, Out& out) override {
    const auto s = co::parse_sync(f);
    const bool valid = canopen(f) && f.can_id() == co::cob::sync &&
                       (f.len == 0 || (f.len == 1 && f.data[0] >= 1 && f.data[0] <= 240));
    if (valid != s.has_value()) defect("sync", "parse_sync() got it wrong: " + describe(f));
    if (!s) return;
    check(same_frame(s->counter ? co::sync_frame(*s->counter) : co::sync_frame(), f), "sync",
          "does not round-trip through sync_frame()");
    out.put(s->counter.value_or(0) + 1000u);
  }
  void poll(TimeNs, Out&) override {}
};

// An NMT slave: the commands it obeys, and the boot-up it sends after each reset.
// param: the node-ID (1 + param % 127).
class NmtUser final : public Consumer {
 public:
  explicit NmtUser(std::uint8_t param) : node_(static_cast<std::uint8_t>(1 + param % 127)) { node_.boot(); }

  void on_frame(const Frame& f, TimeNs, Out& out) override {
    const auto r = co::parse_nmt(f);
    const bool command = f.data[0] == 0x01 || f.data[0] == 0x02 || (f.data[0] >= 0x80 && f.data[0] <= 0x82);
    const bool valid = canopen(f) && f.can_id() == co::cob::nmt && f.len == 2 && command && f.data[1] <= 127;
    if (valid != r.has_value()) defect("nmt", "parse_nmt() got it wrong: " + describe(f));
    if (r)
      check(same_frame(co::nmt_frame(r->command, r->node), f), "nmt",
            "does not round-trip through nmt_frame()");
    const co::NmtState before = node_.state();
    const co::NmtReset reset = node_.on_frame(f);
    co::NmtState expected = before;
    co::NmtReset expected_reset = co::NmtReset::none;
    if (r && r->addresses(node_.node()) && before != co::NmtState::initialising) {
      switch (r->command) {
        case co::NmtCommand::start:
          expected = co::NmtState::operational;
          break;
        case co::NmtCommand::stop:
          expected = co::NmtState::stopped;
          break;
        case co::NmtCommand::enter_pre_operational:
          expected = co::NmtState::pre_operational;
          break;
        case co::NmtCommand::reset_node:
          expected = co::NmtState::initialising;
          expected_reset = co::NmtReset::application;
          break;
        case co::NmtCommand::reset_communication:
          expected = co::NmtState::initialising;
          expected_reset = co::NmtReset::communication;
          break;
      }
    }
    check(node_.state() == expected && reset == expected_reset, "nmt", "the state machine went astray");
    out.put(static_cast<std::uint64_t>(node_.state()) << 8 | static_cast<std::uint64_t>(reset));
    if (reset != co::NmtReset::none) {
      check(!node_.poll(), "nmt", "a boot-up message before the device booted");
      node_.boot();  // the device resets at once
    }
  }

  void poll(TimeNs, Out& out) override {
    if (const auto f = node_.poll()) {
      check(same_frame(*f, co::boot_up_frame(node_.node())) && co::parse_heartbeat(*f), "nmt",
            "a boot-up message that is not one");
      out.send(*f);
    }
  }

 private:
  co::NmtNode node_;
};

// Watches nodes 1 (50 ms), node (100 ms) and 127 (1 s), and checks each event against the story
// told so far.
class HeartbeatUser final : public Consumer {
 public:
  HeartbeatUser() {
    for (const auto& [id, time] : watched) consumer_.watch(id, time);
  }

  void on_frame(const Frame& f, TimeNs now, Out& out) override {
    const auto hb = co::parse_heartbeat(f);
    const bool state = f.data[0] == 0x00 || f.data[0] == 0x04 || f.data[0] == 0x05 || f.data[0] == 0x7F;
    const bool valid = canopen(f) && f.len == 1 && f.can_id() > 0x700 && f.can_id() <= 0x77F && state;
    if (valid != hb.has_value()) defect("heartbeat", "parse_heartbeat() got it wrong: " + describe(f));
    if (hb) {
      check(same_frame(co::heartbeat_frame(hb->node, hb->state), f), "heartbeat",
            "does not round-trip through heartbeat_frame()");
      last_state_[hb->node] = hb->state;
    }
    consumer_.on_frame(f, now);
    drain(now, out);
  }

  void poll(TimeNs now, Out& out) override { drain(now, out); }

 private:
  struct Story {
    bool seen = false, lost = false;
    std::uint32_t losses = 0;
  };
  static constexpr std::pair<std::uint8_t, TimeNs> watched[3] = {
      {1, 50 * ms}, {node, 100 * ms}, {127, 1000 * ms}};

  static TimeNs consumer_time(std::uint8_t id) {
    for (const auto& [n, time] : watched)
      if (n == id) return time;
    return 0;
  }

  void drain(TimeNs now, Out& out) {
    while (const auto e = consumer_.poll(now)) {
      const TimeNs limit = consumer_time(e->node);
      check(limit > 0, "heartbeat", "an event for a node nobody watches");
      Story& s = story_[e->node];
      switch (e->kind) {
        case co::HeartbeatEvent::Kind::appeared:
          check(!s.seen, "heartbeat", "appeared twice");
          s.seen = true;
          break;
        case co::HeartbeatEvent::Kind::lost:
          check(s.seen && !s.lost, "heartbeat", "lost a node not seen, or lost twice");
          check(e->time == now && e->silent_for > limit && e->late_by == e->silent_for - limit, "heartbeat",
                "a loss within the consumer time, or its figures are wrong");
          s.lost = true;
          ++s.losses;
          break;
        case co::HeartbeatEvent::Kind::back:
          check(s.lost && e->silent_for >= 0, "heartbeat", "back without being lost");
          s.lost = false;
          break;
        case co::HeartbeatEvent::Kind::boot_up:
          check(s.seen && e->state == co::NmtState::initialising, "heartbeat", "a boot-up that is not one");
          break;
        case co::HeartbeatEvent::Kind::state_changed:
          check(s.seen && e->state != e->previous, "heartbeat", "a state change to the same state");
          break;
      }
      check(!co::to_string(e->kind).empty() && co::to_string(e->kind) != "unknown", "heartbeat",
            "unknown kind");
      out.put(std::uint64_t{e->node} << 16 | static_cast<std::uint64_t>(e->kind) << 8 |
              static_cast<std::uint64_t>(e->state));
      out.put(static_cast<std::uint64_t>(e->silent_for));
    }
    check(consumer_.dropped_events() == 0, "heartbeat", "events dropped although polled after every frame");
    for (const auto& [id, time] : watched) {
      const co::NodeHeartbeat& n = consumer_.node(id);
      const Story& s = story_[id];
      check(n.seen == s.seen && n.lost == s.lost && n.losses == s.losses && n.consumer_time == time,
            "heartbeat", "node() disagrees with the events it gave");
      if (n.seen)
        check(n.state == last_state_[id], "heartbeat", "node() holds another state than the last heartbeat");
    }
  }

  co::HeartbeatConsumer consumer_;
  std::map<std::uint8_t, Story> story_;
  std::map<std::uint8_t, co::NmtState> last_state_;
};

// ---- PDOs ----------------------------------------------------------------------------------------

std::vector<co::PdoMapping> pdo_mappings() {
  using co::PdoKind;
  std::vector<co::PdoMapping> out;
  const auto mapping = [&](PdoKind kind, std::uint16_t number) -> co::PdoMapping& {
    co::PdoMapping& m = out.emplace_back();
    m.kind = kind;
    m.number = number;
    m.cob_id = co::default_pdo_cob_id(kind, number, node);
    return m;
  };
  // A CiA 402 drive's: statusword, position, mode display (7 bytes).
  mapping(PdoKind::tpdo, 1)
      .map({0x6041, 0}, DataType::unsigned16)
      .map({0x6064, 0}, DataType::integer32)
      .map({0x6061, 0}, DataType::integer8);
  // A REAL32, a 1-bit BOOLEAN, a dummy byte and an INTEGER16: 57 bits in 8 bytes, unaligned.
  mapping(PdoKind::tpdo, 2)
      .map({0x2003, 0}, DataType::real32)
      .map(co::PdoEntry{{0x2002, 0}, 1, DataType::boolean})
      .map(co::PdoEntry{{0x0005, 0}, 8, DataType::unsigned8})
      .map({0x2006, 0}, DataType::integer16);
  mapping(PdoKind::tpdo, 3).map({0x2005, 0}, DataType::unsigned64);
  // Three 1-bit BOOLEANs, then an INTEGER40 and an UNSIGNED8 straddling bytes: 51 bits in 7 bytes.
  mapping(PdoKind::tpdo, 4)
      .map(co::PdoEntry{{0x2010, 1}, 1, DataType::boolean})
      .map(co::PdoEntry{{0x2010, 2}, 1, DataType::boolean})
      .map(co::PdoEntry{{0x2010, 3}, 1, DataType::boolean})
      .map({0x2011, 0}, DataType::integer40)
      .map({0x2012, 0}, DataType::unsigned8);
  mapping(PdoKind::rpdo, 1).map({0x2007, 1}, DataType::real64);
  mapping(PdoKind::rpdo, 2).map({0x6040, 0}, DataType::unsigned16).map({0x60FF, 0}, DataType::integer24);
  return out;
}

class PdoUser final : public Consumer {
 public:
  PdoUser() {
    for (const auto& m : pdo_mappings()) unpackers_.emplace_back(m);
  }

  void on_frame(const Frame& f, TimeNs, Out& out) override {
    for (co::PdoUnpacker& u : unpackers_) {
      const co::PdoLayout& l = u.layout();
      const co::PdoReceive r = u.receive(f);
      co::PdoReceive expected = co::PdoReceive::ok;
      if (f.can_id() != l.cob_id())
        expected = co::PdoReceive::other_identifier;
      else if (!canopen(f))
        expected = co::PdoReceive::not_data;
      else if (f.len != l.bytes())
        expected = co::PdoReceive::wrong_length;
      if (r != expected)
        defect("pdo", "receive() said " + std::string(co::to_string(r)) + ": " + describe(f));
      out.put(static_cast<std::uint64_t>(r));
      if (r != co::PdoReceive::ok) continue;
      check(u.has_data(), "pdo", "accepted a frame but has no data");
      round_trip(u, f, out);
    }
  }
  void poll(TimeNs, Out&) override {}

 private:
  // Every value read is of its type, and packing the values back gives the frame's bits.
  static void round_trip(const co::PdoUnpacker& u, const Frame& f, Out& out) {
    const co::PdoLayout& l = u.layout();
    co::PdoPacker packer(l);
    std::uint64_t mask = 0;
    for (std::size_t i = 0; i < l.size(); ++i) {
      const co::PdoSlot& s = l.slot(i);
      Number n;
      const co::Codec c = u.get_number(i, n);
      double d = 0;
      if (u.get(i, d) == co::Codec::ok) check(std::isfinite(d), "pdo", "a value read as a non-finite double");
      if (c != co::Codec::ok) {
        check(co::type_class(s.type) == co::TypeClass::real || s.type == DataType::boolean, "pdo",
              "an integer that does not decode");
        continue;
      }
      check_number("pdo", s.type, n);
      check(packer.set_number(i, n) == co::Codec::ok, "pdo", "a value read does not pack back");
      mask |= (s.bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << s.bits) - 1) << s.offset;
      out.put(n);
    }
    std::uint64_t got = 0, packed = 0;
    for (std::size_t i = 0; i < f.len; ++i) {
      got |= std::uint64_t{f.data[i]} << (8 * i);
      packed |= std::uint64_t{packer.frame().data[i]} << (8 * i);
    }
    check((got & mask) == (packed & mask), "pdo", "the values read do not pack back to the frame's bits");
    check(packer.frame().id == f.id && packer.frame().len == f.len, "pdo", "the packer's frame is another");
  }

  std::vector<co::PdoUnpacker> unpackers_;
};

// A bus several components share: the bus task routes every frame to the client of its node (A:
// node 5 and TPDOs 0x185, 0x285; B: node 6 and its TPDO1, an I/O node on B's port reading it).
class BusTaskUser final : public Consumer {
 public:
  BusTaskUser() {
    auto bus = std::make_unique<Inbox>();
    inbox_ = bus.get();
    co::BusTaskConfig k;
    k.heartbeat_period = 100 * ms;
    task_ = std::make_unique<co::BusTask>(std::move(bus), k);
    const std::uint8_t a_nodes[] = {5}, b_nodes[] = {6};
    const std::uint32_t a_tpdos[] = {0x185, 0x285}, b_tpdos[] = {0x186};
    a_ = &task_->attach("A", a_nodes, a_tpdos);
    b_ = &task_->attach("B", b_nodes, b_tpdos);
    a_->set_cycling(true);
    b_->set_cycling(true);
    co::IoNodeConfig io;
    io.name = "io";
    io.node = 6;
    io.heartbeat_period = 50 * ms;
    io.heartbeat_timeout = 150 * ms;
    const co::PdoEntry in1 = co::PdoEntry::of({0x6401, 1}, DataType::integer16);
    const co::PdoEntry in2 = co::PdoEntry::of({0x6000, 1}, DataType::unsigned8);
    const co::PdoEntry out1 = co::PdoEntry::of({0x6411, 1}, DataType::integer16);
    const co::PdoEntry tpdo[] = {in1, in2};
    io.pdos.push_back(co::make_pdo(co::PdoKind::tpdo, 1, 6, tpdo));
    io.pdos.push_back(co::make_pdo(co::PdoKind::rpdo, 1, 6, std::span(&out1, 1)));
    io.inputs = {in1, in2};
    io.outputs = {out1};
    io_ = std::make_unique<co::IoNode>(*b_, io);
  }

  void on_frame(const Frame& f, TimeNs now, Out& out) override {
    // A bus never hands over a malformed frame (the backends drop and count it).
    if (saw::can::well_formed(f)) inbox_->frames.push_back(f);
    task_->cycle(now);
    saw::can::Received r[16];
    for (std::size_t n; (n = a_->receive(r)) > 0;)
      for (std::size_t i = 0; i < n; ++i) {
        const Frame& g = r[i].frame;
        const std::uint32_t id = g.can_id() & CAN_SFF_MASK;
        check(canopen(g), "bus task", "handed a client a frame that is no CANopen data frame");
        check(id == 0x85 || id == 0x705 || id == 0x585 || id == 0x185 || id == 0x285, "bus task",
              "handed client A a frame of another node");
        out.put(g);
      }
    io_->receive(now);
    const co::AxisHealth& h = io_->health();
    out.put(h.emcy_count);
    out.put(h.bad_pdos);
    out.put(std::uint64_t{h.boot_ups});
    double v = 0;
    if (io_->input(0, v)) {
      check(v >= -32768 && v <= 32767 && v == std::floor(v), "io node",
            "an INTEGER16 input out of its range");
      out.put(static_cast<std::uint64_t>(static_cast<std::int64_t>(v)));
    }
    if (io_->input(1, v)) check(v >= 0 && v <= 255, "io node", "an UNSIGNED8 input out of its range");
    for (const Frame& g : inbox_->out) {
      check(canopen(g), "bus task", "sent a frame that is no CANopen data frame");
      out.put(g);
    }
    inbox_->out.clear();
    out.put(task_->counters().foreign_frames);
  }
  void poll(TimeNs, Out&) override {}

 private:
  struct Inbox final : saw::can::Bus {
    std::size_t receive(std::span<saw::can::Received> o) noexcept override {
      std::size_t n = 0;
      while (n < o.size() && next < frames.size()) o[n++] = {frames[next++], 0};
      return n;
    }
    std::size_t send(std::span<const Frame> f) noexcept override {
      out.insert(out.end(), f.begin(), f.end());
      return f.size();
    }
    saw::can::BusState state() const noexcept override { return saw::can::BusState::error_active; }
    saw::can::BusCounters counters() const noexcept override { return {}; }
    const std::string& name() const noexcept override { return name_; }
    std::vector<Frame> frames, out;
    std::size_t next = 0;
    std::string name_ = "fuzz";
  };
  Inbox* inbox_ = nullptr;
  std::unique_ptr<co::BusTask> task_;
  co::BusPort *a_ = nullptr, *b_ = nullptr;
  std::unique_ptr<co::IoNode> io_;
};

// ---- the frame consumers' run --------------------------------------------------------------------

struct Record {
  Frame frame;
  TimeNs dt = 0;
  bool garbage = false;
};

std::vector<Record> read_records(std::span<const std::uint8_t> in) {
  std::vector<Record> out;
  std::size_t i = 0;
  const auto next = [&] { return i < in.size() ? in[i++] : std::uint8_t{0}; };
  while (i < in.size()) {
    Record r;
    const std::uint8_t ctl = next();
    r.dt = steps[ctl & 7];
    r.garbage = (ctl & 8) != 0;
    for (int b = 0; b < 4; ++b) r.frame.id |= static_cast<std::uint32_t>(next()) << (8 * b);
    r.frame.len = next();
    r.frame.flags = next();
    const std::size_t n = std::min<std::size_t>(r.frame.len, CANFD_MAX_DLEN);
    for (std::size_t b = 0; b < n; ++b) r.frame.data[b] = next();
    if (r.garbage) {
      for (std::size_t b = n; b < CANFD_MAX_DLEN; ++b) r.frame.data[b] = static_cast<std::uint8_t>(0xA5 + b);
      r.frame.reserved0 = 0x5A;
      r.frame.reserved1 = static_cast<std::uint8_t>(ctl >> 4);
    }
    out.push_back(r);
  }
  return out;
}

enum class Pick : std::uint8_t {
  sdo_client,
  sdo_server,
  emcy,
  heartbeat,
  nmt,
  pdo,
  sync,
  all,  // every consumer above on one bus, each hearing what the others send
  candump,
  socketcand,
  bus_task,  // after the text parsers: the corpus's picks keep their consumers
  count
};

std::vector<std::unique_ptr<Consumer>> make_consumers(Pick pick, std::uint8_t param) {
  std::vector<std::unique_ptr<Consumer>> c;
  const auto want = [&](Pick p) { return pick == p || pick == Pick::all; };
  if (want(Pick::sdo_client)) c.push_back(std::make_unique<SdoClientUser>(param, 0));
  if (want(Pick::sdo_server)) c.push_back(std::make_unique<SdoServerUser>(param));
  if (want(Pick::emcy)) c.push_back(std::make_unique<EmcyUser>());
  if (want(Pick::heartbeat)) c.push_back(std::make_unique<HeartbeatUser>());
  if (want(Pick::nmt)) c.push_back(std::make_unique<NmtUser>(param));
  if (want(Pick::pdo)) c.push_back(std::make_unique<PdoUser>());
  if (want(Pick::sync)) c.push_back(std::make_unique<SyncUser>());
  if (pick == Pick::bus_task) c.push_back(std::make_unique<BusTaskUser>());
  return c;
}

// Feeds the records to the consumers: at each, the clock advances, what was sent the step before
// is delivered (on the loopback bus of `all`), then the record's frame, then everyone polls.
// A last poll 3 s later lets every timeout fire.
std::string run(Pick pick, std::uint8_t param, const std::vector<Record>& records) {
  const auto consumers = make_consumers(pick, param);
  Out out;
  TimeNs now = 0;
  const auto deliver = [&](const Frame& f) {
    for (const auto& c : consumers) c->on_frame(f, now, out);
  };
  const auto poll = [&] {
    for (const auto& c : consumers) c->poll(now, out);
  };
  poll();
  for (const Record& r : records) {
    now += r.dt;
    std::vector<Frame> sent;
    sent.swap(out.sent);
    if (pick == Pick::all)
      for (const Frame& f : sent) deliver(f);
    deliver(r.frame);
    poll();
  }
  now += 3000 * ms;
  poll();
  return out.trace;
}

void frame_consumers(Pick pick, std::uint8_t param, std::span<const std::uint8_t> in) {
  std::vector<Record> records = read_records(in);
  const std::string trace = run(pick, param, records);
  bool garbage = false;
  for (Record& r : records) {
    if (!r.garbage) continue;
    garbage = true;
    const std::size_t n = std::min<std::size_t>(r.frame.len, CANFD_MAX_DLEN);
    std::fill(r.frame.data + n, r.frame.data + CANFD_MAX_DLEN, std::uint8_t{0});
    r.frame.reserved0 = r.frame.reserved1 = 0;
  }
  if (garbage && run(pick, param, records) != trace)
    defect("frames", "the bytes past the length or the reserved bytes changed what a consumer did");
}

// ---- text: candump -L lines and cansend frames ----------------------------------------------------

bool identical(const Frame& a, const Frame& b) { return std::memcmp(&a, &b, sizeof(Frame)) == 0; }

void parsed_frame(const char* who, const Frame& f, const std::string& error) {
  if (!saw::can::well_formed(f))
    defect(who, "accepted a frame that is not well_formed(): " + describe(f) + " (error '" + error + "')");
}

void candump_lines(std::string_view text) {
  while (!text.empty()) {
    const std::size_t end = std::min(text.find('\n'), text.size());
    const std::string_view line = text.substr(0, end);
    text.remove_prefix(std::min(end + 1, text.size()));

    std::string error;
    if (const auto e = saw::can::parse_log_line(line, &error)) {
      parsed_frame("candump log line", e->frame, error);
      check(e->time >= 0, "candump log line", "a time before the epoch");
      const std::string again = saw::can::format_log_line(e->time, e->interface, e->frame);
      std::string why;
      const auto back = saw::can::parse_log_line(again, &why);
      if (!back || back->time != e->time || back->interface != e->interface ||
          !identical(back->frame, e->frame))
        defect("candump log line", "'" + again + "' does not parse back to what it was written from: " + why);
    } else {
      check(!error.empty(), "candump log line", "refused without a reason");
    }

    error.clear();
    if (const auto f = saw::can::parse_frame(line, &error)) {
      parsed_frame("cansend frame", *f, error);
      const std::string again = saw::can::format_frame(*f);
      std::string why;
      const auto back = saw::can::parse_frame(again, &why);
      if (!back || !identical(*back, *f))
        defect("cansend frame", "'" + again + "' does not parse back to what it was written from: " + why);
    } else {
      check(!error.empty(), "cansend frame", "refused without a reason");
    }
  }
}

// ---- text: a socketcand client's byte stream --------------------------------------------------------

bool printable(char c) { return c >= 0x20 && c < 0x7F; }

// A server element: one '< ... >' of printable characters.
void check_element(const char* who, const std::string& s) {
  bool ok = s.size() >= 4 && s.starts_with("< ") && s.ends_with(" >");
  for (std::size_t i = 0; ok && i < s.size(); ++i)
    ok = printable(s[i]) && (i == 0 || s[i] != '<') && (i + 1 == s.size() || s[i] != '>');
  if (!ok) defect(who, "sent a malformed element '" + s + "'");
}

// The element a client sends for `f` (python-can's spelling), to parse back.
std::string client_element(const Frame& f) {
  char head[48];
  const unsigned id = f.can_id(), len = f.len;
  char id_text[16];
  if (f.extended())
    std::snprintf(id_text, sizeof id_text, "%08X", id);
  else
    std::snprintf(id_text, sizeof id_text, "%03X", id);
  if (f.fd())
    std::snprintf(head, sizeof head, "< fdsend %s %X %u", id_text,
                  static_cast<unsigned>(f.flags & (CANFD_BRS | CANFD_ESI)), len);
  else
    std::snprintf(head, sizeof head, "< %s %s %u", f.remote() ? "sendrtr" : "send", id_text, len);
  std::string s = head;
  if (!f.remote())
    for (std::size_t i = 0; i < f.len; ++i) {
      char b[4];
      std::snprintf(b, sizeof b, " %x", static_cast<unsigned>(f.data[i]));
      s += b;
    }
  return s + " >";
}

void command(const std::string& element) {
  namespace sc = saw::can::socketcand;
  std::string error;
  const auto c = sc::parse_command(element, error);
  if (!c) {
    check(!error.empty(), "socketcand", "refused without a reason");
    check_element("socketcand format_error", sc::format_error(error));
    return;
  }
  if (c->kind == sc::Command::Kind::open)
    check(!c->bus.empty() && c->bus.find_first_of(" \t\r\n<>") == std::string::npos, "socketcand",
          "opened a bus with a name no element can hold");
  if (c->kind != sc::Command::Kind::send) return;
  parsed_frame("socketcand", c->frame, error);
  check(!c->frame.error(), "socketcand", "a client sent an error frame");
  check_element("socketcand format_frame", sc::format_frame(c->frame, 1'700'000'000'123'456'789));
  const std::string again = client_element(c->frame);
  std::string why;
  const auto back = sc::parse_command(again, why);
  if (!back || back->kind != sc::Command::Kind::send || !identical(back->frame, c->frame))
    defect("socketcand", "'" + again + "' does not parse back to the frame of '" + element + "': " + why);
}

// Cuts the stream into elements as the server does; the same stream in one piece or in
// `chunk`-byte pieces must give the same elements.
std::vector<std::string> elements(std::string_view stream, std::size_t chunk) {
  saw::can::socketcand::Framer framer;
  std::vector<std::string> out;
  std::string error;
  for (std::size_t at = 0; at < stream.size(); at += chunk) {
    framer.feed(stream.substr(at, chunk));
    for (;;) {
      auto e = framer.next(error);
      if (!e && error.empty()) break;  // more bytes needed
      if (!e) continue;                // refused: the framer resynchronises
      bool ok = e->size() >= 2 && e->size() <= saw::can::socketcand::Framer::max_element &&
                e->front() == '<' && e->back() == '>';
      for (std::size_t i = 1; ok && i + 1 < e->size(); ++i)
        ok = (printable((*e)[i]) || (*e)[i] == '\t' || (*e)[i] == '\n' || (*e)[i] == '\r') &&
             (*e)[i] != '<' && (*e)[i] != '>';
      if (!ok) defect("socketcand framer", "cut a malformed element '" + *e + "'");
      out.push_back(std::move(*e));
    }
  }
  return out;
}

void socketcand_stream(std::uint8_t param, std::string_view stream) {
  const auto whole = elements(stream, stream.size() + 1);
  if (elements(stream, 1 + param % 64) != whole)
    defect("socketcand framer", "the elements depend on how the stream was split");
  for (const auto& e : whole) command(e);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const auto pick = static_cast<Pick>(data[0] % static_cast<std::uint8_t>(Pick::count));
  const std::uint8_t param = data[1];
  const std::span<const std::uint8_t> rest(data + 2, size - 2);
  const std::string_view text(reinterpret_cast<const char*>(rest.data()), rest.size());
  switch (pick) {
    case Pick::candump:
      candump_lines(text);
      break;
    case Pick::socketcand:
      socketcand_stream(param, text);
      break;
    default:
      frame_consumers(pick, param, rest);
      break;
  }
  return 0;
}
