#include "saw/canopen/eds.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include "ini.hpp"

namespace saw::canopen {

using deploy::ConfigError;

std::string_view to_string(ObjectType t) noexcept {
  switch (t) {
    case ObjectType::null:
      return "NULL";
    case ObjectType::domain:
      return "DOMAIN";
    case ObjectType::deftype:
      return "DEFTYPE";
    case ObjectType::defstruct:
      return "DEFSTRUCT";
    case ObjectType::var:
      return "VAR";
    case ObjectType::array:
      return "ARRAY";
    case ObjectType::record:
      return "RECORD";
  }
  return "unknown";
}

namespace {

// ---- numbers as CiA 306 writes them ---------------------------------------------------------

// A whole number: decimal, hexadecimal (0x), or octal (a leading 0), with an optional sign.
// Negative values come back as int64, the others as uint64 (UNSIGNED64 needs the whole range).
std::optional<Number> parse_integer(std::string_view s) {
  bool negative = false;
  if (!s.empty() && (s.front() == '-' || s.front() == '+')) {
    negative = s.front() == '-';
    s.remove_prefix(1);
  }
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    base = 16;
    s.remove_prefix(2);
  } else if (s.size() > 1 && s[0] == '0') {
    base = 8;
    s.remove_prefix(1);
  }
  if (s.empty()) return std::nullopt;
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
  if (!negative) return Number{v};
  if (v > std::uint64_t{1} << 63) return std::nullopt;
  return Number{v == std::uint64_t{1} << 63 ? std::numeric_limits<std::int64_t>::min()
                                            : -static_cast<std::int64_t>(v)};
}

std::optional<double> parse_real(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double d = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
  if (ec != std::errc{} || end != s.data() + s.size() || !std::isfinite(d)) return std::nullopt;
  return d;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

// Errors of one file, located by the ini values.
struct Context {
  const ini::File& file;

  [[noreturn]] void fail(const ini::Value& v, const std::string& section, const std::string& what) const {
    throw ConfigError(file.path, v.line, v.column, section + "." + v.key, what);
  }
  [[noreturn]] void fail(const ini::Section& s, const std::string& key, const std::string& what) const {
    throw ConfigError(file.path, s.line, 1, key.empty() ? "[" + s.name + "]" : s.name + "." + key, what);
  }

  const ini::Value& required(const ini::Section& s, std::string_view key, std::string_view spelled) const {
    const ini::Value* v = s.find(key);
    if (v == nullptr) fail(s, std::string(spelled), "missing");
    return *v;
  }

  std::uint64_t unsigned_value(const ini::Section& s, const ini::Value& v, std::uint64_t max) const {
    const auto n = parse_integer(v.text);
    std::uint64_t u = 0;
    if (!n || to_value(*n, u) != Codec::ok || u > max)
      fail(v, s.name, "'" + v.text + "' is not a whole number in 0.." + std::to_string(max));
    return u;
  }

  // A value of `type`; node-relative only where `allow_node` (default and parameter values).
  EdsValue value(const ini::Section& s, const ini::Value& v, DataType type, bool allow_node) const {
    EdsValue out;
    out.text = v.text;
    const TypeClass c = type_class(type);
    if (c == TypeClass::bytes) {
      if (type == DataType::visible_string) {
        for (char ch : v.text) {
          const auto b = static_cast<unsigned char>(ch);
          if (b < 0x20 || b >= 0x7F) fail(v, s.name, "a VISIBLE_STRING holds printable ASCII only");
          out.bytes.push_back(b);
        }
        return out;
      }
      // OCTET_STRING, UNICODE_STRING and DOMAIN values are written as hex bytes.
      std::string hex;
      for (char ch : v.text)
        if (!std::isspace(static_cast<unsigned char>(ch))) hex += ch;
      if (hex.size() % 2 != 0) fail(v, s.name, "'" + v.text + "' is not a whole number of hex bytes");
      for (std::size_t i = 0; i < hex.size(); i += 2) {
        std::uint8_t b = 0;
        const auto [end, ec] = std::from_chars(hex.data() + i, hex.data() + i + 2, b, 16);
        if (ec != std::errc{} || end != hex.data() + i + 2)
          fail(v, s.name, "'" + v.text + "' is not a whole number of hex bytes");
        out.bytes.push_back(b);
      }
      return out;
    }
    std::string_view text = v.text;
    const std::string low = ini::lower(text);
    if (const std::size_t at = low.find("$nodeid"); at != std::string::npos) {
      if (!allow_node || c == TypeClass::real || c == TypeClass::boolean)
        fail(v, s.name, "$NODEID is not allowed here");
      out.node_relative = true;
      // "$NODEID", "$NODEID+<n>" or "<n>+$NODEID".
      std::string_view before = trimmed(text.substr(0, at)), after = trimmed(text.substr(at + 7));
      if (!before.empty() && !after.empty())
        fail(v, s.name, "'" + v.text + "': $NODEID plus one number only");
      std::string_view rest;
      if (!after.empty()) {
        if (after.front() != '+') fail(v, s.name, "'" + v.text + "': expected '+' after $NODEID");
        rest = trimmed(after.substr(1));
      } else if (!before.empty()) {
        if (before.back() != '+') fail(v, s.name, "'" + v.text + "': expected '+' before $NODEID");
        rest = trimmed(before.substr(0, before.size() - 1));
      }
      text = rest.empty() ? std::string_view("0") : rest;
    }
    if (c == TypeClass::real) {
      const auto d = parse_real(text);
      if (!d) fail(v, s.name, "'" + v.text + "' is not a finite decimal number");
      out.number = *d;
    } else {
      const auto n = parse_integer(text);
      if (!n) fail(v, s.name, "'" + v.text + "' is not a whole number (decimal, 0x hex or 0 octal)");
      out.number = *n;
    }
    std::uint8_t scratch[8];
    if (const Codec codec = encode(type, out.number, scratch); codec != Codec::ok)
      fail(v, s.name,
           "'" + v.text + "' is " + std::string(to_string(codec)) + " for " + std::string(to_string(type)));
    return out;
  }
};

bool all_hex(std::string_view s) {
  return !s.empty() &&
         std::all_of(s.begin(), s.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); });
}

