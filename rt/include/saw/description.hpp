// ComponentDescription: what a component is, and which components play its roles, for clients.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace saw {

// One setting a component declares (a control law's gain, scale, limits): read back as the read
// command `name`, written with `set_<name>` when `command`.
struct DeclaredSetting {
  std::array<char, 32> name{};
  std::array<char, 24> unit{};  // "" for a ratio, a flag
  double min = 0, max = 0;      // every number of the value; ±infinity: any finite number
  std::uint32_t count = 0;      // numbers in the value: 1 (a number, a flag), 2 (master, slave), 3 (x, y, z)
  bool command = false;
};

// Exported as the read command `description`, so that a client (a GUI, sawctl) finds a
// component by what it says it is rather than by its command names: e.g. kind "teleoperation",
// variant "collaborative" (its law), roles "master" and "slave" with the components connected
// to each, and the settings it declares. Fixed-size, NUL-terminated text (set() truncates;
// unused roles are empty, settings beyond `setting_count` unused).
struct ComponentDescription {
  static constexpr std::string_view type_name = "saw::ComponentDescription";
  static constexpr std::uint32_t layout_version = 2;  // 2: settings
  static constexpr std::size_t max_roles = 4;
  static constexpr std::size_t max_settings = 12;
  std::array<char, 32> kind{};
  std::array<char, 32> variant{};
  std::array<std::array<char, 16>, max_roles> roles{};
  std::array<std::array<char, 64>, max_roles> servers{};  // "component.interface", "" until connected
  std::uint32_t setting_count = 0;
  std::array<DeclaredSetting, max_settings> settings{};

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
