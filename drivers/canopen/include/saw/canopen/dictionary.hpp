// An object dictionary as an SDO server sees it, and an in-memory one for simulated devices.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "saw/canopen/od.hpp"
#include "saw/canopen/sdo.hpp"

namespace saw::canopen {

// CiA 306 AccessType. rwr and rww are read-write objects that a TPDO (rwr) or an RPDO (rww)
// may map; const is read-only and never changes.
enum class Access : std::uint8_t { ro, wo, rw, rwr, rww, const_ };
// "ro", "wo", "rw", "rwr", "rww", "const", in any case; nullopt for anything else.
std::optional<Access> access_from_string(std::string_view s) noexcept;
std::string_view to_string(Access a) noexcept;
constexpr bool readable(Access a) noexcept { return a != Access::wo; }
constexpr bool writable(Access a) noexcept { return a != Access::ro && a != Access::const_; }

// What an SDO server serves. Every call answers with an abort code (none: success), so the
// server never decides what an object accepts: the dictionary behind it does.
class ObjectDictionary {
 public:
  virtual ~ObjectDictionary() = default;
  // Whether a segmented download to `address` may begin; `size` if the client indicated one.
  // Asked at the initiate so that a client learns "no such object" before sending the data.
  virtual SdoAbort check_download(ObjectAddress address, std::optional<std::size_t> size) noexcept = 0;
  // Copies the value's bytes into `out`; `size` is set to how many.
  virtual SdoAbort read(ObjectAddress address, std::span<std::uint8_t> out, std::size_t& size) noexcept = 0;
  // Stores `data`. `size_indicated` false: an expedited download that did not say its size,
  // whose 4 bytes may be longer than the object (the object's own size is used).
  virtual SdoAbort write(ObjectAddress address, std::span<const std::uint8_t> data,
                         bool size_indicated) noexcept = 0;
};

// One entry of a LocalDictionary.
struct Entry {
  std::string name;
  DataType type = DataType::unsigned8;
  Access access = Access::rw;
  std::vector<std::uint8_t> value;  // encoded; numeric types: exactly size_of(type) bytes
  std::optional<Number> low, high;  // limits of a numeric value (EDS LowLimit/HighLimit)
  std::size_t capacity = 0;         // strings and DOMAIN: most bytes a write may store
  bool pdo_mappable = false;
};

// An object dictionary held in memory: the simulated drive's, built by hand or from an EDS.
// Lookups and writes of numeric values neither allocate nor throw (strings and domains are
// reserved to their capacity when added), so a simulated device may serve SDO in its cycle.
class LocalDictionary final : public ObjectDictionary {
 public:
  // Checked before an SDO write is stored: a result other than none refuses the write with
  // that abort (a mode the drive does not support, a write the device state forbids).
  using WriteHook = std::function<SdoAbort(ObjectAddress, std::span<const std::uint8_t>)>;

  // Set-up: adds an entry; throws std::invalid_argument naming the address for a duplicate,
  // a numeric value of the wrong size, or a value outside its limits.
  void add(ObjectAddress address, Entry entry);
  // Set-up shorthand for a numeric entry.
  template <class T>
  void add_value(ObjectAddress address, std::string name, DataType type, Access access, T value,
                 std::optional<Number> low = std::nullopt, std::optional<Number> high = std::nullopt);
  void on_write(WriteHook hook) { hook_ = std::move(hook); }

  const Entry* find(ObjectAddress address) const noexcept;
  bool has_index(std::uint16_t index) const noexcept;
  std::size_t size() const noexcept { return entries_.size(); }
  const std::map<ObjectAddress, Entry>& entries() const noexcept { return entries_; }

  // The device's own access (its application updating 0x6041, reading 0x6040): access rights
  // do not apply, type and limits do.
  template <class T>
  Codec set(ObjectAddress address, T value) noexcept;
  template <class T>
  Codec get(ObjectAddress address, T& out) const noexcept;

  SdoAbort check_download(ObjectAddress address, std::optional<std::size_t> size) noexcept override;
  SdoAbort read(ObjectAddress address, std::span<std::uint8_t> out, std::size_t& size) noexcept override;
  SdoAbort write(ObjectAddress address, std::span<const std::uint8_t> data,
                 bool size_indicated) noexcept override;

 private:
  // Whether `data` is a value `e` may hold (length, type, limits), as an abort code.
  static SdoAbort check_value(const Entry& e, std::span<const std::uint8_t> data) noexcept;
  SdoAbort lookup(ObjectAddress address, Entry*& out) noexcept;

  std::map<ObjectAddress, Entry> entries_;
  WriteHook hook_;
};

template <class T>
void LocalDictionary::add_value(ObjectAddress address, std::string name, DataType type, Access access,
                                T value, std::optional<Number> low, std::optional<Number> high) {
  Entry e;
  e.name = std::move(name);
  e.type = type;
  e.access = access;
  e.low = low;
  e.high = high;
  e.value.resize(size_of(type));
  if (encode_value(type, value, e.value) != Codec::ok) e.value.clear();  // add() names the problem
  add(address, std::move(e));
}

template <class T>
Codec LocalDictionary::set(ObjectAddress address, T value) noexcept {
  const auto it = entries_.find(address);
  if (it == entries_.end() || !is_numeric(type_class(it->second.type))) return Codec::invalid;
  std::uint8_t bytes[8];
  const std::span<std::uint8_t> span(bytes, size_of(it->second.type));
  if (const Codec c = encode_value(it->second.type, value, span); c != Codec::ok) return c;
  switch (check_value(it->second, span)) {
    case SdoAbort::none:
      break;
    case SdoAbort::value_too_high:
      return Codec::too_high;
    case SdoAbort::value_too_low:
      return Codec::too_low;
    default:
      return Codec::invalid;
  }
  std::copy(span.begin(), span.end(), it->second.value.begin());
  return Codec::ok;
}

template <class T>
Codec LocalDictionary::get(ObjectAddress address, T& out) const noexcept {
  const Entry* e = find(address);
  if (e == nullptr || !is_numeric(type_class(e->type))) return Codec::invalid;
  return decode_value(e->type, std::span<const std::uint8_t>(e->value), out);
}

}  // namespace saw::canopen