std::uint32_t hex_of(std::string_view s) {
  std::uint32_t v = 0;
  std::from_chars(s.data(), s.data() + s.size(), v, 16);
  return v;
}

// What a section's name says it is.
struct SectionName {
  enum Kind { other, object, sub, names, values } kind = other;
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
};

SectionName classify(std::string_view lower_name) {
  if (lower_name.size() <= 4 && all_hex(lower_name))
    return {SectionName::object, static_cast<std::uint16_t>(hex_of(lower_name)), 0};
  std::size_t digits = 0;
  while (digits < lower_name.size() && digits < 4 &&
         std::isxdigit(static_cast<unsigned char>(lower_name[digits])))
    ++digits;
  if (digits == 0) return {};
  const auto index = static_cast<std::uint16_t>(hex_of(lower_name.substr(0, digits)));
  const std::string_view rest = lower_name.substr(digits);
  if (rest.starts_with("sub") && rest.size() > 3 && rest.size() <= 5 && all_hex(rest.substr(3)))
    return {SectionName::sub, index, static_cast<std::uint8_t>(hex_of(rest.substr(3)))};
  if (rest == "name") return {SectionName::names, index, 0};
  if (rest == "value") return {SectionName::values, index, 0};
  return {};
}

ObjectType object_type_of(const Context& cx, const ini::Section& s) {
  const ini::Value* v = s.find("objecttype");
  if (v == nullptr) return ObjectType::var;  // CiA 306: VAR when not given
  switch (cx.unsigned_value(s, *v, 0xFF)) {
    case 0x0:
      return ObjectType::null;
    case 0x2:
      return ObjectType::domain;
    case 0x5:
      return ObjectType::deftype;
    case 0x6:
      return ObjectType::defstruct;
    case 0x7:
      return ObjectType::var;
    case 0x8:
      return ObjectType::array;
    case 0x9:
      return ObjectType::record;
    default:
      cx.fail(*v, s.name,
              "'" + v->text + "' is not an object type (0x7 VAR, 0x8 ARRAY, 0x9 RECORD, 0x2 DOMAIN)");
  }
}

DataType data_type_of(const Context& cx, const ini::Section& s) {
  const ini::Value& v = cx.required(s, "datatype", "DataType");
  const auto code = cx.unsigned_value(s, v, 0xFFFF);
  const auto t = data_type_from_code(static_cast<std::uint32_t>(code));
  if (!t)
    cx.fail(
        v, s.name,
        "data type '" + v.text + "' is not supported (BOOLEAN, INTEGERn, UNSIGNEDn, REALn, strings, DOMAIN)");
  return *t;
}

