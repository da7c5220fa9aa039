// DvrkArm: a da Vinci Research Kit arm (an MTM or a PSM, dVRK 2.x) as a sawrt device; its hardware
// is the "dvrk" interface of the gateway's import of the arm's CRTK topics (no DDS in this process).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "saw/device.hpp"
#include "saw/functions.hpp"

namespace saw::drivers::dvrk {

// An MTM takes wrenches; a PSM and an ECM (the endoscope's arm, no jaw) follow poses.
enum class ArmKind : std::uint8_t { mtm, psm, ecm };
inline bool follows_poses(ArmKind k) noexcept { return k != ArmKind::mtm; }

// What reaches the arm when our commands stop (disable, a fault, the command watchdog, a stop):
// once, after the last motion command, and nothing after it (the dVRK keeps its last goal).
enum class SafeCommand : std::uint8_t {
  zero_wrench,        // MTM: servo_cf zero (gravity compensation keeps the handle floating)
  hold,               // PSM (or MTM): the dVRK's `hold`, at its current setpoint
  servo_cp_measured,  // PSM without `hold`: servo_cp at its last measured pose
};

struct DvrkArmConfig {
  ArmKind kind = ArmKind::mtm;
  SafeCommand safe_command = SafeCommand::zero_wrench;
  // The base's settings: max_force (N: MTM servo_cf above it is refused); command_timeout (no
  // servo command for this long: the safe command; 0: 3 periods); enable and home timeouts (the
  // dVRK powers an arm in a few s); start_enabled (real hardware: the operator enables); PSM
  // servo_cp: from the last accepted pose no faster than max_linear/angular_speed, in the workspace.
  DeviceSettings contract{.max_force = 3.0,
                          .start_enabled = false,
                          .enable_timeout = 10'000'000'000,
                          .home_timeout = 60'000'000'000,
                          .max_linear_speed = 0.2,
                          .max_angular_speed = 3.0};
  TimeNs stale_timeout = 50'000'000;  // measured_cp older than this while following: FAULT
  bool home = false;                  // send `home` to an arm that is not homed (it moves!)
  // PSM jaw_servo_jp: its angle (rad) within these, else refused (the dVRK's large needle
  // driver opens to about 80 degrees and closes a little past zero to grip).
  double jaw_min = -0.35, jaw_max = 1.4;
  // PSM servo_cp: the arm further than this (m) from the goal it was sent, for this long, does
  // not follow (a tool not past the cannula: the dVRK drops Cartesian commands with a warning
  // only) and is this device's FAULT. 0: not checked.
  double following_error = 0.01;
  TimeNs following_time = 200'000'000;
  // The arm's joints as its measured_js has them (an MTM's 7, a PSM's 6 without the jaw): with
  // them, measured_js is this device's (a sample of another size is refused) and move_jp goals
  // are checked against min/max. Empty: no joint space.
  std::vector<JointLimits> joints;
  bool servo_jp = false;  // also take servo_jp (needs joints; the base checks steps by max_velocity)
};

// What went to the arm, for the run's summary and a GUI.
struct DvrkSummary {
  static constexpr std::string_view type_name = "saw::dvrk::DvrkSummary";
  static constexpr std::uint32_t layout_version = 3;  // 2: jaw; 3: moves, joints
  std::uint64_t commands = 0;                         // motion commands sent (servo_cf, servo_cp)
  std::uint64_t safe_commands = 0;                    // safe commands sent
  std::uint64_t held_busy = 0;                        // motion commands held back while the arm was busy
  std::uint64_t not_sent = 0;                         // commands the import's queue did not take (full)
  std::uint64_t bad_poses = 0;         // measured_cp samples refused (not finite, not a rotation)
  std::uint64_t jaw_commands = 0;      // jaw_servo_jp sent
  std::uint64_t jaw_refused = 0;       // jaw_servo_jp refused (not one finite angle within the limits)
  std::uint64_t moves = 0;             // move_cp, move_jp and free sent
  std::uint64_t moves_refused = 0;     // refused (not finite, outside the limits, not driven, not allowed)
  std::uint64_t bad_joint_states = 0;  // measured_js samples refused (another size, not finite)
  std::uint64_t state_commands = 0;    // enable and home sent (again after 1 s without effect)
  OperatingState arm{};                // the dVRK's own operating state, as last read
  static constexpr auto fields =
      std::tuple{&DvrkSummary::commands,         &DvrkSummary::safe_commands,  &DvrkSummary::held_busy,
                 &DvrkSummary::not_sent,         &DvrkSummary::bad_poses,      &DvrkSummary::jaw_commands,
                 &DvrkSummary::jaw_refused,      &DvrkSummary::moves,          &DvrkSummary::moves_refused,
                 &DvrkSummary::bad_joint_states, &DvrkSummary::state_commands, &DvrkSummary::arm};
};

// Requires "dvrk" (the import: measured_cp, operating_state, state_command; servo_cf for an MTM,
// servo_cp for a PSM; measured_cv, hold, errors, and the gripper (MTM) or the jaw (PSM) when
// there; the console's clutch and operator_present, which become this device's events). Provides,
// besides the device's "arm": an MTM's gripper_measured_js; a PSM's
// jaw_measured_js and jaw_servo_jp (one finite angle within jaw_min/max, else refused and
// counted; sent with the cycle's pose, only while the arm is driven, never while it is busy); the
// arm's measured_cf where the import has it (a finite wrench); with `joints`, measured_js (checked)
// and servo_jp when `servo_jp`. move_cp and move_jp (the dVRK plans the trajectory: alignment
// before following), and an MTM's `free`: checked when given (finite, a unit quaternion, in the
// workspace; every joint within its limits), sent in the next cycle only while the arm is driven
// and no servo command is given in it (refused and counted otherwise). A move ends the client's
// servo commands (the last one is not sent again, their silence trips no watchdog, no hold cuts
// the move): a client stops streaming and moves the arm (the surgical law aligning an MTM).
// Servo commands are held back while
// the move makes the arm busy (this device is busy then too: a client waits for it), and every
// stop path after a move sends the safe command, which stops a move still under way. Enabling walks
// the dVRK's handshake: `enable` sent (again after 1 s idle without effect: one lost) and ENABLED awaited; a
// not-homed arm homed (`home: true`, only once ENABLED) or refused; no motion command reaches the arm before
// it is ENABLED, homed and not busy, nor while it is busy. Following, an arm that leaves ENABLED, loses its
// homing, stops publishing (stale_timeout), reports an error (the import's `errors` grows), does not follow a
// PSM's servo_cp goals (following_error for following_time) or whose import is gone is this device's FAULT,
// naming which.
class DvrkArm final : public Device {
 public:
  DvrkArm(std::string name, TaskConfig task, DvrkArmConfig config);

