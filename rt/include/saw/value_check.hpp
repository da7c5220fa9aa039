// Value checks: what a value's bytes must satisfy before code that trusts its type may use them.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <tuple>
#include <type_traits>

namespace saw {

// Bounds a component declares for every number in a write command's argument (Pose: its
// position and orientation alike; an integer argument too, but not a struct's integer members,
// which are counts). Enforced where values enter from another process (the
// bridge's exporter, the DDS gateway); the component still validates what it receives.
struct Limits {
  double min = 0, max = 0;
};

// A value's bytes may come from another process: a bool must be 0 or 1, an enum one of its
// enumerators, a floating-point number finite (and within `limits` when given). A type tells
// the check about itself with
//   static constexpr auto fields = std::tuple{&T::a, &T::b};   // every member, checked in turn
//   static bool valid(const T& v) noexcept;                    // invariants across members
// and an enum with `constexpr std::size_t enum_count(E) { return N; }` (found by ADL) for
// enumerators 0..N-1. A class type without `fields` is opaque: only its size is checked.
// No allocation, lock or exception: the bridge runs this in the RT thread.
template <class T>
bool check_value_bytes(const std::byte* bytes, const Limits* limits) noexcept;

template <class T>
bool check_value(const T& value, const Limits* limits = nullptr) noexcept {
  return check_value_bytes<T>(reinterpret_cast<const std::byte*>(&value), limits);
}

namespace detail {

template <class T>
struct is_array : std::false_type {};
template <class T, std::size_t N>
struct is_array<std::array<T, N>> : std::true_type {};

template <class T, class M>
std::size_t member_offset(M T::*member) noexcept {
  const T probe{};  // Plain types are trivially copyable and default-constructible
  return static_cast<std::size_t>(reinterpret_cast<const std::byte*>(&(probe.*member)) -
                                  reinterpret_cast<const std::byte*>(&probe));
}

// A struct's integer members are counts and indices (a JointState's size), not quantities: its
// limits bound its floating-point numbers only; an integer value itself is bounded.
template <class T, class M>
bool check_member(const std::byte* bytes, M T::*member, const Limits* limits) noexcept {
  return check_value_bytes<M>(bytes + member_offset(member), std::is_integral_v<M> ? nullptr : limits);
}

}  // namespace detail

template <class T>
bool check_value_bytes(const std::byte* bytes, const Limits* limits) noexcept {
  if constexpr (std::is_same_v<T, bool>) {
    return std::to_integer<unsigned>(bytes[0]) <= 1U;  // read as a byte: any other is not a bool
  } else if constexpr (std::is_floating_point_v<T>) {
    T v;
    std::memcpy(&v, bytes, sizeof v);
    if (!std::isfinite(v)) return false;
    return limits == nullptr || (v >= limits->min && v <= limits->max);
  } else if constexpr (std::is_integral_v<T>) {
    if (limits == nullptr) return true;
    T v;
    std::memcpy(&v, bytes, sizeof v);
    const auto x = static_cast<double>(v);
    return x >= limits->min && x <= limits->max;
  } else if constexpr (std::is_enum_v<T>) {
    if constexpr (requires { enum_count(T{}); }) {
      std::underlying_type_t<T> u;
      std::memcpy(&u, bytes, sizeof u);
      return u >= 0 && static_cast<std::size_t>(u) < enum_count(T{});
    } else {
      return true;
    }
  } else if constexpr (detail::is_array<T>::value) {
    using E = typename T::value_type;
    for (std::size_t i = 0; i < std::tuple_size_v<T>; ++i)
      if (!check_value_bytes<E>(bytes + i * sizeof(E), limits)) return false;
    return true;
  } else if constexpr (requires { T::fields; }) {
    const bool members = std::apply(
        [&](auto... member) { return (detail::check_member(bytes, member, limits) && ...); }, T::fields);
    if (!members) return false;
    if constexpr (requires(const T& v) { T::valid(v); }) {
      T v;  // every member holds a valid value now: safe to look at it as a T
      std::memcpy(&v, bytes, sizeof v);
      return T::valid(v);
    }
    return true;
  } else {
    return true;
  }
}

}  // namespace saw