Access access_of(const Context& cx, const ini::Section& s) {
  const ini::Value& v = cx.required(s, "accesstype", "AccessType");
  const auto a = access_from_string(v.text);
  if (!a) cx.fail(v, s.name, "'" + v.text + "' is not an access type (ro, wo, rw, rwr, rww, const)");
  return *a;
}

// The fields of a value: type, access, values, limits, mapping. `s` holds them (a VAR's or a
// sub-object's section, or the ARRAY's own for compact sub-objects).
void read_value_fields(const Context& cx, const ini::Section& s, EdsEntry& e) {
  e.type = data_type_of(cx, s);
  e.access = access_of(cx, s);
  const bool numeric = is_numeric(type_class(e.type));
  for (const auto& [key, field] : {std::pair{"lowlimit", &e.low}, std::pair{"highlimit", &e.high}}) {
    const ini::Value* v = s.find(key);
    if (v == nullptr || v->text.empty()) continue;
    if (!numeric) cx.fail(*v, s.name, "limits apply to numeric types only");
    *field = cx.value(s, *v, e.type, false).number;
  }
  if (e.low && e.high && compare(*e.low, *e.high) > 0)
    cx.fail(*s.find("lowlimit"), s.name, "LowLimit is above HighLimit");
  for (const auto& [key, field] :
       {std::pair{"defaultvalue", &e.default_value}, std::pair{"parametervalue", &e.parameter_value}}) {
    const ini::Value* v = s.find(key);
    if (v == nullptr || (v->text.empty() && numeric)) continue;
    EdsValue value = cx.value(s, *v, e.type, true);
    if (numeric && !value.node_relative) {
      if (e.low && compare(value.number, *e.low) < 0)
        cx.fail(*v, s.name, "'" + v->text + "' is below LowLimit");
      if (e.high && compare(value.number, *e.high) > 0)
        cx.fail(*v, s.name, "'" + v->text + "' is above HighLimit");
    }
    *field = std::move(value);
  }
  if (const ini::Value* v = s.find("pdomapping")) e.pdo_mapping = cx.unsigned_value(s, *v, 1) == 1;
}

EdsEntry entry_of(const Context& cx, const ini::Section& s, ObjectAddress a) {
  EdsEntry e;
  e.address = a;
  e.line = s.line;
  e.name = cx.required(s, "parametername", "ParameterName").text;
  const ObjectType t = object_type_of(cx, s);
  if (t != ObjectType::var && t != ObjectType::domain)
    cx.fail(*s.find("objecttype"), s.name, "a value's object type must be VAR (0x7) or DOMAIN (0x2)");
  read_value_fields(cx, s, e);
  return e;
}

// ARRAY with CompactSubObj=N: sub 0 holds N, subs 1..N share the object's fields; names and
// values may come from [<index>Name] and [<index>Value].
void expand_compact(const Context& cx, const ini::Section& s, const ini::Value& compact, EdsObject& object,
                    Eds& eds) {
  const auto n = static_cast<std::uint8_t>(cx.unsigned_value(s, compact, 0xFE));
  object.sub_number = static_cast<std::uint8_t>(n + 1);
  EdsEntry count;
  count.address = {object.index, 0};
  count.name = "Number of entries";
  count.type = DataType::unsigned8;
  count.access = Access::ro;
  count.default_value = EdsValue{std::to_string(n), false, std::uint64_t{n}, {}};
  count.line = s.line;
  eds.entries.emplace(count.address, count);
  char suffix[8];
  std::snprintf(suffix, sizeof suffix, "%04x", object.index);
  const ini::Section* names = cx.file.find(std::string(suffix) + "name");
  const ini::Section* values = cx.file.find(std::string(suffix) + "value");
  for (std::uint8_t i = 1; i <= n; ++i) {
    EdsEntry e;
    e.address = {object.index, i};
    e.line = s.line;
    read_value_fields(cx, s, e);
    e.name = object.name + std::to_string(i);
    const std::string key = std::to_string(i);
    if (names != nullptr)
      if (const ini::Value* v = names->find(key)) e.name = v->text;
    if (values != nullptr)
      if (const ini::Value* v = values->find(key)) e.parameter_value = cx.value(*values, *v, e.type, true);
    eds.entries.emplace(e.address, std::move(e));
  }
}

