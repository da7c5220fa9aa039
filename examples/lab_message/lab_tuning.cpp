// lab_tuning: a component whose setting is a lab's own type (lab::SpringParams) — the example of
// adding a message type: it is written with `set_spring` and read back as `spring`, over the
// bridge and, through the lab's mapping module, over DDS.
#include <cmath>
#include <memory>
#include <saw/deploy/plugin.hpp>
#include <saw/task.hpp>

#include "spring_params.hpp"

namespace lab {

class Tuning : public saw::Task {
 public:
  Tuning(std::string name, saw::TaskConfig task, const SpringParams& initial)
      : Task(std::move(name), task), spring_(initial) {
    auto& p = provide("tuning");
    p.add_command_write<SpringParams>("set_spring", [this](const SpringParams& s) {
      // A command may come from another process: checked here, whatever the caller checked.
      if (valid(s))
        spring_ = s;
      else
        ++refused_;
    });
    p.limit("set_spring", 0, 5000);  // every number of the value; the gateway refuses beyond
    p.add_command_read("spring", state_table().add_column("spring", &spring_));
    p.add_command_read("refused", state_table().add_column("refused", &refused_));
  }
  static bool valid(const SpringParams& s) noexcept {
    return std::isfinite(s.stiffness) && s.stiffness >= 0 && s.stiffness <= 5000 &&
           std::isfinite(s.max_force) && s.max_force >= 0 && s.max_force <= 10;
  }
  void run() override {}  // the setting is the state: nothing to compute

 private:
  SpringParams spring_;
  std::int64_t refused_ = 0;
};

void register_components(saw::deploy::ComponentRegistry& registry) {
  registry.add(
      "lab_tuning", "example lab component: a setting of the lab's own message type",
      [](const saw::deploy::ComponentContext& ctx, saw::deploy::Params& p) {
        SpringParams s;
        s.stiffness = p.get_in_range("stiffness", 0, 5000, s.stiffness);
        s.max_force = p.get_in_range("max_force", 0, 10, s.max_force);
        return std::pair{saw::deploy::periodic_task(ctx, p, "lab_tuning"), s};
      },
      [](const std::string& name, const std::pair<saw::TaskConfig, SpringParams>& c) {
        return std::make_unique<Tuning>(name, c.first, c.second);
      });
}

}  // namespace lab

SAW_PLUGIN(lab::register_components)
