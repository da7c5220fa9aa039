// saw-rt: the RT host. Loads a YAML deployment, validates all of it, runs it, prints a summary.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <thread>

#include "builtin_types.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/teleop/collaborative_control_force.hpp"

namespace {

using namespace std::chrono_literals;
std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }

void print_summary(saw::deploy::Deployment& d, double seconds) {
  std::printf("summary of '%s' (%s clock, %.3f s):\n", d.name().c_str(),
              d.clock() == saw::deploy::Clock::stepped ? "stepped" : "real", seconds);
  std::printf("  %-14s %8s %10s %9s %9s %9s %9s %9s %9s\n", "task", "period", "cycles", "overruns", "missed",
              "lat.min", "lat.mean", "lat.p99", "lat.max");
  for (saw::Component* c : d.components()) {
    const auto* t = dynamic_cast<saw::Task*>(c);
    if (t == nullptr) continue;
    const auto s = t->statistics();
    const auto& h = t->wakeup_histogram();
    std::printf("  %-14s %6.2fms %10llu %9llu %9llu %7.1fus %7.1fus %7.1fus %7.1fus\n", t->name().c_str(),
                static_cast<double>(t->config().period.count()) * 1e-6,
                static_cast<unsigned long long>(s.cycles), static_cast<unsigned long long>(s.overruns),
                static_cast<unsigned long long>(s.missed_periods), static_cast<double>(h.min()) / 1e3,
                h.mean() / 1e3, static_cast<double>(h.percentile(0.99)) / 1e3,
                static_cast<double>(h.max()) / 1e3);
  }
  for (saw::Component* c : d.components()) {
    if (const auto* t = dynamic_cast<saw::teleop::CollaborativeControlForce*>(c))
      std::printf(
          "  %s: %s, tracking error |e_s| RMS %.3f mm, max %.3f mm over %llu enabled cycles; "
          "rejected settings %llu, refused force commands %llu\n",
          t->name().c_str(), std::string(saw::to_string(t->operating_state())).c_str(),
          t->tracking_rms() * 1e3, t->tracking_max() * 1e3,
          static_cast<unsigned long long>(t->enabled_cycles()),
          static_cast<unsigned long long>(t->rejected_commands()),
          static_cast<unsigned long long>(t->refused_sends()));
    if (const auto* t = dynamic_cast<saw::teleop::CollaborativeControlForce*>(c);
        t && t->enabled_cycles() != 0)
      std::printf(
          "  %s: master sample -> force command: mean %.1f us, max %.1f us; %llu of %llu cycles used a "
          "sample "
          "from an earlier cycle\n",
          t->name().c_str(), t->master_age_mean() / 1e3, static_cast<double>(t->master_age_max()) / 1e3,
          static_cast<unsigned long long>(t->master_age_late()),
          static_cast<unsigned long long>(t->enabled_cycles()));
    if (const auto* s = dynamic_cast<saw::drivers::SimHapticDevice*>(c))
      if (s->rejected_commands() != 0)
        std::printf("  %s: %llu force commands rejected (non-finite or over the limit)\n", s->name().c_str(),
                    static_cast<unsigned long long>(s->rejected_commands()));
  }
  if (const auto* r = d.recorder())
    std::printf("  recorder: %llu rows to %s, %llu rows lost\n", static_cast<unsigned long long>(r->rows()),
                r->path().c_str(), static_cast<unsigned long long>(r->lost_rows()));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-rt: runs a sawrt deployment (YAML)"};
  std::string config, record;
  double duration = 0;
  bool stepped = false, list = false;
  app.add_option("config", config, "deployment file (YAML)");
  app.add_option("--duration", duration, "seconds to run (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_flag("--stepped", stepped, "simulated clock, as fast as possible (needs --duration)");
  app.add_option("--record", record, "CSV file for the deployment's record: columns")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_flag("--list-types", list, "list the component types and exit");
  std::string host;
  app.add_option("--host", host, "the host (of the file's hosts: section) whose components to run here");
  CLI11_PARSE(app, argc, argv);

  saw::deploy::ComponentRegistry registry;
  saw::apps::register_builtin_types(registry);
  if (list) {
    for (const auto& [name, entry] : registry.types())
      std::printf("%-20s %s\n", name.c_str(), entry.second.c_str());
    return 0;
  }
  if (config.empty()) {
    std::fprintf(stderr, "saw-rt: a deployment file is required (see --help)\n");
    return 2;
  }
  std::optional<saw::deploy::Deployment> d;
  try {
    d.emplace(saw::deploy::load_deployment(config, registry, host));
    if (stepped) d->set_clock(saw::deploy::Clock::stepped);
    if (!record.empty()) d->set_record_file(record);
  } catch (const saw::deploy::ConfigError& e) {
    std::fprintf(stderr, "saw-rt: %s\nnothing was started.\n", e.what());
    return 2;
  }
  if (d->clock() == saw::deploy::Clock::stepped && duration <= 0) {
    std::fprintf(stderr, "saw-rt: the stepped clock needs --duration\n");
    return 2;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  d->start();
  const auto started = std::chrono::steady_clock::now();
  if (d->clock() == saw::deploy::Clock::stepped) {
    d->run_for(duration);
  } else {
    while (!stop_requested.load() && (duration <= 0 || std::chrono::steady_clock::now() - started <
                                                           std::chrono::duration<double>(duration)))
      std::this_thread::sleep_for(20ms);
  }
  d->stop();
  const double ran = d->clock() == saw::deploy::Clock::stepped
                         ? duration
                         : std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  print_summary(*d, ran);
  return 0;
}
