// saw-demo: two connected 1 kHz tasks (a simulated 1-DOF plant and its PD controller); the
// README's main job until the teleoperation deployment lands.
#include <CLI/CLI.hpp>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <fstream>
#include <thread>

#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;

std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }

// A mass on a rail: integrates the commanded force each cycle.
class Plant : public saw::Task {
 public:
  explicit Plant(saw::TaskConfig c) : Task("plant", c) {
    auto& p = provide("joint");
    p.add_command_read("measured_js", state_table().add_column("measured_js", &position_));
    p.add_command_write<double>("servo_jf", [this](const double& f) { force_ = f; });
    limit_ = &p.add_event_write<double>("limit_reached");
  }
  void run() override {
    constexpr double mass = 0.5, damping = 0.2, limit = 0.2;
    const double dt = static_cast<double>(config().period.count()) * 1e-9;
    velocity_ += dt * (force_ - damping * velocity_) / mass;
    position_ += dt * velocity_;
    if (std::abs(position_) > limit && !at_limit_) (void)(*limit_)(position_);
    at_limit_ = std::abs(position_) > limit;
  }

 private:
  double position_ = 0, velocity_ = 0, force_ = 0;
  bool at_limit_ = false;
  saw::EventWrite<double>* limit_;
};

// Tracks a 0.5 Hz sinusoid with a PD law; keeps its tracking error as state.
class Controller : public saw::Task {
 public:
  explicit Controller(saw::TaskConfig c) : Task("controller", c) {
    auto& r = require("joint");
    r.add_function("measured_js", measured_js_);
    r.add_function("servo_jf", servo_jf_);
    r.add_event_handler_write<double>("limit_reached", [this](const double&) { ++limit_events_; });
    provide("stats").add_command_read("error", state_table().add_column("error", &error_));
  }
  void run() override {
    double q = 0;
    if (measured_js_(q) != saw::Status::ok) return;
    if (t0_ == 0) t0_ = now();
    const double t = static_cast<double>(now() - t0_) * 1e-9;
    const double goal = 0.1 * std::sin(2 * M_PI * 0.5 * t);
    error_ = goal - q;
    const double f = 2000.0 * error_ - 60.0 * (q - last_q_) / (static_cast<double>(config().period.count()) * 1e-9);
    last_q_ = q;
    if (servo_jf_(f) != saw::Status::ok) ++refused_;
    sum_sq_ += error_ * error_;
    ++samples_;
  }
  double rms_error() const { return samples_ ? std::sqrt(sum_sq_ / static_cast<double>(samples_)) : 0; }
  std::uint64_t refused_ = 0, limit_events_ = 0;

 private:
  saw::FunctionRead<double> measured_js_;
  saw::FunctionWrite<double> servo_jf_;
  saw::TimeNs t0_ = 0;
  double error_ = 0, last_q_ = 0, sum_sq_ = 0;
  std::uint64_t samples_ = 0;
};

void print_task(const saw::Task& t) {
  const auto s = t.statistics();
  const auto& h = t.wakeup_histogram();
  std::printf("  %-11s cycles %7llu  overruns %llu (missed %llu)  wake-up latency us: min %.1f mean %.1f p99 %.1f max %.1f  compute mean %.1f us\n",
              t.name().c_str(), static_cast<unsigned long long>(s.cycles), static_cast<unsigned long long>(s.overruns),
              static_cast<unsigned long long>(s.missed_periods), static_cast<double>(h.min()) / 1e3, h.mean() / 1e3,
              static_cast<double>(h.percentile(0.99)) / 1e3, static_cast<double>(h.max()) / 1e3, s.mean_compute / 1e3);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-demo: a simulated plant and its controller, two 1 kHz tasks"};
  double duration = 5.0;
  int priority = 80;
  int cpu = -1;
  std::string histogram;
  app.add_option("--duration", duration, "seconds to run (0: until SIGINT/SIGTERM)")->check(CLI::NonNegativeNumber);
  app.add_option("--priority", priority, "SCHED_FIFO priority of the plant (controller: one less)")->check(CLI::Range(0, 99));
  app.add_option("--cpu", cpu, "CPU to pin both tasks to (-1: any)");
  app.add_option("--histogram", histogram, "write both wake-up histograms here, cyclictest format");
  CLI11_PARSE(app, argc, argv);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  Plant plant(saw::TaskConfig::periodic(1ms, priority, cpu));
  Controller controller(saw::TaskConfig::periodic(1ms, priority > 1 ? priority - 1 : priority, cpu));
  saw::Manager manager;
  manager.add(plant);
  manager.add(controller);
  manager.connect("controller", "joint", "plant", "joint");
  manager.start();
  std::printf("saw-demo: plant and controller at 1 kHz for %s (Ctrl-C stops)\n",
              duration > 0 ? (std::to_string(duration) + " s").c_str() : "ever");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration);
  while (!stop_requested.load() && (duration == 0 || std::chrono::steady_clock::now() < deadline))
    std::this_thread::sleep_for(50ms);
  manager.stop();

  std::printf("summary:\n");
  print_task(plant);
  print_task(controller);
  std::printf("  tracking RMS error %.3f mm, commands refused %llu, limit events %llu\n", controller.rms_error() * 1e3,
              static_cast<unsigned long long>(controller.refused_),
              static_cast<unsigned long long>(controller.limit_events_));
  if (!histogram.empty()) {
    std::ofstream out(histogram);
    const saw::LatencyHistogram* hs[] = {&plant.wakeup_histogram(), &controller.wakeup_histogram()};
    saw::write_cyclictest_histogram(out, hs);
    std::printf("  histograms written to %s\n", histogram.c_str());
  }
  return 0;
}