void read_device_info(const Context& cx, const ini::Section& s, DeviceInfo& d) {
  const auto text = [&](std::string_view key) {
    const ini::Value* v = s.find(key);
    return v == nullptr ? std::string{} : v->text;
  };
  const auto number = [&](std::string_view key, std::uint64_t max) -> std::uint64_t {
    const ini::Value* v = s.find(key);
    return v == nullptr || v->text.empty() ? 0 : cx.unsigned_value(s, *v, max);
  };
  d.vendor_name = text("vendorname");
  d.product_name = text("productname");
  d.order_code = text("ordercode");
  d.vendor_number = static_cast<std::uint32_t>(number("vendornumber", 0xFFFFFFFF));
  d.product_number = static_cast<std::uint32_t>(number("productnumber", 0xFFFFFFFF));
  d.revision_number = static_cast<std::uint32_t>(number("revisionnumber", 0xFFFFFFFF));
  d.granularity = static_cast<std::uint8_t>(number("granularity", 64));
  d.rx_pdos = static_cast<std::uint16_t>(number("nrofrxpdo", 512));
  d.tx_pdos = static_cast<std::uint16_t>(number("nroftxpdo", 512));
  d.lss_supported = number("lss_supported", 1) == 1;
  for (unsigned rate : {10u, 20u, 50u, 125u, 250u, 500u, 800u, 1000u})
    if (number("baudrate_" + std::to_string(rate), 1) == 1) d.baud_rates.push_back(rate);
}

// An object list ([MandatoryObjects] ...): SupportedObjects=N and 1..N naming indices that must
// have a section.
void check_object_list(const Context& cx, const ini::Section& s, const Eds& eds) {
  const ini::Value& count = cx.required(s, "supportedobjects", "SupportedObjects");
  const auto n = cx.unsigned_value(s, count, 0xFFFF);
  for (std::uint64_t i = 1; i <= n; ++i) {
    const ini::Value* v = s.find(std::to_string(i));
    if (v == nullptr)
      cx.fail(count, s.name,
              "lists " + std::to_string(n) + " objects, entry " + std::to_string(i) + " is missing");
    const auto index = static_cast<std::uint16_t>(cx.unsigned_value(s, *v, 0xFFFF));
    if (!eds.objects.contains(index))
      cx.fail(*v, s.name, "object " + v->text + " has no section in the file");
  }
  for (const auto& [key, v] : s.values) {
    if (key == "supportedobjects") continue;
    const auto i = parse_integer(key);
    std::uint64_t u = 0;
    if (!i || to_value(*i, u) != Codec::ok || u < 1 || u > n)
      cx.fail(v, s.name, "not an entry 1.." + std::to_string(n) + " of this list");
  }
}

}  // namespace

const EdsEntry* Eds::find(ObjectAddress a) const noexcept {
  const auto it = entries.find(a);
  return it == entries.end() ? nullptr : &it->second;
}

std::optional<Number> Eds::value(ObjectAddress a, std::uint8_t node) const {
  const EdsEntry* e = find(a);
  if (e == nullptr || !is_numeric(type_class(e->type))) return std::nullopt;
  const std::optional<EdsValue>& v = e->parameter_value ? e->parameter_value : e->default_value;
  if (!v) return std::nullopt;
  if (!v->node_relative) return v->number;
  // The offset was checked against the type alone: the sum must fit it too.
  Number sum;
  bool fits = true;
  if (const auto* i = std::get_if<std::int64_t>(&v->number)) {
    sum = *i + node;
  } else {
    const std::uint64_t offset = std::get<std::uint64_t>(v->number);
    // An UNSIGNED64 offset near 2^64 would wrap around to a small value that fits.
    fits = offset <= std::numeric_limits<std::uint64_t>::max() - node;
    sum = offset + node;
  }
  std::uint8_t scratch[8];
  if (!fits || encode(e->type, sum, scratch) != Codec::ok)
    throw ConfigError(file, e->line, 1, to_string(a),
                      "'" + v->text + "' with node-ID " + std::to_string(node) + " does not fit " +
                          std::string(to_string(e->type)));
  return sum;
}

