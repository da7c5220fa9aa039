#include "saw/teleop/delay_task.hpp"

#include <stdexcept>

namespace saw::teleop {
namespace {
std::size_t rows_for(TaskConfig task, double delay_seconds) {
  const double period = static_cast<double>(task.period.count()) * 1e-9;
  if (period <= 0) throw std::invalid_argument("DelayTask must be periodic");
  if (!(delay_seconds >= 0) || delay_seconds > 10)
    throw std::invalid_argument("DelayTask delay must be 0..10 s");
  // History must reach back `delay`, with margin for the row being written and the lookup.
  return static_cast<std::size_t>(delay_seconds / period) + 16;
}
}  // namespace

DelayTask::DelayTask(std::string name, TaskConfig task, double delay_seconds)
    : Task(std::move(name), task, rows_for(task, delay_seconds)),
      delay_(static_cast<TimeNs>(delay_seconds * 1e9)) {
  source_cp_column_ = state_table().add_column("source_cp", &source_cp_);
  source_cv_column_ = state_table().add_column("source_cv", &source_cv_);
  auto& p = provide("arm");
  p.add_command_read("measured_cp", state_table().add_column("measured_cp", &measured_cp_));
  p.add_command_read("measured_cv", state_table().add_column("measured_cv", &measured_cv_));
  p.add_command_write<Wrench>("servo_cf", [this](const Wrench& w) { (void)write_cf_(w); });
  clutch_ = &p.add_event_write<ButtonEvent>("clutch");
  operator_present_ = &p.add_event_write<ButtonEvent>("operator_present");

  auto& r = require("source");
  r.add_function("measured_cp", read_cp_);
  r.add_function("measured_cv", read_cv_);
  r.add_function("servo_cf", write_cf_, Need::optional);
  r.add_event_handler_write<ButtonEvent>(
      "clutch", [this](const ButtonEvent& b) { (void)(*clutch_)(b); }, Need::optional);
  r.add_event_handler_write<ButtonEvent>(
      "operator_present", [this](const ButtonEvent& b) { (void)(*operator_present_)(b); }, Need::optional);
}

void DelayTask::run() {
  (void)read_cp_(source_cp_);
  (void)read_cv_(source_cv_);
  // The rows written so far hold the source as it was at each past cycle; until history
  // reaches back `delay`, the output is not published (the row repeats the initial value).
  if (delay_ == 0) {
    measured_cp_ = source_cp_;
    measured_cv_ = source_cv_;
    return;
  }
  Pose p;
  Twist v;
  if (state_table().read_at_or_before(source_cp_column_, now() - delay_, p) == Status::ok &&
      state_table().read_at_or_before(source_cv_column_, now() - delay_, v) == Status::ok) {
    measured_cp_ = p;
    measured_cv_ = v;
    have_output_ = true;
  } else if (!have_output_) {
    measured_cp_ = source_cp_;  // no history reaching back `delay` yet: the oldest we have is now
    measured_cv_ = source_cv_;
  }
}

}  // namespace saw::teleop
