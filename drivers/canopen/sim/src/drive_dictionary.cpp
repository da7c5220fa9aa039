#include "saw/canopen/sim/drive_dictionary.hpp"

#include "saw/canopen/cia402.hpp"

namespace saw::canopen::sim {

namespace {

struct Required {
  ObjectAddress address;
  const char* name;
  DataType type;
  Access access;
  std::int64_t value;
  bool mappable;
};

// What the simulation reads (setpoints, parameters) and writes (actual values, status), with
// sim_drive.eds's definitions. Objects it only uses when present (0x1003, 0x6066, 0x607D,
// 0x608F, 0x6091, ...) are not added: their absence has a meaning (no history, no limit, ...).
constexpr Required required[] = {
    {{0x1001, 0}, "Error register", DataType::unsigned8, Access::ro, 0, true},
    {{0x1016, 0}, "Highest sub-index supported", DataType::unsigned8, Access::ro, 1, false},
    {{0x1016, 1}, "Consumer heartbeat time", DataType::unsigned32, Access::rw, 0, false},
    {{0x1017, 0}, "Producer heartbeat time", DataType::unsigned16, Access::rw, 0, false},
    {{0x2F00, 0}, "Highest sub-index supported", DataType::unsigned8, Access::ro, 5, false},
    {injection_object::inject, "Inject fault", DataType::unsigned8, Access::rw, 0, false},
    {injection_object::duration, "Fault duration", DataType::unsigned32, Access::rw, 0, false},
    {injection_object::object, "SDO abort object", DataType::unsigned32, Access::rw, 0, false},
    {injection_object::code, "SDO abort code", DataType::unsigned32, Access::rw, 0x06060000, false},
    {injection_object::active, "Active faults", DataType::unsigned8, Access::ro, 0, false},
    {cia402::object::error_code, "Error code", DataType::unsigned16, Access::ro, 0, true},
    {cia402::object::controlword, "Controlword", DataType::unsigned16, Access::rww, 0, true},
    {cia402::object::statusword, "Statusword", DataType::unsigned16, Access::ro, 0, true},
    {cia402::object::modes_of_operation, "Modes of operation", DataType::integer8, Access::rww, 8, true},
    {cia402::object::modes_of_operation_display, "Modes of operation display", DataType::integer8, Access::ro,
     0, true},
    {cia402::object::position_actual_value, "Position actual value", DataType::integer32, Access::ro, 0,
     true},
    // 0xFFFFFFFF: following error monitoring off (CiA 402), for a file that does not set one.
    {cia402::object::following_error_window, "Following error window", DataType::unsigned32, Access::rw,
     0xFFFFFFFF, false},
    {cia402::object::velocity_actual_value, "Velocity actual value", DataType::integer32, Access::ro, 0,
     true},
    {cia402::object::target_torque, "Target torque", DataType::integer16, Access::rww, 0, true},
    {cia402::object::max_torque, "Max torque", DataType::unsigned16, Access::rw, 3000, false},
    {cia402::object::motor_rated_torque, "Motor rated torque", DataType::unsigned32, Access::rw, 318, false},
    {cia402::object::torque_actual_value, "Torque actual value", DataType::integer16, Access::ro, 0, true},
    {cia402::object::target_position, "Target position", DataType::integer32, Access::rww, 0, true},
    {cia402::object::target_velocity, "Target velocity", DataType::integer32, Access::rww, 0, true},
    {cia402::object::supported_drive_modes, "Supported drive modes", DataType::unsigned32, Access::ro, 0x380,
     false},
};

}  // namespace

Eds load_drive_eds(const std::string& path) {
  if (path.empty()) return parse_eds(builtin_eds(), builtin_eds_name);
  return load_eds(path);
}

LocalDictionary make_drive_dictionary(const Eds& eds, std::uint8_t node) {
  LocalDictionary d = make_dictionary(eds, node);
  for (const Required& r : required) {
    if (const Entry* e = d.find(r.address)) {
      if (e->type != r.type) {
        const EdsEntry* source = eds.find(r.address);
        throw deploy::ConfigError(eds.file, source != nullptr ? source->line : 0, 1, to_string(r.address),
                                  "the simulated drive uses it as " + std::string(to_string(r.type)) +
                                      ", the file says " + std::string(to_string(e->type)));
      }
      continue;
    }
    Entry e;
    e.name = r.name;
    e.type = r.type;
    e.access = r.access;
    e.pdo_mappable = r.mappable;
    e.value.resize(size_of(r.type));
    (void)encode(
        r.type,
        r.type == DataType::unsigned32 ? Number{static_cast<std::uint64_t>(r.value)} : Number{r.value},
        e.value);
    d.add(r.address, std::move(e));
  }
  return d;
}

}  // namespace saw::canopen::sim