Eds parse_eds(std::string_view text, const std::string& file) {
  const ini::File ini = ini::parse(text, file);
  const Context cx{ini};
  Eds eds;
  eds.file = file;

  const ini::Section* info = ini.find("deviceinfo");
  if (info == nullptr) throw ConfigError(file, 1, 1, "[DeviceInfo]", "missing: every EDS has one");
  read_device_info(cx, *info, eds.device);
  const ini::Section* commissioning = ini.find("devicecomissioning");  // CiA 306 spells it so
  if (commissioning == nullptr) commissioning = ini.find("devicecommissioning");
  if (commissioning != nullptr)
    if (const ini::Value* v = commissioning->find("nodeid")) {
      const auto id = cx.unsigned_value(*commissioning, *v, 127);
      if (id == 0) cx.fail(*v, commissioning->name, "node-ID 0 is not a node");
      eds.node_id = static_cast<std::uint8_t>(id);
    }

  // Objects first, then their sub-objects, so a sub-object can be checked against its object.
  std::set<std::uint16_t> compact_objects;
  for (const ini::Section& s : ini.sections) {
    const SectionName n = classify(ini::lower(s.name));
    if (n.kind != SectionName::object) continue;
    EdsObject object;
    object.index = n.index;
    object.line = s.line;
    object.name = cx.required(s, "parametername", "ParameterName").text;
    object.type = object_type_of(cx, s);
    if (object.type == ObjectType::deftype || object.type == ObjectType::defstruct ||
        object.type == ObjectType::null)
      continue;  // type definitions: nothing a device stores
    if (object.type == ObjectType::var || object.type == ObjectType::domain) {
      eds.entries.emplace(ObjectAddress{n.index, 0}, entry_of(cx, s, {n.index, 0}));
    } else if (const ini::Value* compact = s.find("compactsubobj");
               compact != nullptr && object.type == ObjectType::array) {
      expand_compact(cx, s, *compact, object, eds);
      compact_objects.insert(n.index);
    } else {
      object.sub_number =
          static_cast<std::uint8_t>(cx.unsigned_value(s, cx.required(s, "subnumber", "SubNumber"), 0xFF));
    }
    eds.objects.emplace(n.index, std::move(object));
  }
  std::map<std::uint16_t, unsigned> subs_seen;
  for (const ini::Section& s : ini.sections) {
    const SectionName n = classify(ini::lower(s.name));
    if (n.kind != SectionName::sub) continue;
    const auto it = eds.objects.find(n.index);
    if (it == eds.objects.end()) cx.fail(s, "", "a sub-object of an object the file does not define");
    if (it->second.type != ObjectType::array && it->second.type != ObjectType::record)
      cx.fail(s, "",
              "a sub-object of a " + std::string(to_string(it->second.type)) +
                  " (only ARRAY and RECORD have them)");
    if (compact_objects.contains(n.index))
      cx.fail(s, "", "a sub-object section of an object with CompactSubObj (which defines its sub-objects)");
    eds.entries.emplace(ObjectAddress{n.index, n.subindex}, entry_of(cx, s, {n.index, n.subindex}));
    ++subs_seen[n.index];
  }
  for (const auto& [index, object] : eds.objects) {
    if (object.type != ObjectType::array && object.type != ObjectType::record) continue;
    const unsigned seen = subs_seen[index];
    if (!compact_objects.contains(index) && seen != object.sub_number) {
      char name[8];
      std::snprintf(name, sizeof name, "%04X", index);
      throw ConfigError(
          file, object.line, 1, std::string(name) + ".SubNumber",
          "says " + std::to_string(object.sub_number) + " sub-objects, the file has " + std::to_string(seen));
    }
  }

  const ini::Section* mandatory = ini.find("mandatoryobjects");
  if (mandatory == nullptr) throw ConfigError(file, 1, 1, "[MandatoryObjects]", "missing: every EDS has one");
  for (const char* list : {"mandatoryobjects", "optionalobjects", "manufacturerobjects"})
    if (const ini::Section* s = ini.find(list)) check_object_list(cx, *s, eds);
  for (const int required : {0x1000, 0x1001, 0x1018})
    if (!eds.objects.contains(static_cast<std::uint16_t>(required))) {
      char name[8];
      std::snprintf(name, sizeof name, "0x%04X", required);
      cx.fail(*mandatory, "", std::string("object ") + name + " is mandatory (CiA 301) and missing");
    }
  return eds;
}

Eds load_eds(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path, 0, 0, "", "cannot read the file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_eds(text.str(), path);
}

