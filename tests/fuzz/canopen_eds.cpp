// Fuzz target: an EDS or DCF file (CiA 306) as a vendor or a user could write it, read as a
// deployment reads one: parse_eds(), each entry's value for a node, make_dictionary() and
// eds_pdo_mappings(). Every problem must be a ConfigError naming the file and a line of it
// (fuzz.eds:line:column: key '…': what); any other exception, or a crash, is a defect. What the
// calls return must keep the header's promises: values of their entry's type, within its limits,
// PDO mappings that check() accepts.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>
#include <typeinfo>

#include "saw/canopen/eds.hpp"
#include "saw/canopen/pdo.hpp"

namespace {

namespace co = saw::canopen;
using saw::deploy::ConfigError;

const std::string file = "fuzz.eds";

[[noreturn]] void defect(const std::string& what) {
  std::fprintf(stderr, "%s\n", what.c_str());
  std::abort();
}

void check(bool ok, const char* what) {
  if (!ok) defect(what);
}

// Runs one step; a ConfigError must name the file and a line of it (line 1 for what is missing
// from the whole file). Returns whether the step succeeded.
template <class F>
bool step(const char* what, int lines, F&& f) {
  try {
    f();
    return true;
  } catch (const ConfigError& e) {
    if (e.file() != file || std::string_view(e.what()).substr(0, file.size() + 1) != file + ":")
      defect(std::string(what) + ": a ConfigError that does not name the file: " + e.what());
    if (e.line() < 1 || e.line() > lines)
      defect(std::string(what) + ": a ConfigError naming a line the file does not have: " + e.what());
    if (e.key().empty()) defect(std::string(what) + ": a ConfigError without a key: " + e.what());
  } catch (const std::exception& e) {
    defect(std::string(what) + ": " + typeid(e).name() + " escaped: " + e.what());
  }
  return false;
}

// A value the file gives an entry: of its type, within its limits when it is not node-relative.
void check_value(const co::EdsEntry& e, const co::EdsValue& v) {
  const co::TypeClass c = co::type_class(e.type);
  if (!co::is_numeric(c)) {
    if (e.type == co::DataType::visible_string)
      for (const std::uint8_t b : v.bytes)
        check(b >= 0x20 && b < 0x7F, "an unprintable VISIBLE_STRING value");
    return;
  }
  check(!v.node_relative || c == co::TypeClass::signed_integer || c == co::TypeClass::unsigned_integer,
        "$NODEID in a value that is not an integer");
  std::uint8_t bytes[8];
  check(co::encode(e.type, v.number, bytes) == co::Codec::ok, "a value (or $NODEID offset) outside its type");
  if (v.node_relative) return;
  check(!e.low || co::compare(v.number, *e.low) >= 0, "a value below LowLimit");
  check(!e.high || co::compare(v.number, *e.high) <= 0, "a value above HighLimit");
}

void check_parsed(const co::Eds& eds) {
  check(eds.file == file, "the Eds names another file");
  check(!eds.node_id || co::valid_node_id(*eds.node_id), "a DCF node-ID outside 1..127");
  for (const std::uint16_t index : {std::uint16_t{0x1000}, std::uint16_t{0x1001}, std::uint16_t{0x1018}})
    check(eds.objects.contains(index), "a file without a mandatory object was accepted");
  for (const auto& [a, e] : eds.entries) {
    check(a == e.address, "an entry filed under another address");
    const auto object = eds.objects.find(a.index);
    check(object != eds.objects.end(), "an entry of an object the file does not define");
    if (object->second.type == co::ObjectType::var || object->second.type == co::ObjectType::domain)
      check(a.subindex == 0, "a sub-index other than 0 in a VAR");
    if (e.low && e.high) check(co::compare(*e.low, *e.high) <= 0, "LowLimit above HighLimit");
    for (const auto* v : {&e.low, &e.high})
      if (*v) {
        std::uint8_t bytes[8];
        check(co::encode(e.type, **v, bytes) == co::Codec::ok, "a limit outside its type");
      }
    if (e.default_value) check_value(e, *e.default_value);
    if (e.parameter_value) check_value(e, *e.parameter_value);
  }
}

// The value for a node: ParameterValue or DefaultValue with the node-ID added, of the type.
void check_resolved(const co::Eds& eds, std::uint8_t node, int lines) {
  for (const auto& item : eds.entries) {
    const co::ObjectAddress a = item.first;  // not a structured binding: clang 14 lambdas cannot capture one
    const co::EdsEntry& e = item.second;
    (void)step("value()", lines, [&] {
      const auto n = eds.value(a, node);
      if (!n) return;
      check(co::is_numeric(co::type_class(e.type)), "a numeric value for a string or domain");
      std::uint8_t bytes[8];
      check(co::encode(e.type, *n, bytes) == co::Codec::ok, "value() outside the entry's type");
      const auto& v = e.parameter_value ? e.parameter_value : e.default_value;
      check(v.has_value(), "value() for an entry without a value");
      // A node-relative value is the offset plus the node-ID, so above the offset (a sum that
      // wrapped around would be a different, smaller value).
      if (v->node_relative) check(co::compare(*n, v->number) > 0, "$NODEID plus the offset wrapped around");
    });
  }
}

void check_dictionary(const co::Eds& eds, const co::LocalDictionary& d) {
  check(d.size() == eds.entries.size(), "make_dictionary() lost or added entries");
  for (const auto& [a, e] : eds.entries) {
    const co::Entry* entry = d.find(a);
    check(entry != nullptr && entry->type == e.type && entry->access == e.access,
          "make_dictionary() changed an entry");
    if (!co::is_numeric(co::type_class(e.type))) {
      check(entry->value.size() <= entry->capacity, "a string beyond its capacity");
      continue;
    }
    co::Number n;
    check(co::decode(e.type, entry->value, n) == co::Codec::ok, "a dictionary value that does not decode");
    check(!e.low || co::compare(n, *e.low) >= 0, "a dictionary value below LowLimit");
    check(!e.high || co::compare(n, *e.high) <= 0, "a dictionary value above HighLimit");
  }
}

void check_mappings(const std::vector<co::PdoMapping>& maps) {
  for (const co::PdoMapping& m : maps) {
    check(m.number >= 1 && m.number <= 512 && m.count <= co::max_pdo_entries, "a mapping out of its bounds");
    if (!m.enabled) continue;
    check(m.cob_id <= CAN_SFF_MASK, "a PDO identifier beyond 11 bits");
    try {
      const co::PdoLayout layout(m);  // what the master builds from it
      check(layout.bytes() <= 8, "a PDO longer than 8 bytes");
    } catch (const std::exception& e) {
      defect(std::string("eds_pdo_mappings() returned a mapping check() refuses: ") + e.what());
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  int lines = 1;
  for (const char c : text) lines += c == '\n' ? 1 : 0;
  co::Eds eds;
  if (!step("parse_eds()", lines, [&] { eds = co::parse_eds(text, file); })) return 0;
  check_parsed(eds);
  // The DCF's own node-ID, and the highest (where $NODEID+offset overflows first).
  for (const std::uint8_t node : {eds.node_id.value_or(1), std::uint8_t{127}}) {
    check_resolved(eds, node, lines);
    (void)step("make_dictionary()", lines, [&] { check_dictionary(eds, co::make_dictionary(eds, node)); });
    (void)step("eds_pdo_mappings()", lines, [&] { check_mappings(co::eds_pdo_mappings(eds, node)); });
  }
  return 0;
}
