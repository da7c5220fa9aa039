#include "saw/canopen/pdo_text.hpp"

#include <charconv>
#include <stdexcept>
#include <string>
#include <utility>

namespace saw::canopen {
namespace {

using namespace cia402;

struct KnownObject {
  std::string_view name;
  ObjectAddress address;
  DataType type;
};

constexpr KnownObject known[] = {
    {"controlword", object::controlword, DataType::unsigned16},
    {"statusword", object::statusword, DataType::unsigned16},
    {"mode_of_operation", object::modes_of_operation, DataType::integer8},
    {"mode_display", object::modes_of_operation_display, DataType::integer8},
    {"error_code", object::error_code, DataType::unsigned16},
    {"target_position", object::target_position, DataType::integer32},
    {"target_velocity", object::target_velocity, DataType::integer32},
    {"target_torque", object::target_torque, DataType::integer16},
    {"position_actual", object::position_actual_value, DataType::integer32},
    {"velocity_actual", object::velocity_actual_value, DataType::integer32},
    {"torque_actual", object::torque_actual_value, DataType::integer16},
    {"following_error_window", object::following_error_window, DataType::unsigned32},
    {"max_torque", object::max_torque, DataType::unsigned16},
    {"error_register", {0x1001, 0}, DataType::unsigned8},
};

constexpr std::pair<std::string_view, DataType> type_names[] = {
    {"bool", DataType::boolean},   {"i8", DataType::integer8},    {"i16", DataType::integer16},
    {"i32", DataType::integer32},  {"i64", DataType::integer64},  {"u8", DataType::unsigned8},
    {"u16", DataType::unsigned16}, {"u32", DataType::unsigned32}, {"u64", DataType::unsigned64},
    {"f32", DataType::real32},     {"f64", DataType::real64},
};

template <class T>
bool parse_hex(std::string_view s, T& out) {
  if (s.starts_with("0x") || s.starts_with("0X")) s.remove_prefix(2);
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out, 16);
  return ec == std::errc{} && end == s.data() + s.size();
}

}  // namespace

std::optional<DataType> known_object_type(ObjectAddress a) noexcept {
  for (const auto& k : known)
    if (k.address == a) return k.type;
  return std::nullopt;
}

PdoEntry parse_pdo_entry(std::string_view text) {
  const std::string quoted = "'" + std::string(text) + "'";
  for (const auto& k : known)
    if (k.name == text) return PdoEntry::of(k.address, k.type);
  const auto colon = text.find(':');
  if (colon == std::string_view::npos)
    throw std::invalid_argument(quoted +
                                " is neither an object's name (controlword, target_position, ...) nor "
                                "an address such as 0x6041:00 or 0x2001:01:i32");
  const std::string_view index_text = text.substr(0, colon);
  std::string_view rest = text.substr(colon + 1);
  const auto colon2 = rest.find(':');
  const std::string_view sub_text = rest.substr(0, colon2);
  ObjectAddress a;
  if (!parse_hex(index_text, a.index)) throw std::invalid_argument(quoted + ": index is not 4 hex digits");
  if (!parse_hex(sub_text, a.subindex))
    throw std::invalid_argument(quoted + ": sub-index is not 1-2 hex digits");
  if (colon2 == std::string_view::npos) {
    if (const auto t = known_object_type(a)) return PdoEntry::of(a, *t);
    throw std::invalid_argument(quoted + ": the type of " + to_string(a) +
                                " is not known here: add it (for example " + std::string(text) + ":i32)");
  }
  const std::string_view type_text = rest.substr(colon2 + 1);
  for (const auto& [name, type] : type_names)
    if (name == type_text) return PdoEntry::of(a, type);
  throw std::invalid_argument(quoted + ": unknown type '" + std::string(type_text) +
                              "' (bool, i8, i16, i32, i64, u8, u16, u32, u64, f32, f64)");
}

PdoMapping make_pdo(PdoKind kind, std::uint16_t number, std::uint8_t node, std::span<const PdoEntry> entries,
                    std::optional<std::uint32_t> cob_id) {
  PdoMapping m;
  m.kind = kind;
  m.number = number;
  m.cob_id = cob_id ? *cob_id : default_pdo_cob_id(kind, number, node);
  m.transmission = transmission::synchronous;
  for (const PdoEntry& e : entries) m.map(e);
  check(m);
  return m;
}

std::vector<PdoMapping> default_pdo_mappings(cia402::Mode mode, std::uint8_t node) {
  const ObjectAddress target = mode == csv   ? object::target_velocity
                               : mode == cst ? object::target_torque
                                             : object::target_position;
  const PdoEntry rpdo1[] = {PdoEntry::of(object::controlword, DataType::unsigned16),
                            PdoEntry::of(target, *known_object_type(target))};
  const PdoEntry tpdo1[] = {PdoEntry::of(object::statusword, DataType::unsigned16),
                            PdoEntry::of(object::position_actual_value, DataType::integer32),
                            PdoEntry::of(object::torque_actual_value, DataType::integer16)};
  // The mode display and the error code: the master enables a drive only in the mode it asked
  // for, and names the error of a drive in fault.
  const PdoEntry tpdo2[] = {PdoEntry::of(object::velocity_actual_value, DataType::integer32),
                            PdoEntry::of(object::modes_of_operation_display, DataType::integer8),
                            PdoEntry::of(object::error_code, DataType::unsigned16)};
  std::vector<PdoMapping> maps{make_pdo(PdoKind::rpdo, 1, node, rpdo1),
                               make_pdo(PdoKind::tpdo, 1, node, tpdo1),
                               make_pdo(PdoKind::tpdo, 2, node, tpdo2)};
  for (std::uint16_t n = 2; n <= 4; ++n) maps.push_back(unused_pdo(PdoKind::rpdo, n, node));
  for (std::uint16_t n = 3; n <= 4; ++n) maps.push_back(unused_pdo(PdoKind::tpdo, n, node));
  return maps;
}

PdoMapping unused_pdo(PdoKind kind, std::uint16_t number, std::uint8_t node) noexcept {
  PdoMapping m;
  m.kind = kind;
  m.number = number;
  m.enabled = false;
  m.cob_id = default_pdo_cob_id(kind, number, node);
  return m;
}

}  // namespace saw::canopen
