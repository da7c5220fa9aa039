// CollaborativeLaw: the paper's collaborative force law, with its ratchet and Euler prediction.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <tuple>

#include "saw/crtk.hpp"
#include "saw/teleop/law.hpp"
#include "saw/teleop/law_setting.hpp"
#include "saw/teleop/offset_trajectory.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

// The local model predicts only the inputs that arrive late: a side's horizon is the delay of
// the link its positions come over (0 for a device beside this task).
struct Prediction {
  static constexpr std::string_view type_name = "saw::teleop::Prediction";
  static constexpr std::uint32_t layout_version = 1;
  bool enabled = false;
  double master_horizon = 0.0;  // s
  double slave_horizon = 0.0;   // s
  static constexpr auto fields =
      std::tuple{&Prediction::enabled, &Prediction::master_horizon, &Prediction::slave_horizon};
  // Each horizon within [0, max_horizon] (false for NaN): what the setting's bounds say.
  static constexpr std::string_view range = "each horizon within [0, 1] s";
  static bool valid(const Prediction& v) noexcept {
    return v.master_horizon >= 0 && v.master_horizon <= max_horizon && v.slave_horizon >= 0 &&
           v.slave_horizon <= max_horizon;
  }
};
// Crosses processes byte for byte (set_prediction; saw_msgs/Prediction over DDS).
static_assert(max_horizon == 1.0, "Prediction::range says 1 s");
static_assert(sizeof(Prediction) == 24 && offsetof(Prediction, master_horizon) == 8 &&
              offsetof(Prediction, slave_horizon) == 16);

// {enabled, master, slave}: the horizons within the setting's bounds, in seconds ("20ms" too).
template <>
struct SettingCodec<Prediction> {
  static constexpr std::string_view shape = "{enabled, master, slave}";
  static constexpr std::uint32_t count = 3;
  static constexpr bool declares_limits = false;  // a bool beside the horizons
  static bool within(const Prediction& v, double lo, double hi) noexcept {
    return SettingCodec<double>::within(v.master_horizon, lo, hi) &&
           SettingCodec<double>::within(v.slave_horizon, lo, hi);
  }
  static Prediction parse(const deploy::Params& p, const std::string& key, double lo, double hi,
                          const Prediction& fallback);
  static std::string text(const Prediction& v);
};

// {velocity, acceleration, jerk}, each bounded on its own (the setting's bounds are the widest).
template <>
struct SettingCodec<OffsetLimits> {
  static constexpr std::string_view shape = "{velocity, acceleration, jerk}";
  static constexpr std::uint32_t count = 3;
  static constexpr bool declares_limits = false;
  static constexpr double min = OffsetLimits::smallest, max_velocity = OffsetLimits::max_velocity,
                          max_acceleration = OffsetLimits::max_acceleration,
                          max_jerk = OffsetLimits::max_jerk;
  static bool within(const OffsetLimits& v, double, double) noexcept { return OffsetLimits::valid(v); }
  static OffsetLimits parse(const deploy::Params& p, const std::string& key, double lo, double hi,
                            const OffsetLimits& fallback);
  static std::string text(const OffsetLimits& v);
};

struct CollaborativeSettings {
  double scale = 1.0;  // the slave moves `scale` times the master
  Vec3 mirror{1, 1, 1};
  Gains gains;
  ForceLimits limits;
  bool ratchet = true;
  OffsetLimits offset_limits;
  Prediction prediction;
  // Aligned mode: after enabling, the slave offset travels (jerk-limited) from the value that
  // cancels the error to `slave_offset`, pulling the slave smoothly into the configured pose.
  bool align = false;
  Vec3 slave_offset{};
};

// With d = p + o: e_m = d_m − S·d_s, e_s = d_s − S⁻¹·d_m, f = −k·e saturated (teleop_law.hpp).
// The slave offset snaps to the value cancelling the error while held and on engaging, travels
// along a jerk-limited trajectory otherwise (ratchet, alignment), and is re-expressed when the
// scale or the prediction changes so that e_s does not jump (docs/architecture.md).
class CollaborativeLaw {
 public:
  using Settings = CollaborativeSettings;
  static constexpr std::string_view name = "collaborative";
  static constexpr std::string_view description =
      "the paper's collaborative force law: each side pulled toward the other, saturated, with ratchet "
      "and Euler prediction";
  static bool unit_mirror(const Vec3& m) noexcept;
  static constexpr auto declared_settings = std::tuple{
      Setting<Settings, double>{"scale", "", min_scale, max_scale, &Settings::scale,
                                "slave displacement per master displacement"},
      Setting<Settings, Vec3>{"mirror", "", -unbounded, unbounded, &Settings::mirror,
                              "per axis, 1 or −1: axes that flip between the devices", false, &unit_mirror,
                              "each entry must be 1 or -1"},
      Setting<Settings, Gains>{"gains", "N/m", 0, max_gain, &Settings::gains, "stiffness k_m, k_s"},
      Setting<Settings, ForceLimits>{"force_limits", "N", 0, max_force_limit, &Settings::limits,
                                     "force magnitude limits lim_m, lim_s"},
      Setting<Settings, bool>{"ratchet", "", 0, 1, &Settings::ratchet,
                              "at a force limit the slave offset slips instead of the force growing", false},
      Setting<Settings, OffsetLimits>{"offset_limits", "m/s, m/s², m/s³", SettingCodec<OffsetLimits>::min,
                                      SettingCodec<OffsetLimits>::max_jerk, &Settings::offset_limits,
                                      "the offset trajectory's limits (velocity ≤ 10, acceleration ≤ 1e3)"},
      Setting<Settings, Prediction>{"prediction", "s", 0, max_horizon, &Settings::prediction,
                                    "Euler prediction over each side's horizon (eq. 7)"},
      Setting<Settings, bool>{"align", "", 0, 1, &Settings::align,
                              "after enabling, carry the slave offset to `slave_offset`", false},
      Setting<Settings, Vec3>{"slave_offset", "m", -unbounded, unbounded, &Settings::slave_offset,
                              "the slave offset to align to (set_slave_offset turns align on)"},
  };

  CollaborativeLaw(const Settings& s, const LawContext& ctx);

  Settings& settings() noexcept { return s_; }
  void reset(const LawInputs& in) noexcept;
  void hold(const LawInputs& in) noexcept;
  LawCommand step(const LawInputs& in) noexcept;
  void on_set(std::string_view setting, const Settings& before) noexcept;
  // Offset trajectories Ruckig refused (the offset then stays where it is, at rest).
  std::uint64_t refusals() const noexcept { return offset_.errors(); }
  int last_refusal() const noexcept { return offset_.last_error(); }

 private:
  // What the offset is expressed in: a change re-expresses it so that e_s does not jump.
  struct Frame {
    Scale scale;
    Prediction prediction;
  };
  Frame frame() const noexcept { return {{s_.scale, s_.mirror}, s_.prediction}; }
  Eigen::Vector3d predict(const SideSample& in, double horizon, const Prediction& pr) const noexcept;
  void snap(const LawInputs& in) noexcept;
  void reexpress(const LawInputs& in) noexcept;
  bool ratchet(const Eigen::Vector3d& p_m, const Eigen::Vector3d& p_s) noexcept;

  Settings s_;
  double dt_;
  OffsetTrajectory offset_;
  Eigen::Vector3d master_offset_ = Eigen::Vector3d::Zero();
  bool reexpress_pending_ = false;
  Frame previous_;
};

}  // namespace saw::teleop
