// lab::SpringParams: a lab's own value type, sent and read over DDS as lab_msgs/msg/SpringParams.
#pragma once

#include <cstdint>
#include <string_view>
#include <tuple>

namespace lab {

// Registered for other processes (its name and layout version), and its `fields`, every member
// in the order of its IDL (idl/lab_msgs/msg/SpringParams.idl): the bridge checks them, and the
// gateway carries them to and from the message without a conversion written by hand.
struct SpringParams {
  static constexpr std::string_view type_name = "lab::SpringParams";
  static constexpr std::uint32_t layout_version = 1;
  double stiffness = 100;  // N/m
  double max_force = 2;    // N
  static constexpr auto fields = std::tuple{&SpringParams::stiffness, &SpringParams::max_force};
};

}  // namespace lab
