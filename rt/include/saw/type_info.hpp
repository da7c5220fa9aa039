// TypeInfo: a value type's name, size and layout version, compared when interfaces are bound.
#pragma once

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <type_traits>

#include "saw/value_check.hpp"

namespace saw {

// Values that cross a mailbox, a state table or a process boundary are copied as bytes.
template <class T>
concept Plain =
    std::is_trivially_copyable_v<T> && std::is_standard_layout_v<T> && std::is_default_constructible_v<T>;

// How the compiler spells T: enough to tell types apart inside one binary, not to agree with
// another (GCC says "long int" where clang says "long").
template <class T>
constexpr std::string_view compiler_type_name() {
  // The compiler spells T inside its own signature; this keeps only that part.
  constexpr std::string_view f = __PRETTY_FUNCTION__;
  constexpr std::string_view key = "T = ";
  constexpr auto start = f.find(key) + key.size();
  constexpr auto end = f.find_first_of(";]", start);
  return f.substr(start, end - start);
}

// A type that crosses a process boundary (the shared-memory bridge, the DDS gateway) is
// registered: it has a name every compiler agrees on, and a layout version bumped whenever a
// field changes, so that processes built from different code refuse to connect, naming both
// types, instead of reading each other's bytes wrongly.
//   arithmetic types   named by their bytes: "bool", "int8".."int64", "uint8".."uint64",
//                      "float32", "float64" (long double has no stable layout: unregistered)
//   std::array<T, N>   "array<T's name,N>", registered when T is
//   a class            struct Gains {
//                        static constexpr std::string_view type_name = "saw::teleop::Gains";
//                        static constexpr std::uint32_t layout_version = 1;
//                        double master, slave;
//                      };   (one without the other does not compile)
//   an enum            constexpr std::string_view enum_type_name(E) { return "saw::E"; } beside
//                      it (found by ADL, like enum_count); its layout version is 1
// Any other type still connects inside one process, under its compiler's spelling, with layout
// version 0: "not registered for other processes" (the bridge's exporter refuses it).
template <class T>
struct is_std_array : std::false_type {};
template <class T, std::size_t N>
struct is_std_array<std::array<T, N>> : std::true_type {};

template <class T>
constexpr std::string_view stable_type_name();

namespace detail {

template <class T>
constexpr std::string_view arithmetic_name() {
  if constexpr (std::is_same_v<T, bool>) {
    return "bool";
  } else if constexpr (std::is_floating_point_v<T>) {
    if constexpr (!std::numeric_limits<T>::is_iec559)
      return {};
    else if constexpr (sizeof(T) == 4)
      return "float32";
    else if constexpr (sizeof(T) == 8)
      return "float64";
    else
      return {};  // long double: 80-bit x87 here, 128-bit or 64-bit elsewhere
  } else {
    constexpr bool s = std::is_signed_v<T>;
    if constexpr (sizeof(T) == 1)
      return s ? "int8" : "uint8";
    else if constexpr (sizeof(T) == 2)
      return s ? "int16" : "uint16";
    else if constexpr (sizeof(T) == 4)
      return s ? "int32" : "uint32";
    else if constexpr (sizeof(T) == 8)
      return s ? "int64" : "uint64";
    else
      return {};
  }
}

constexpr std::size_t decimal_digits(std::size_t n) {
  std::size_t d = 1;
  for (; n >= 10; n /= 10) ++d;
  return d;
}

// "array<E,N>", built once at compile time and kept in static storage.
template <class E, std::size_t N>
struct ArrayName {
  static constexpr std::string_view element = stable_type_name<E>();
  static constexpr std::size_t length = 6 + element.size() + 1 + decimal_digits(N) + 1;
  static constexpr auto chars = [] {
    std::array<char, length + 1> out{};
    std::size_t k = 0;
    for (char c : std::string_view("array<")) out[k++] = c;
    for (char c : element) out[k++] = c;
    out[k++] = ',';
    for (std::size_t i = decimal_digits(N), n = N; i > 0; --i, n /= 10)
      out[k + i - 1] = static_cast<char>('0' + n % 10);
    k += decimal_digits(N);
    out[k] = '>';
    return out;
  }();
  static constexpr std::string_view value() {
    if constexpr (element.empty())
      return {};
    else
      return {chars.data(), length};
  }
};

template <class T>
inline constexpr bool declares_type_name = requires {
  { T::type_name } -> std::convertible_to<std::string_view>;
};
template <class T>
inline constexpr bool declares_layout_version = requires {
  T::layout_version;
};

}  // namespace detail

// T's registered name, or "" if T has none.
template <class T>
constexpr std::string_view stable_type_name() {
  if constexpr (std::is_arithmetic_v<T>) {
    return detail::arithmetic_name<T>();
  } else if constexpr (std::is_enum_v<T>) {
    if constexpr (requires { enum_type_name(T{}); })
      return enum_type_name(T{});
    else
      return {};
  } else if constexpr (is_std_array<T>::value) {
    return detail::ArrayName<typename T::value_type, std::tuple_size_v<T>>::value();
  } else if constexpr (detail::declares_type_name<T>) {
    static_assert(detail::declares_layout_version<T>,
                  "a type with a type_name crosses processes: declare its layout_version too");
    return T::type_name;
  } else {
    static_assert(!detail::declares_layout_version<T>,
                  "a type with a layout_version crosses processes: declare its type_name too "
                  "(static constexpr std::string_view type_name = \"ns::Type\";)");
    return {};
  }
}

// The name in messages, manifests and connect errors: the registered one, else the compiler's.
template <class T>
constexpr std::string_view type_name() {
  if constexpr (!stable_type_name<T>().empty())
    return stable_type_name<T>();
  else
    return compiler_type_name<T>();
}

// 0 for a type not registered for other processes.
template <class T>
constexpr std::uint32_t layout_version_of() {
  if constexpr (stable_type_name<T>().empty())
    return 0;
  else if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T>)
    return 1;
  else if constexpr (is_std_array<T>::value)
    return layout_version_of<typename T::value_type>();
  else
    return static_cast<std::uint32_t>(T::layout_version);
}

struct TypeInfo {
  std::string_view name;  // "" for "no value"
  std::size_t size = 0;
  std::uint32_t version = 0;  // layout version; 0: not registered for other processes
  // Whether bytes from outside the process are a valid value of this type (see value_check.hpp);
  // null for a type known only by name (a proxy's).
  bool (*check)(const std::byte* bytes, const Limits* limits) noexcept = nullptr;

  friend constexpr bool operator==(const TypeInfo& a, const TypeInfo& b) {
    return a.size == b.size && a.name == b.name && a.version == b.version;
  }
};

template <class T>
constexpr TypeInfo type_info_of() {
  return {type_name<T>(), sizeof(T), layout_version_of<T>(), &check_value_bytes<T>};
}

constexpr TypeInfo no_type{};

}  // namespace saw
