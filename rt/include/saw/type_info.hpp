// TypeInfo: a value type's name, size and layout version, compared when interfaces are bound.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>

namespace saw {

// Values that cross a mailbox, a state table or a process boundary are copied as bytes.
template <class T>
concept Plain =
    std::is_trivially_copyable_v<T> && std::is_standard_layout_v<T> && std::is_default_constructible_v<T>;

template <class T>
constexpr std::string_view type_name() {
  // The compiler spells T inside its own signature; this keeps only that part.
  constexpr std::string_view f = __PRETTY_FUNCTION__;
  constexpr std::string_view key = "T = ";
  constexpr auto start = f.find(key) + key.size();
  constexpr auto end = f.find_first_of(";]", start);
  return f.substr(start, end - start);
}

// A type that crosses a process boundary is registered by declaring its layout version:
//   struct Gains { static constexpr std::uint32_t layout_version = 1; double k_m, k_s; };
// and bumping it whenever a field changes. Processes built with different versions of a type
// then refuse to connect, naming both, instead of reading each other's bytes wrongly.
// Arithmetic and enum types are version 1; 0 means "not registered" (refused by the bridge).
template <class T>
struct is_std_array : std::false_type {};
template <class T, std::size_t N>
struct is_std_array<std::array<T, N>> : std::true_type {};

template <class T>
constexpr std::uint32_t layout_version_of() {
  if constexpr (std::is_arithmetic_v<T> || std::is_enum_v<T>)
    return 1;
  else if constexpr (is_std_array<T>::value)
    return layout_version_of<typename T::value_type>();
  else if constexpr (requires { T::layout_version; })
    return static_cast<std::uint32_t>(T::layout_version);
  else
    return 0;
}

struct TypeInfo {
  std::string_view name;  // "" for "no value"
  std::size_t size = 0;
  std::uint32_t version = 0;  // layout version; 0: not registered for other processes

  friend constexpr bool operator==(const TypeInfo& a, const TypeInfo& b) {
    return a.size == b.size && a.name == b.name && a.version == b.version;
  }
};

template <class T>
constexpr TypeInfo type_info_of() {
  return {type_name<T>(), sizeof(T), layout_version_of<T>()};
}

constexpr TypeInfo no_type{};

}  // namespace saw
