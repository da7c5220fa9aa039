// ComponentDescription: what a component is, and which components play its roles, for clients.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace saw {

// Exported as the read command `description`, so that a client (a GUI, sawctl) finds a
// component by what it says it is rather than by its command names: e.g. kind "teleoperation",
// variant "collaborative" (its law), roles "master" and "slave" with the components connected
// to each. Fixed-size, NUL-terminated text (set() truncates; unused roles are empty).
struct ComponentDescription {
  static constexpr std::string_view type_name = "saw::ComponentDescription";
  static constexpr std::uint32_t layout_version = 1;
  static constexpr std::size_t max_roles = 4;
  std::array<char, 32> kind{};
  std::array<char, 32> variant{};
  std::array<std::array<char, 16>, max_roles> roles{};
  std::array<std::array<char, 64>, max_roles> servers{};  // "component.interface", "" until connected

  template <std::size_t N>
  static void set(std::array<char, N>& field, std::string_view text) noexcept {
    const std::size_t n = text.size() < N - 1 ? text.size() : N - 1;
    for (std::size_t i = 0; i < N; ++i) field[i] = i < n ? text[i] : '\0';
  }
  template <std::size_t N>
  static std::string_view get(const std::array<char, N>& field) noexcept {
    std::size_t n = 0;
    while (n < N && field[n] != '\0') ++n;
    return {field.data(), n};
  }
};

}  // namespace saw
