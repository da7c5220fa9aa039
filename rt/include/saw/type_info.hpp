// TypeInfo: a value type's readable name and size, compared when interfaces are bound.
#pragma once

#include <cstddef>
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

struct TypeInfo {
  std::string_view name;  // "" for "no value"
  std::size_t size = 0;

  friend constexpr bool operator==(const TypeInfo& a, const TypeInfo& b) {
    return a.size == b.size && a.name == b.name;
  }
};

template <class T>
constexpr TypeInfo type_info_of() {
  return {type_name<T>(), sizeof(T)};
}

constexpr TypeInfo no_type{};

}  // namespace saw
