// The CRTK arm interface: its commands and events, each a name with its value type, declared once.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <utility>

#include "saw/command_kind.hpp"
#include "saw/crtk.hpp"
#include "saw/functions.hpp"
#include "saw/provided_interface.hpp"
#include "saw/required_interface.hpp"

namespace saw::crtk {

// A member of an interface, as a name and a value type together: a device provides it and a
// client requires it through the same constant (provide() and require() below), so the two
// cannot spell the name differently, and a function or column of another type does not compile.
template <Plain T>
struct Read {
  using value_type = T;
  std::string_view name;
};
template <Plain T>
struct Write {
  using value_type = T;
  std::string_view name;
};
template <Plain T>
struct Event {
  using value_type = T;
  std::string_view name;
};

// The same, erased: for tables that list an interface (the gateway, tests).
struct Member {
  std::string_view name;
  Signature signature;
};
template <class T>
constexpr Member member(Read<T> m) {
  return {m.name, {CommandKind::read, type_info_of<T>()}};
}
template <class T>
constexpr Member member(Write<T> m) {
  return {m.name, {CommandKind::write, type_info_of<T>()}};
}
template <class T>
constexpr Member member(Event<T> m) {
  return {m.name, {CommandKind::write_event, type_info_of<T>()}};
}

// A device's side: a read served from a state-table column, a write command run in the
// device's thread, an event it emits.
template <Plain T>
void provide(ProvidedInterface& p, Read<T> m, StateColumn<T> column) {
  p.add_command_read(std::string(m.name), column);
}
// The same with a new column of the same name, copied from *source every cycle.
template <Plain T>
StateColumn<T> provide(ProvidedInterface& p, Read<T> m, StateTable& table, const T* source) {
  const StateColumn<T> column = table.add_column(std::string(m.name), source);
  p.add_command_read(std::string(m.name), column);
  return column;
}
template <Plain T, class F>
void provide(ProvidedInterface& p, Write<T> m, F&& on_command) {
  p.add_command_write<T>(std::string(m.name), std::forward<F>(on_command));
}
template <Plain T>
EventWrite<T>& provide(ProvidedInterface& p, Event<T> m) {
  return p.add_event_write<T>(std::string(m.name));
}

// A client's side.
template <Plain T>
void require(RequiredInterface& r, Read<T> m, FunctionRead<T>& f, Need need = Need::required) {
  r.add_function(std::string(m.name), f, need);
}
template <Plain T>
void require(RequiredInterface& r, Write<T> m, FunctionWrite<T>& f, Need need = Need::required) {
  r.add_function(std::string(m.name), f, need);
}
template <Plain T, class F>
void require(RequiredInterface& r, Event<T> m, F&& handler, Need need = Need::required) {
  r.add_event_handler_write<T>(std::string(m.name), std::forward<F>(handler), need);
}

// The state machine of every CRTK component (an arm, the teleoperation task). CRTK has a read
// and an event both named operating_state: commands and events are separate namespaces.
inline constexpr Read<OperatingState> operating_state{"operating_state"};
inline constexpr Write<StateCommand> state_command{"state_command"};
inline constexpr Event<OperatingState> operating_state_event{"operating_state"};

// The arm, as sawrt's devices provide it and its clients (the teleoperation task, the gateway)
// use it.
namespace arm {

inline constexpr std::string_view interface_name = "arm";  // what devices call the interface

inline constexpr Read<Pose> measured_cp{"measured_cp"};
inline constexpr Read<Twist> measured_cv{"measured_cv"};
inline constexpr Read<JointState> measured_js{"measured_js"};  // with the joints' names
using crtk::operating_state;
inline constexpr Write<Wrench> servo_cf{"servo_cf"};
inline constexpr Write<Pose> servo_cp{"servo_cp"};  // a device with DeviceConfig::servo_cp
// CRTK's joint-space servo commands and the setpoint they became.
inline constexpr Read<JointState> setpoint_js{"setpoint_js"};
inline constexpr Write<JointState> servo_jp{"servo_jp"};  // positions
inline constexpr Write<JointState> servo_jv{"servo_jv"};  // velocities
inline constexpr Write<JointState> servo_jf{"servo_jf"};  // efforts: N·m or N
// CRTK's move commands: a goal the arm reaches along a trajectory it plans itself (busy until
// there), as a dVRK arm aligns before teleoperation.
inline constexpr Write<Pose> move_cp{"move_cp"};
inline constexpr Write<JointState> move_jp{"move_jp"};
// The wrench the arm measures or estimates at its tip, where it publishes one (a dVRK MTM's
// body/measured_cf).
inline constexpr Read<Wrench> measured_cf{"measured_cf"};
using crtk::operating_state_event;
using crtk::state_command;
inline constexpr Event<ButtonEvent> clutch{"clutch"};                      // a foot pedal
inline constexpr Event<ButtonEvent> operator_present{"operator_present"};  // the head sensor
// A surgical instrument's jaw (a dVRK PSM's jaw/measured_js and jaw/servo_jp) and the master's
// gripper that commands it (a dVRK MTM's gripper/measured_js): one joint, rad. Not every arm's.
inline constexpr Read<JointState> jaw_measured_js{"jaw_measured_js"};
inline constexpr Write<JointState> jaw_servo_jp{"jaw_servo_jp"};
inline constexpr Read<JointState> gripper_measured_js{"gripper_measured_js"};

inline constexpr std::array members{
    member(measured_cp), member(measured_cv),      member(measured_js),   member(operating_state),
    member(servo_cf),    member(servo_cp),         member(state_command), member(operating_state_event),
    member(clutch),      member(operator_present),
};

}  // namespace arm

}  // namespace saw::crtk
