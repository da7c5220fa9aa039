// ImportedArm: a foreign CRTK arm on DDS (a dVRK arm) presented as a local provided interface (internal).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dds_context.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/task.hpp"

namespace saw::gateway {

// Read-only (as the paper's research API was), the provided "arm" (crtk_arm.hpp): measured_cp,
// measured_cv, measured_js, measured_cf (where published: an MTM's body/measured_cf),
// gripper_measured_js (an MTM's), jaw_measured_js (a PSM's),
// operating_state (reads); operating_state, clutch, operator_present (events).
// Read-write (ImportConfig::commands), the provided "dvrk" for one client, a dvrk_arm device in
// saw-rt: the same reads and `errors` (how many error messages the arm sent; each, and each
// warning, printed), and state_command, servo_cf (the arm's body/servo_cf), servo_cp, servo_jp,
// jaw_servo_jp (jaw/servo_jp), move_cp, move_jp, hold, free
// forwarded to reliable writers as the dVRK's subscriptions require. The device keeps the
// contract; the import keeps what a process must do for a client that can no longer: the safe
// command when the client falls silent while moving the arm, and on the gateway's exit (its
// SIGTERM, or saw-rt's death through PDEATHSIG), acknowledged by the arm before the exit goes on.
// A 1 ms task of normal priority takes the newest samples; its state row is stamped with the
// arrival of the newest measured_cp, so a client sees the stream age when it stops. Samples that
// are not valid values (NaN, bad quaternion) are counted and dropped.
class ImportedArm : public Task {
 public:
  ImportedArm(DdsContext& dds, const ImportConfig& config);
  void run() override;
  // "arm", or "dvrk" when it sends commands: the one interface exported through the bridge.
  const std::string& interface_name() const noexcept { return interface_; }
  std::uint64_t samples() const noexcept { return samples_.load(std::memory_order_relaxed); }
  std::uint64_t rejected() const noexcept { return rejected_.load(std::memory_order_relaxed); }
  // measured_cp samples not taken for their header stamp: 0 (the dVRK's invalid data), or not
  // newer than the last one's.
  std::uint64_t invalid_stamps() const noexcept { return invalid_stamps_.load(std::memory_order_relaxed); }
  std::uint64_t repeated_stamps() const noexcept { return repeated_stamps_.load(std::memory_order_relaxed); }
  // Commands written to the arm, and safe commands the import sent of itself (silence, exit).
  std::uint64_t commands_sent() const noexcept { return sent_.load(std::memory_order_relaxed); }
  std::uint64_t safe_commands() const noexcept { return safe_sent_.load(std::memory_order_relaxed); }
  // For the manifest: each imported value ("import") and command ("import_command"), its topic.
  const std::vector<EndpointInfo>& endpoints() const noexcept { return endpoints_; }
  // The exit path, once the task has stopped: the safe command if a motion command was the last
  // one sent, then waits (until `deadline`) for the arm to acknowledge it.
  void leave_safely(TimeNs deadline);

 private:
  struct Writer {
    fdds::DataWriter* writer = nullptr;
    const Mapping* mapping = nullptr;
  };
  fdds::DataReader* reader(const std::string& name, const std::string& topic, const Mapping& m, Flow f);
  template <class M>
  fdds::DataReader* reader(M member, const std::string& topic, Flow f);
  Writer writer(const std::string& name, const std::string& topic, const Mapping& m);
  // The manifest's row for an imported value ("import") or command ("import_command").
  void add_endpoint(const std::string& name, const std::string& topic, const Mapping& m, const char* kind);
  template <class T>
  bool take_newest(fdds::DataReader* r, T& out);
  bool take_cp();
  fdds::DataReader* text_reader(const std::string& topic);
  void take_text(fdds::DataReader* r, const char* kind, bool is_error);
  void provide_commands(ProvidedInterface& p, const std::string& prefix);
  static bool matched(const Writer& w);
  bool send(const Writer& w, const void* value);
  // motion: a servo stream (its silence is the client's death); move: a trajectory the arm plans.
  void command(const Writer& w, const void* value, bool motion, bool move = false);
  // Waits (until `deadline`) for the arm to acknowledge what `w` sent; false if it did not.
  static bool acknowledged(const Writer& w, TimeNs deadline);
  // Every motion command acknowledged (bounded) before a safe command on another topic.
  void settle_motion(TimeNs deadline);
  bool send_safe_command();
  void watch_client();

  DdsContext& dds_;
  ImportConfig config_;
  std::string interface_;
  fdds::DataReader *cp_ = nullptr, *cv_ = nullptr, *js_ = nullptr, *cf_ = nullptr, *state_ = nullptr,
                   *clutch_ = nullptr, *operator_ = nullptr, *gripper_ = nullptr, *jaw_ = nullptr;
  Writer state_command_, servo_cf_, servo_cp_, servo_jp_, jaw_servo_jp_, move_cp_, move_jp_, hold_, free_,
      gravity_;
  fdds::DataReader *error_ = nullptr, *warning_ = nullptr;
  std::uint64_t errors_ = 0;  // error messages of the arm (a state column: "errors")
  bool gravity_sent_ = false;
  Pose measured_cp_;
  bool has_cp_ = false;
  Twist measured_cv_;
  Wrench measured_cf_;
  JointState measured_js_, gripper_js_, jaw_js_;
  OperatingState operating_state_;
  TimeNs cp_arrival_ = 0;
  // The client's last state command while the arm's subscription was not matched yet: a
  // volatile reader never sees what was written before it matched, and the dVRK's is one.
  std::optional<StateCommand> pending_state_command_;
  // A motion command was the last one sent (the safe command is owed if the client goes).
  bool moving_ = false;
  bool move_sent_ = false;  // a move was the last command sent: stopped on exit if under way
  TimeNs last_command_ = 0;
  int cycles_since_command_ = 0;
  EventWrite<OperatingState>* state_event_ = nullptr;
  EventWrite<ButtonEvent>*clutch_event_ = nullptr, *operator_event_ = nullptr;
  std::atomic<std::uint64_t> samples_{0}, rejected_{0}, sent_{0}, safe_sent_{0}, invalid_stamps_{0},
      repeated_stamps_{0};
  std::int64_t last_cp_stamp_ = 0;
  std::vector<EndpointInfo> endpoints_;
};

}  // namespace saw::gateway
