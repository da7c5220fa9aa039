#include "saw/canopen/od.hpp"

#include <bit>
#include <cfloat>
#include <cstdio>
#include <cstring>

#include "saw/canopen/cob.hpp"

namespace saw::canopen {

bool canopen_data_frame(const can::Frame& f) noexcept {
  return can::well_formed(f) && !f.fd() && !f.extended() && !f.remote() && !f.error();
}

std::string to_string(ObjectAddress a) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04X:%02X", static_cast<unsigned>(a.index),
                static_cast<unsigned>(a.subindex));
  return buf;
}

std::optional<DataType> data_type_from_code(std::uint32_t code) noexcept {
  switch (code) {
    case 0x01:
    case 0x02:
    case 0x03:
    case 0x04:
    case 0x05:
    case 0x06:
    case 0x07:
    case 0x08:
    case 0x09:
    case 0x0A:
    case 0x0B:
    case 0x0F:
    case 0x10:
    case 0x11:
    case 0x12:
    case 0x13:
    case 0x14:
    case 0x15:
    case 0x16:
    case 0x18:
    case 0x19:
    case 0x1A:
    case 0x1B:
      return static_cast<DataType>(code);
    default:
      return std::nullopt;
  }
}

std::string_view to_string(DataType t) noexcept {
  switch (t) {
    case DataType::boolean:
      return "BOOLEAN";
    case DataType::integer8:
      return "INTEGER8";
    case DataType::integer16:
      return "INTEGER16";
    case DataType::integer24:
      return "INTEGER24";
    case DataType::integer32:
      return "INTEGER32";
    case DataType::integer40:
      return "INTEGER40";
    case DataType::integer48:
      return "INTEGER48";
    case DataType::integer56:
      return "INTEGER56";
    case DataType::integer64:
      return "INTEGER64";
    case DataType::unsigned8:
      return "UNSIGNED8";
    case DataType::unsigned16:
      return "UNSIGNED16";
    case DataType::unsigned24:
      return "UNSIGNED24";
    case DataType::unsigned32:
      return "UNSIGNED32";
    case DataType::unsigned40:
      return "UNSIGNED40";
    case DataType::unsigned48:
      return "UNSIGNED48";
    case DataType::unsigned56:
      return "UNSIGNED56";
    case DataType::unsigned64:
      return "UNSIGNED64";
    case DataType::real32:
      return "REAL32";
    case DataType::real64:
      return "REAL64";
    case DataType::visible_string:
      return "VISIBLE_STRING";
    case DataType::octet_string:
      return "OCTET_STRING";
    case DataType::unicode_string:
      return "UNICODE_STRING";
    case DataType::domain:
      return "DOMAIN";
  }
  return "unknown data type";
}

TypeClass type_class(DataType t) noexcept {
  switch (t) {
    case DataType::boolean:
      return TypeClass::boolean;
    case DataType::integer8:
    case DataType::integer16:
    case DataType::integer24:
    case DataType::integer32:
    case DataType::integer40:
    case DataType::integer48:
    case DataType::integer56:
    case DataType::integer64:
      return TypeClass::signed_integer;
    case DataType::unsigned8:
    case DataType::unsigned16:
    case DataType::unsigned24:
    case DataType::unsigned32:
    case DataType::unsigned40:
    case DataType::unsigned48:
    case DataType::unsigned56:
    case DataType::unsigned64:
      return TypeClass::unsigned_integer;
    case DataType::real32:
    case DataType::real64:
      return TypeClass::real;
    case DataType::visible_string:
    case DataType::octet_string:
    case DataType::unicode_string:
    case DataType::domain:
      return TypeClass::bytes;
  }
  return TypeClass::bytes;
}

std::size_t size_of(DataType t) noexcept {
  switch (t) {
    case DataType::boolean:
    case DataType::integer8:
    case DataType::unsigned8:
      return 1;
    case DataType::integer16:
    case DataType::unsigned16:
      return 2;
    case DataType::integer24:
    case DataType::unsigned24:
      return 3;
    case DataType::integer32:
    case DataType::unsigned32:
    case DataType::real32:
      return 4;
    case DataType::integer40:
    case DataType::unsigned40:
      return 5;
    case DataType::integer48:
    case DataType::unsigned48:
      return 6;
    case DataType::integer56:
    case DataType::unsigned56:
      return 7;
    case DataType::integer64:
    case DataType::unsigned64:
    case DataType::real64:
      return 8;
    case DataType::visible_string:
    case DataType::octet_string:
    case DataType::unicode_string:
    case DataType::domain:
      return 0;
  }
  return 0;
}

std::string_view to_string(Codec c) noexcept {
  switch (c) {
    case Codec::ok:
      return "ok";
    case Codec::wrong_length:
      return "wrong length";
    case Codec::too_high:
      return "value too high";
    case Codec::too_low:
      return "value too low";
    case Codec::invalid:
      return "invalid value";
  }
  return "unknown";
}

namespace {

void put_le(std::uint64_t v, std::size_t n, std::span<std::uint8_t> out) noexcept {
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::uint64_t get_le(std::span<const std::uint8_t> in) noexcept {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < in.size(); ++i) v |= static_cast<std::uint64_t>(in[i]) << (8 * i);
  return v;
}

// Largest value of an n-byte signed integer (n in 1..8).
std::int64_t signed_max(std::size_t n) noexcept {
  return static_cast<std::int64_t>((std::uint64_t{1} << (8 * n - 1)) - 1);
}
std::uint64_t unsigned_max(std::size_t n) noexcept {
  return n >= 8 ? std::numeric_limits<std::uint64_t>::max() : (std::uint64_t{1} << (8 * n)) - 1;
}

}  // namespace

