// EDS and DCF files (CiA 306) read into a checked description of a device's object dictionary.
//
// Configuration-time code: it allocates and throws saw::deploy::ConfigError naming
// file:line:column and the key ("1018sub1.DefaultValue").
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/od.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/deploy/config_error.hpp"

namespace saw::canopen {

// CiA 306 ObjectType.
enum class ObjectType : std::uint8_t {
  null = 0x0,
  domain = 0x2,
  deftype = 0x5,
  defstruct = 0x6,
  var = 0x7,
  array = 0x8,
  record = 0x9
};
std::string_view to_string(ObjectType t) noexcept;

// A value as the file writes it: a number (possibly "$NODEID+0x180", to be added to the node-ID),
// or the bytes of a string or domain.
struct EdsValue {
  std::string text;                 // as written
  bool node_relative = false;       // "$NODEID" appears: the node-ID is added
  Number number = std::int64_t{0};  // numeric types: the value, or the offset from the node-ID
  std::vector<std::uint8_t> bytes;  // strings (their characters), octet strings and domains (hex)
};

// One value of the dictionary: a VAR, or one sub-object of an ARRAY or RECORD.
struct EdsEntry {
  ObjectAddress address;
  std::string name;  // ParameterName
  DataType type = DataType::unsigned8;
  Access access = Access::ro;
  std::optional<EdsValue> default_value;    // DefaultValue
  std::optional<EdsValue> parameter_value;  // ParameterValue (a DCF's configured value)
  std::optional<Number> low, high;          // LowLimit, HighLimit
  bool pdo_mapping = false;
  int line = 0;  // the line of its section header
};

// One index: a VAR (its entry is sub-index 0), an ARRAY or a RECORD.
struct EdsObject {
  std::uint16_t index = 0;
  std::string name;
  ObjectType type = ObjectType::var;
  std::uint8_t sub_number = 0;  // SubNumber or CompactSubObj + 1 (ARRAY, RECORD)
  int line = 0;
};

struct DeviceInfo {
  std::string vendor_name, product_name, order_code;
  std::uint32_t vendor_number = 0, product_number = 0, revision_number = 0;
  std::vector<unsigned> baud_rates;  // kbit/s, those BaudRate_<n>=1 lists
  std::uint8_t granularity = 0;
  std::uint16_t rx_pdos = 0, tx_pdos = 0;
  bool lss_supported = false;
};

struct Eds {
  std::string file;
  DeviceInfo device;
  std::optional<std::uint8_t> node_id;  // DCF: [DeviceComissioning] NodeID
  std::map<std::uint16_t, EdsObject> objects;
  std::map<ObjectAddress, EdsEntry> entries;

  const EdsEntry* find(ObjectAddress a) const noexcept;
  // The entry's value for a node: ParameterValue if given (DCF), else DefaultValue, with
  // $NODEID resolved; nullopt for an entry without either or a non-numeric one. Throws
  // ConfigError if the resolved value leaves the entry's type (e.g. $NODEID+0xFF as UNSIGNED8).
  std::optional<Number> value(ObjectAddress a, std::uint8_t node_id) const;
};

// Parses an EDS or DCF held in memory; `file` names it in errors.
Eds parse_eds(std::string_view text, const std::string& file);
// Reads and parses a file; a file that cannot be read is a ConfigError at line 0.
Eds load_eds(const std::string& path);

// The PDOs the file's communication and mapping parameters describe (0x1400.. with 0x1600..,
// 0x1800.. with 0x1A00..), for `node_id`; entry types come from the mapped objects. A mapping of
// an object the file does not define, or one check() refuses, is a ConfigError.
std::vector<PdoMapping> eds_pdo_mappings(const Eds& eds, std::uint8_t node_id);

// An in-memory dictionary holding the file's values for `node_id` (the simulated device):
// numeric entries without a value hold 0, strings and domains may grow to `string_capacity`.
LocalDictionary make_dictionary(const Eds& eds, std::uint8_t node_id, std::size_t string_capacity = 256);

}  // namespace saw::canopen
