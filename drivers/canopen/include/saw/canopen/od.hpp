// Object dictionary addressing and the CiA 301 data types: what a value's bytes mean on the bus.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>

namespace saw::canopen {

// An entry of the object dictionary: 16-bit index, 8-bit sub-index.
struct ObjectAddress {
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  friend constexpr auto operator<=>(const ObjectAddress&, const ObjectAddress&) = default;
};
// "0x6040:00", the way vendors' manuals write it.
std::string to_string(ObjectAddress a);

// The static data types of CiA 301 (7.4.7.1), by their object-dictionary index.
enum class DataType : std::uint16_t {
  boolean = 0x0001,
  integer8 = 0x0002,
  integer16 = 0x0003,
  integer32 = 0x0004,
  unsigned8 = 0x0005,
  unsigned16 = 0x0006,
  unsigned32 = 0x0007,
  real32 = 0x0008,
  visible_string = 0x0009,
  octet_string = 0x000A,
  unicode_string = 0x000B,
  domain = 0x000F,
  integer24 = 0x0010,
  real64 = 0x0011,
  integer40 = 0x0012,
  integer48 = 0x0013,
  integer56 = 0x0014,
  integer64 = 0x0015,
  unsigned24 = 0x0016,
  unsigned40 = 0x0018,
  unsigned48 = 0x0019,
  unsigned56 = 0x001A,
  unsigned64 = 0x001B,
};

// How a type's bytes are read: the codec's switch, and what an EDS value must parse as.
enum class TypeClass : std::uint8_t { boolean, signed_integer, unsigned_integer, real, bytes };

// The type with this code, if it is one of the above (TIME_OF_DAY and the like are not).
std::optional<DataType> data_type_from_code(std::uint32_t code) noexcept;
std::string_view to_string(DataType t) noexcept;  // "UNSIGNED16", as CiA 301 spells it
TypeClass type_class(DataType t) noexcept;
// Bytes of a value of this type; 0 for the variable-length ones (strings, DOMAIN).
std::size_t size_of(DataType t) noexcept;
constexpr bool is_numeric(TypeClass c) noexcept { return c != TypeClass::bytes; }

// A number as the dictionary holds it before encoding: signed and unsigned integers in 64 bits
// (UNSIGNED64 needs the full unsigned range), reals as double.
using Number = std::variant<std::int64_t, std::uint64_t, double>;

// What a conversion between a number and its bytes found. Every failure is a reason an SDO
// server would abort with (value too high, too low, invalid, wrong length).
enum class Codec : std::uint8_t {
  ok,
  wrong_length,  // the bytes are not size_of(type) long
  too_high,      // above the type's (or the target's) range
  too_low,       // below it
  invalid,       // not a value of the type: NaN or infinity, a BOOLEAN other than 0 or 1,
                 // a fraction for an integer type, a string type given to the numeric codec
};
std::string_view to_string(Codec c) noexcept;

// Writes `value` as `type`, little-endian, into the first size_of(type) bytes of `out`.
// Range-checked: 300 as UNSIGNED8 is too_high, -1 is too_low, 1.5 as an integer is invalid.
Codec encode(DataType type, Number value, std::span<std::uint8_t> out) noexcept;
// Reads a value of `type` from exactly size_of(type) bytes.
Codec decode(DataType type, std::span<const std::uint8_t> in, Number& out) noexcept;

// Range limits of a numeric type as numbers (REAL32: ±FLT_MAX).
Number type_min(DataType t) noexcept;
Number type_max(DataType t) noexcept;
// -1, 0 or 1 as a is below, equal to or above b, exactly (no rounding through double for
// integers); NaN compares as unordered and yields 2.
int compare(const Number& a, const Number& b) noexcept;

// Number <-> C++ arithmetic types, range-checked (a double must be finite, and integral when
// the target is an integer).
template <class T>
Codec to_value(const Number& n, T& out) noexcept;
template <class T>
Number to_number(T v) noexcept;

// Typed shorthands: encode(type, to_number(v)) and decode-then-to_value.
template <class T>
Codec encode_value(DataType type, T value, std::span<std::uint8_t> out) noexcept {
  return encode(type, to_number(value), out);
}
template <class T>
Codec decode_value(DataType type, std::span<const std::uint8_t> in, T& out) noexcept {
  Number n;
  const Codec c = decode(type, in, n);
  return c == Codec::ok ? to_value(n, out) : c;
}

// ---- implementation of the templates ------------------------------------------------------

template <class T>
Number to_number(T v) noexcept {
  static_assert(std::is_arithmetic_v<T>);
  if constexpr (std::is_same_v<T, bool>) {
    return std::uint64_t{v ? 1U : 0U};
  } else if constexpr (std::is_floating_point_v<T>) {
    return static_cast<double>(v);
  } else if constexpr (std::is_signed_v<T>) {
    return static_cast<std::int64_t>(v);
  } else {
    return static_cast<std::uint64_t>(v);
  }
}

template <class T>
Codec to_value(const Number& n, T& out) noexcept {
  static_assert(std::is_arithmetic_v<T>);
  if constexpr (std::is_same_v<T, bool>) {
    std::uint64_t u = 0;
    if (const Codec c = to_value(n, u); c != Codec::ok) return c;
    if (u > 1) return Codec::invalid;
    out = u == 1;
    return Codec::ok;
  } else if constexpr (std::is_floating_point_v<T>) {
    double d = 0;
    if (const auto* i = std::get_if<std::int64_t>(&n)) {
      d = static_cast<double>(*i);
    } else if (const auto* u = std::get_if<std::uint64_t>(&n)) {
      d = static_cast<double>(*u);
    } else {
      d = std::get<double>(n);
    }
    if (!std::isfinite(d)) return Codec::invalid;
    if (d > static_cast<double>(std::numeric_limits<T>::max())) return Codec::too_high;
    if (d < static_cast<double>(std::numeric_limits<T>::lowest())) return Codec::too_low;
    out = static_cast<T>(d);
    return Codec::ok;
  } else {
    if (const auto* i = std::get_if<std::int64_t>(&n)) {
      if (std::cmp_greater(*i, std::numeric_limits<T>::max())) return Codec::too_high;
      if (std::cmp_less(*i, std::numeric_limits<T>::min())) return Codec::too_low;
      out = static_cast<T>(*i);
      return Codec::ok;
    }
    if (const auto* u = std::get_if<std::uint64_t>(&n)) {
      if (std::cmp_greater(*u, std::numeric_limits<T>::max())) return Codec::too_high;
      out = static_cast<T>(*u);
      return Codec::ok;
    }
    const double d = std::get<double>(n);
    if (!std::isfinite(d) || d != std::trunc(d)) return Codec::invalid;
    // 2^63 and 2^64 are exact doubles: compare against them, not against max() rounded up.
    constexpr double two63 = 9223372036854775808.0;
    if (d >= (std::is_signed_v<T> ? two63 : 2 * two63)) return Codec::too_high;
    if (d < (std::is_signed_v<T> ? -two63 : 0.0)) return Codec::too_low;
    if constexpr (std::is_signed_v<T>) {
      return to_value(Number{static_cast<std::int64_t>(d)}, out);
    } else {
      return to_value(Number{static_cast<std::uint64_t>(d)}, out);
    }
  }
}

}  // namespace saw::canopen