Number type_min(DataType t) noexcept {
  switch (type_class(t)) {
    case TypeClass::signed_integer:
      return std::int64_t{-signed_max(size_of(t)) - 1};
    case TypeClass::real:
      return t == DataType::real32 ? -static_cast<double>(FLT_MAX) : -DBL_MAX;
    default:
      return std::uint64_t{0};
  }
}

Number type_max(DataType t) noexcept {
  switch (type_class(t)) {
    case TypeClass::boolean:
      return std::uint64_t{1};
    case TypeClass::signed_integer:
      return signed_max(size_of(t));
    case TypeClass::unsigned_integer:
      return unsigned_max(size_of(t));
    case TypeClass::real:
      return t == DataType::real32 ? static_cast<double>(FLT_MAX) : DBL_MAX;
    case TypeClass::bytes:
      return std::uint64_t{0};
  }
  return std::uint64_t{0};
}

int compare(const Number& a, const Number& b) noexcept {
  if (std::holds_alternative<double>(a) || std::holds_alternative<double>(b)) {
    const auto as_double = [](const Number& n) {
      return std::visit([](auto v) { return static_cast<double>(v); }, n);
    };
    const double x = as_double(a), y = as_double(b);
    if (std::isnan(x) || std::isnan(y)) return 2;
    return x < y ? -1 : (x == y ? 0 : 1);
  }
  const auto order = [](auto x, auto y) { return std::cmp_less(x, y) ? -1 : (std::cmp_equal(x, y) ? 0 : 1); };
  if (const auto* x = std::get_if<std::int64_t>(&a)) {
    if (const auto* y = std::get_if<std::int64_t>(&b)) return order(*x, *y);
    return order(*x, std::get<std::uint64_t>(b));
  }
  const std::uint64_t x = std::get<std::uint64_t>(a);
  if (const auto* y = std::get_if<std::int64_t>(&b)) return order(x, *y);
  return order(x, std::get<std::uint64_t>(b));
}

Codec encode(DataType type, Number value, std::span<std::uint8_t> out) noexcept {
  const std::size_t n = size_of(type);
  if (type_class(type) == TypeClass::bytes) return Codec::invalid;
  if (out.size() < n) return Codec::wrong_length;
  switch (type_class(type)) {
    case TypeClass::boolean: {
      // A BOOLEAN has two values; anything else is not "too high", it is not a boolean.
      std::uint64_t u = 0;
      if (to_value(value, u) != Codec::ok || u > 1) return Codec::invalid;
      out[0] = static_cast<std::uint8_t>(u);
      return Codec::ok;
    }
    case TypeClass::signed_integer: {
      std::int64_t i = 0;
      if (const Codec c = to_value(value, i); c != Codec::ok) return c;
      if (i > signed_max(n)) return Codec::too_high;
      if (i < -signed_max(n) - 1) return Codec::too_low;
      put_le(static_cast<std::uint64_t>(i), n, out);
      return Codec::ok;
    }
    case TypeClass::unsigned_integer: {
      std::uint64_t u = 0;
      if (const Codec c = to_value(value, u); c != Codec::ok) return c;
      if (u > unsigned_max(n)) return Codec::too_high;
      put_le(u, n, out);
      return Codec::ok;
    }
    case TypeClass::real: {
      double d = 0;
      if (const Codec c = to_value(value, d); c != Codec::ok) return c;
      if (type == DataType::real32) {
        if (d > FLT_MAX) return Codec::too_high;
        if (d < -FLT_MAX) return Codec::too_low;
        put_le(std::bit_cast<std::uint32_t>(static_cast<float>(d)), 4, out);
      } else {
        put_le(std::bit_cast<std::uint64_t>(d), 8, out);
      }
      return Codec::ok;
    }
    case TypeClass::bytes:
      break;
  }
  return Codec::invalid;
}

Codec decode(DataType type, std::span<const std::uint8_t> in, Number& out) noexcept {
  const std::size_t n = size_of(type);
  if (type_class(type) == TypeClass::bytes) return Codec::invalid;
  if (in.size() != n) return Codec::wrong_length;
  const std::uint64_t raw = get_le(in);
  switch (type_class(type)) {
    case TypeClass::boolean:
      if (raw > 1) return Codec::invalid;
      out = raw;
      return Codec::ok;
    case TypeClass::signed_integer: {
      // Sign-extend from the type's top bit: shift it to bit 63, then back arithmetically.
      const unsigned unused = static_cast<unsigned>(64 - 8 * n);
      out = static_cast<std::int64_t>(raw << unused) >> unused;
      return Codec::ok;
    }
    case TypeClass::unsigned_integer:
      out = raw;
      return Codec::ok;
    case TypeClass::real: {
      const double d = type == DataType::real32
                           ? static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(raw)))
                           : std::bit_cast<double>(raw);
      if (!std::isfinite(d)) return Codec::invalid;
      out = d;
      return Codec::ok;
    }
    case TypeClass::bytes:
      break;
  }
  return Codec::invalid;
}

}  // namespace saw::canopen
