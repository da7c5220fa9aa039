// The deployment keys every CANopen device type shares: read once, range-checked, located (file:line:key).
#include "saw/canopen/device_params.hpp"

#include <chrono>
#include <filesystem>

#include "saw/canopen/bus_link.hpp"
#include "saw/canopen/pdo_text.hpp"
#include "saw/canopen/rpdo_deadline.hpp"

namespace saw::canopen {

using namespace std::chrono_literals;
using deploy::Params;

namespace params {

NodeParams parse_node(const Params& p, TimeNs period) {
  NodeParams n;
  const std::chrono::nanoseconds t{period};
  n.bus = parse_bus(p);
  const Params hb = p.child("heartbeat");
  n.heartbeat_period = hb.get_duration_in("period", 100ms, 1ms, 65535ms);
  n.heartbeat_timeout =
      hb.get_duration_in("timeout", 3 * std::chrono::nanoseconds(n.heartbeat_period), 1ms, 600s);
  if (n.heartbeat_timeout <= n.heartbeat_period) hb.fail_at("timeout", "must be above the heartbeat period");
  if (!is_bus_uri(n.bus) && p.has("master_heartbeat"))
    p.fail_at("master_heartbeat",
              "the master's heartbeat is the bus's: set it on canopen_bus '" + n.bus + "'");
  n.master = parse_master_heartbeat(p);
  n.rpdo_deadline = rpdo_deadline(p, period);
  n.feedback_timeout =
      p.get_duration_in("feedback_timeout", std::max<std::chrono::nanoseconds>(10 * t, 10ms), 2 * t, 10s);
  const Params st = p.child("startup");
  n.startup.boot_timeout = st.get_duration_in("boot_timeout", 2s, 10ms, 600s);
  n.startup.sdo_timeout = st.get_duration_in("sdo_timeout", 500ms, 1ms, 60s);
  n.startup.operational_timeout = st.get_duration_in("operational_timeout", 2s, 10ms, 600s);
  return n;
}

MasterHeartbeatParams parse_master_heartbeat(const Params& p) {
  MasterHeartbeatParams m;
  const Params master = p.child("master_heartbeat");
  m.node = static_cast<std::uint8_t>(master.get_in_range("node", 1, 127, 127));
  m.period = master.get_duration_in("period", 100ms, 1ms, 65535ms);
  m.timeout = master.get_duration_in("timeout", 3 * std::chrono::nanoseconds(m.period), 0ms, 65535ms);
  // 0: the nodes are not told to watch the master (one without 0x1016); said at start-up.
  if (m.timeout != 0 && m.timeout <= m.period)
    master.fail_at("timeout", "must be above the master's heartbeat period (or 0: not watched)");
  return m;
}

// `pdo: {rpdo1: [controlword, target_position], tpdo1: [...], ...}`: the PDOs 1..4 listed are
// mapped, the others configured as not valid. `eds: file` instead: the file's PDOs (a DCF's
// ParameterValues). Neither: the defaults for the mode.
std::vector<PdoMapping> parse_pdos(const Params& p, cia402::Mode mode, std::uint8_t node,
                                   const std::string& directory, std::optional<DriveIdentity>& identity,
                                   std::optional<Eds>* eds_out) {
  if (p.has("pdo") && p.has("eds")) p.fail_at("eds", "give either pdo or eds, not both");
  if (p.has("eds")) {
    std::filesystem::path file = p.get<std::string>("eds");
    if (file.is_relative() && !directory.empty()) file = std::filesystem::path(directory) / file;
    Eds eds = load_eds(file.string());  // its errors name the EDS file and line
    DriveIdentity id;
    id.file = file.string();
    const auto type = eds.value({0x1000, 0}, node);
    id.device_type = type ? std::visit([](auto v) { return static_cast<std::uint32_t>(v); }, *type) : 0;
    id.vendor_id = eds.device.vendor_number;
    id.product_code = eds.device.product_number;
    identity = id;
    auto maps = eds_pdo_mappings(eds, node);
    if (eds_out != nullptr) *eds_out = std::move(eds);
    return maps;
  }
  if (!p.has("pdo")) {
    p.mark_used("pdo");
    return default_pdo_mappings(mode, node);
  }
  const Params pdo = p.child("pdo");
  std::vector<PdoMapping> maps;
  for (const PdoKind kind : {PdoKind::rpdo, PdoKind::tpdo})
    for (std::uint16_t n = 1; n <= 4; ++n) {
      const std::string key = (kind == PdoKind::rpdo ? "rpdo" : "tpdo") + std::to_string(n);
      if (!pdo.has(key)) {
        pdo.mark_used(key);
        maps.push_back(unused_pdo(kind, n, node));
        continue;
      }
      std::vector<PdoEntry> entries;
      try {
        for (const std::string& text : pdo.get<std::vector<std::string>>(key))
          entries.push_back(parse_pdo_entry(text));
        maps.push_back(make_pdo(kind, n, node, entries));
      } catch (const std::invalid_argument& e) {
        pdo.fail_at(key, e.what());
      }
    }
  return maps;
}

// `sdo: ["0x60C2:01:u8=10", "interpolation...", ...]`: the deployment's own start-up writes, an
// object as a PDO entry is written (a known name, an address, with a type) and its value.
std::vector<SdoWrite> parse_writes(const Params& p) {
  std::vector<SdoWrite> out;
  if (!p.has("sdo")) {
    p.mark_used("sdo");
    return out;
  }
  for (const std::string& text : p.get<std::vector<std::string>>("sdo")) {
    const auto eq = text.find('=');
    if (eq == std::string::npos) p.fail_at("sdo", "'" + text + "' is not <object>=<value> (0x60C2:01:u8=10)");
    PdoEntry entry;
    long long value = 0;
    try {
      entry = parse_pdo_entry(text.substr(0, eq));
      std::size_t used = 0;
      value = std::stoll(text.substr(eq + 1), &used, 0);
      if (used != text.size() - eq - 1)
        throw std::invalid_argument("'" + text.substr(eq + 1) + "' is not a number");
    } catch (const std::exception& e) {
      p.fail_at("sdo", "'" + text + "': " + e.what());
    }
    if (size_of(entry.type) > 4 || type_class(entry.type) == TypeClass::real)
      p.fail_at("sdo", "'" + text + "': only integers of up to 32 bits");
    std::uint8_t bytes[8];
    const Number n = type_class(entry.type) == TypeClass::signed_integer
                         ? Number{std::int64_t{value}}
                         : Number{static_cast<std::uint64_t>(value)};
    if (value < 0 && type_class(entry.type) != TypeClass::signed_integer)
      p.fail_at("sdo", "'" + text + "': a negative value for an unsigned object");
    if (encode(entry.type, n, std::span(bytes, size_of(entry.type))) != Codec::ok)
      p.fail_at("sdo", "'" + text + "': the value does not fit " + std::string(to_string(entry.type)));
    out.push_back({entry.address, entry.type, static_cast<std::uint32_t>(value)});
  }
  return out;
}

std::optional<TimeNs> rpdo_deadline(const Params& p, TimeNs period) {
  if (!p.has("rpdo_deadline")) return std::nullopt;
  // YAML 1.1 reads a bare `off` as false: both spell "not watched", as 0 does.
  const auto text = p.get<std::string>("rpdo_deadline");
  if (text == "off" || text == "false") return 0;
  try {
    return resolve_rpdo_deadline(p.get<std::chrono::nanoseconds>("rpdo_deadline").count(), period);
  } catch (const std::invalid_argument& e) {
    p.fail_at("rpdo_deadline", e.what());
  }
}

std::string parse_bus(const Params& p) {
  const std::string bus = p.get<std::string>("bus");
  if (is_bus_uri(bus)) return bus;
  if (bus.empty() || bus.find(':') != std::string::npos)
    p.fail_at("bus", "'" + bus +
                         "' is not a bus: virtual:<name>, socketcan:<interface>, or the name of a "
                         "canopen_bus component");
  return bus;
}

}  // namespace params

}  // namespace saw::canopen