std::vector<PdoMapping> eds_pdo_mappings(const Eds& eds, std::uint8_t node) {
  std::vector<PdoMapping> out;
  for (const PdoKind kind : {PdoKind::rpdo, PdoKind::tpdo}) {
    for (std::uint16_t number = 1; number <= 512; ++number) {
      PdoMapping m;
      m.kind = kind;
      m.number = number;
      const ObjectAddress cob{m.communication_index(), 1};
      const EdsEntry* cob_entry = eds.find(cob);
      if (cob_entry == nullptr) continue;
      std::uint32_t id = 0;
      if (const auto v = eds.value(cob, node); !v || to_value(*v, id) != Codec::ok)
        throw ConfigError(eds.file, cob_entry->line, 1, to_string(cob),
                          "a PDO's COB-ID needs an UNSIGNED32 value");
      m.enabled = (id & pdo_invalid) == 0;
      // Bit 30 (no RTR) does not matter to us; bit 29 (a 29-bit identifier) and identifier bits
      // above the 11th would mean frames CANopen's classic set does not use.
      if (m.enabled && (id & 0x3FFFF800u) != 0)
        throw ConfigError(eds.file, cob_entry->line, 1, to_string(cob),
                          "COB-ID is not an 11-bit identifier (29-bit PDOs are not supported)");
      m.cob_id = id & CAN_SFF_MASK;
      if (const auto t = eds.value({m.communication_index(), 2}, node)) (void)to_value(*t, m.transmission);
      if (const auto t = eds.value({m.communication_index(), 3}, node)) (void)to_value(*t, m.inhibit_time);
      if (const auto t = eds.value({m.communication_index(), 5}, node)) (void)to_value(*t, m.event_timer);
      std::uint8_t count = 0;
      if (const auto c = eds.value({m.mapping_index(), 0}, node)) (void)to_value(*c, count);
      for (std::uint8_t i = 1; i <= count; ++i) {
        const ObjectAddress at{m.mapping_index(), i};
        const EdsEntry* e = eds.find(at);
        std::uint32_t raw = 0;
        const auto v = eds.value(at, node);
        if (e == nullptr || !v || to_value(*v, raw) != Codec::ok) {
          const EdsEntry* map0 = eds.find({m.mapping_index(), 0});
          throw ConfigError(eds.file, map0 ? map0->line : 0, 1, to_string(at),
                            "the mapping count is " + std::to_string(count) + " but this entry has no value");
        }
        PdoEntry entry = PdoEntry::from_u32(raw);
        if (!entry.dummy()) {
          const EdsEntry* mapped = eds.find(entry.address);
          if (mapped == nullptr)
            throw ConfigError(eds.file, e->line, 1, to_string(at),
                              "maps " + to_string(entry.address) + ", which the file does not define");
          entry.type = mapped->type;
        }
        if (m.count < max_pdo_entries) m.entries[m.count] = entry;
        ++m.count;
      }
      if (m.count > max_pdo_entries)
        throw ConfigError(eds.file, cob_entry->line, 1, to_string({m.mapping_index(), 0}),
                          std::to_string(m.count) + " entries mapped, a PDO has at most 8");
      if (m.enabled) {
        try {
          check(m);
        } catch (const std::invalid_argument& e) {
          throw ConfigError(eds.file, cob_entry->line, 1, to_string(cob), e.what());
        }
      }
      out.push_back(m);
    }
  }
  return out;
}

LocalDictionary make_dictionary(const Eds& eds, std::uint8_t node, std::size_t string_capacity) {
  LocalDictionary d;
  for (const auto& [address, e] : eds.entries) {
    Entry entry;
    entry.name = e.name;
    entry.type = e.type;
    entry.access = e.access;
    entry.low = e.low;
    entry.high = e.high;
    entry.pdo_mappable = e.pdo_mapping;
    if (is_numeric(type_class(e.type))) {
      entry.value.resize(size_of(e.type));
      const Number n = eds.value(address, node).value_or(std::uint64_t{0});
      if (encode(e.type, n, entry.value) != Codec::ok)
        throw ConfigError(eds.file, e.line, 1, to_string(address),
                          "its value does not fit " + std::string(to_string(e.type)));
    } else {
      const auto& v = e.parameter_value ? e.parameter_value : e.default_value;
      if (v) entry.value = v->bytes;
      entry.capacity = string_capacity;
    }
    try {
      d.add(address, std::move(entry));
    } catch (const std::invalid_argument& x) {
      throw ConfigError(eds.file, e.line, 1, to_string(address), x.what());
    }
  }
  return d;
}

}  // namespace saw::canopen