  const DvrkArmConfig& arm_config() const noexcept { return arm_config_; }
  const DvrkSummary& summary() const noexcept { return summary_; }

 protected:
  void open() override;
  Outcome read() override;
  Outcome write(const Setpoint& s) override;
  Outcome enable() override;
  Outcome home() override;
  void enter_safe_state(SafeReason why) override;
  bool accepts(ServoMode m) const noexcept override;

 private:
  DvrkArm(std::string name, TaskConfig task, Checked<DvrkArmConfig> config);
  Outcome send_state(StateCommand c, bool& sent, const char* why) noexcept;
  void on_jaw(const JointState& j) noexcept;
  Status send_safe() noexcept;
  void on_move_cp(const Pose& p) noexcept;
  void on_move_jp(const JointState& j) noexcept;
  void on_free() noexcept;
  Outcome send_request() noexcept;
  Outcome check_following() noexcept;
  void read_joints() noexcept;

  DvrkArmConfig arm_config_;
  FunctionRead<Pose> read_cp_;
  FunctionRead<Twist> read_cv_;
  FunctionRead<OperatingState> read_state_;
  FunctionRead<std::uint64_t> read_errors_;  // the import's count of the arm's error messages
  std::uint64_t errors_before_ = 0;          // the count when the arm was last not driven
  FunctionWrite<Wrench> write_cf_;
  FunctionWrite<Pose> write_cp_;
  FunctionWrite<StateCommand> write_state_;
  FunctionVoid hold_;
  FunctionRead<JointState> read_jaw_;  // the gripper (MTM) or the jaw (PSM)
  FunctionWrite<JointState> write_jaw_;
  FunctionRead<Wrench> read_cf_;
  Wrench cf_{};  // the arm's measured_cf, the last finite one
  FunctionRead<JointState> read_js_;
  FunctionWrite<JointState> write_jp_, move_jp_;
  FunctionWrite<Pose> move_cp_;
  FunctionVoid free_;
  // One request of a client that the arm carries out by itself: checked when given, sent by the
  // next write() (the hardware is written there only).
  struct Request {
    enum class Kind : std::uint8_t { none, move_cp, move_jp, free } kind = Kind::none;
    Pose pose{};
    JointState joints{};
  };
  Request request_{};
  bool moved_ = false;             // a move of ours is under way at the arm: a stop sends the safe command
  TimeNs moved_at_ = 0;            // when it went out
  bool move_seen_busy_ = false;    // the arm has shown it busy since
  JointState jaw_{}, jaw_goal_{};  // the last good gripper/jaw sample; the last accepted jaw goal
  bool jaw_pending_ = false;
  DvrkSummary summary_{};
  bool have_state_ = false;
  TimeNs cp_time_ = -1;  // the newest measured_cp's row time (its arrival at the import)
  bool enable_sent_ = false, home_sent_ = false;
  TimeNs state_sent_at_ = 0;
  bool commanded_ = false;  // a motion command went out since the last safe command
  Vec3 goal_sent_{};        // the last servo_cp goal that went out
  bool goal_live_ = false;  // it went out in the last cycle
  TimeNs far_since_ = -1;   // since when the arm has been further than following_error from it
  int not_sent_in_a_row_ = 0;
};

}  // namespace saw::drivers::dvrk
