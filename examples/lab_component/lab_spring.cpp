// lab_spring: a virtual spring rendered on a haptic device — an example of a lab's component,
// built outside the sawrt tree and deployed beside sawrt's own components as a plug-in.
//
// Required "arm" (CRTK): measured_cp, servo_cf. Provided "spring": set_stiffness (write),
// force (read). Its "summary" column is printed by saw-rt when the run ends.
#include <cmath>
#include <memory>
#include <saw/crtk.hpp>
#include <saw/deploy/plugin.hpp>
#include <saw/functions.hpp>
#include <saw/task.hpp>

namespace lab {

struct SpringConfig {
  saw::TaskConfig task;
  double stiffness = 100;  // N/m
  double max_force = 2;    // N: the force is clipped to this norm
  bool anchor_given = false;
  saw::Vec3 anchor{};  // m; default: where the device is at the first good read
};

// What a run comes to; a state-table column like any other, marked for the summary.
struct SpringSummary {
  static constexpr std::string_view type_name = "lab::SpringSummary";
  static constexpr std::uint32_t layout_version = 1;
  std::uint64_t cycles = 0, failed_reads = 0, rejected_settings = 0;
  double max_force = 0;  // N, the largest force sent
};

class VirtualSpring : public saw::Task {
 public:
  VirtualSpring(std::string name, const SpringConfig& c) : Task(std::move(name), c.task), config_(c) {
    auto& arm = require("arm");
    arm.add_function("measured_cp", measured_cp_);
    arm.add_function("servo_cf", servo_cf_);
    auto& spring = provide("spring");
    spring.add_command_write<double>("set_stiffness", [this](const double& k) {
      // A command may come from another process: checked here, whatever the caller checked.
      if (std::isfinite(k) && k >= 0 && k <= 5000)
        config_.stiffness = k;
      else
        ++summary_.rejected_settings;
    });
    spring.limit("set_stiffness", 0, 5000);
    spring.add_command_read("force", state_table().add_column("force", &force_));
    state_table().add_column("summary", &summary_, saw::ColumnUse::summary);
  }

  // RT path: no allocation, no lock, no exception.
  void run() override {
    ++summary_.cycles;
    saw::Pose p;
    if (measured_cp_(p) != saw::Status::ok) {
      ++summary_.failed_reads;
      force_ = {};
      (void)servo_cf_(saw::Wrench{});  // no position, no push
      return;
    }
    if (!config_.anchor_given) {
      config_.anchor = p.position;
      config_.anchor_given = true;
    }
    double norm2 = 0;
    for (int i = 0; i < 3; ++i) {
      force_[i] = -config_.stiffness * (p.position[i] - config_.anchor[i]);
      norm2 += force_[i] * force_[i];
    }
    const double norm = std::sqrt(norm2);
    if (norm > config_.max_force)
      for (double& f : force_) f *= config_.max_force / norm;
    summary_.max_force = std::max(summary_.max_force, std::min(norm, config_.max_force));
    saw::Wrench w;
    w.force = force_;
    (void)servo_cf_(w);
  }

 private:
  SpringConfig config_;
  saw::FunctionRead<saw::Pose> measured_cp_;
  saw::FunctionWrite<saw::Wrench> servo_cf_;
  saw::Vec3 force_{};
  SpringSummary summary_{};
};

// The parameters, read and range-checked next to the config they fill: a bad value is a
// file:line error before anything starts.
SpringConfig parse(const saw::deploy::ComponentContext& ctx, saw::deploy::Params& p) {
  SpringConfig c;
  c.task = saw::deploy::periodic_task(ctx, p, "lab_spring");
  c.stiffness = p.get_in_range("stiffness", 0, 5000, c.stiffness);
  c.max_force = p.get_in_range("max_force", 0, 10, c.max_force);
  c.anchor_given = p.has("anchor");
  c.anchor = p.get_or<saw::Vec3>("anchor", {0, 0, 0});
  return c;
}

void register_components(saw::deploy::ComponentRegistry& registry) {
  registry.add("lab_spring", "example lab component: a virtual spring on a haptic device", parse,
               [](const std::string& name, const SpringConfig& c) {
                 return std::make_unique<VirtualSpring>(name, c);
               });
  registry.add_summary_format<SpringSummary>([](const SpringSummary& s) {
    return std::to_string(s.cycles) + " cycles, largest force " + std::to_string(s.max_force) +
           " N, " + std::to_string(s.failed_reads) + " failed reads, " + std::to_string(s.rejected_settings) +
           " settings refused";
  });
}

}  // namespace lab

SAW_PLUGIN(lab::register_components)
