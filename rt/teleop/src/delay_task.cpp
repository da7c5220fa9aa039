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
  source_row_time_column_ = state_table().add_column("source_row_time", &source_row_time_);
  namespace arm = crtk::arm;
  auto& p = provide(std::string(arm::interface_name));
  crtk::provide(p, arm::measured_cp, state_table(), &measured_cp_);
  crtk::provide(p, arm::measured_cv, state_table(), &measured_cv_);
  crtk::provide(p, delayed_arm::source_time, state_table(), &source_time_);
  crtk::provide(p, delayed_arm::delay, state_table(), &delay_);
  crtk::provide(p, arm::servo_cf, [this](const Wrench& w) { (void)write_cf_(w); });
  clutch_ = &crtk::provide(p, arm::clutch);
  operator_present_ = &crtk::provide(p, arm::operator_present);

  auto& r = require("source");
  crtk::require(r, arm::measured_cp, read_cp_);
  crtk::require(r, arm::measured_cv, read_cv_);
  crtk::require(r, arm::servo_cf, write_cf_, Need::optional);
  crtk::require(
      r, arm::clutch, [this](const ButtonEvent& b) { (void)(*clutch_)(b); }, Need::optional);
  crtk::require(
      r, arm::operator_present, [this](const ButtonEvent& b) { (void)(*operator_present_)(b); },
      Need::optional);
}

void DelayTask::run() {
  // A failed read keeps the previous value and its time: a dead source shows as a source time
  // that stops advancing, never as fresh rows of this task.
  Pose cp;
  Twist cv;
  RowStamp stamp;
  if (read_cp_(cp, stamp) == Status::ok && read_cv_(cv) == Status::ok) {
    source_cp_ = cp;
    source_cv_ = cv;
    source_row_time_ = stamp.time;
  }
  // The rows written so far hold the source as it was at each past cycle; until history
  // reaches back `delay`, the output is not published (the row repeats the initial value).
  if (delay_ == 0) {
    measured_cp_ = source_cp_;
    measured_cv_ = source_cv_;
    source_time_ = source_row_time_;
    return;
  }
  Pose p;
  Twist v;
  TimeNs t = 0;
  const TimeNs then = now() - delay_;
  if (state_table().read_at_or_before(source_cp_column_, then, p) == Status::ok &&
      state_table().read_at_or_before(source_cv_column_, then, v) == Status::ok &&
      state_table().read_at_or_before(source_row_time_column_, then, t) == Status::ok) {
    measured_cp_ = p;
    measured_cv_ = v;
    source_time_ = t;
    have_output_ = true;
  } else if (!have_output_) {
    measured_cp_ = source_cp_;  // no history reaching back `delay` yet: the oldest we have is now
    measured_cv_ = source_cv_;
    source_time_ = source_row_time_;
  }
}

}  // namespace saw::teleop
