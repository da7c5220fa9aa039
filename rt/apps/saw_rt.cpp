// saw-rt: the RT host. Loads the packages (the package directory, as plug-ins), a YAML deployment
// (and its plug-ins), validates all of it, runs it (with its packages' sections: a gateway
// process), prints a summary. It knows no concrete
// component and links no package.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <thread>

#include "packages.hpp"
#include "run_summary.hpp"
#include "saw/deploy/deployment.hpp"
#include "service_notify.hpp"

namespace {

using namespace std::chrono_literals;
std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-rt: runs a sawrt deployment (YAML)"};
  std::string config, record, host;
  std::vector<std::string> plugins;
  double duration = 0;
  bool stepped = false, list = false;
  app.add_option("config", config, "deployment file (YAML)");
  app.add_option("--duration", duration, "seconds to run (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_flag("--stepped", stepped, "simulated clock, as fast as possible (needs --duration)");
  app.add_option("--record", record, "CSV file for the deployment's record: columns")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_flag("--list-types", list, "list the component types (with --plugin's) and exit");
  app.add_option("--plugin", plugins, "a plug-in to load before the file's own plugins: (repeatable)");
  app.add_option("--host", host, "the host (of the file's hosts: section) whose components to run here");
  CLI11_PARSE(app, argc, argv);
  // From the first moment: a service manager's SIGTERM while the packages load or the devices
  // start is an orderly stop, never the default death (which a slow start once met).
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  saw::deploy::ComponentRegistry registry;
  try {
    saw::apps::load_packages(registry);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-rt: %s\n", e.what());
    return 2;
  }
  for (const auto& p : plugins) {
    try {
      registry.load_plugin(p);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "saw-rt: --plugin %s: %s\n", p.c_str(), e.what());
      return 2;
    }
  }
  if (list) {
    for (const auto& [name, type] : registry.types())
      std::printf("%-20s %s%s\n", name.c_str(), type.description.c_str(),
                  type.origin.empty() ? "" : (" [" + type.origin + "]").c_str());
    return 0;
  }
  if (config.empty()) {
    std::fprintf(stderr, "saw-rt: a deployment file is required (see --help)\n");
    return 2;
  }
  std::optional<saw::deploy::Deployment> d;
  try {
    auto spec = saw::deploy::load_deployment_spec(config, registry, host);
    if (stepped) spec.clock = saw::deploy::Clock::stepped;
    d.emplace(saw::deploy::build_deployment(std::move(spec), registry));
    if (!record.empty()) d->set_record_file(record);
  } catch (const saw::deploy::ConfigError& e) {
    std::fprintf(stderr, "saw-rt: %s\nnothing was started.\n", e.what());
    return 2;
  }
  if (d->clock() == saw::deploy::Clock::stepped && duration <= 0) {
    std::fprintf(stderr, "saw-rt: the stepped clock needs --duration\n");
    return 2;
  }
  if (stop_requested.load()) {
    std::fprintf(stderr, "saw-rt: stopped before it started (a signal while loading)\n");
    return 0;
  }
  try {
    d->start();
  } catch (const std::exception& e) {
    // A device that does not boot, a port that does not open: the others were stopped safely.
    std::fprintf(stderr, "saw-rt: %s\n", e.what());
    return 1;
  }
  // Every task runs: what a Type=notify unit (and a test that stops saw-rt) waits for.
  saw::apps::notify_service("READY=1");
  const auto started = std::chrono::steady_clock::now();
  if (d->clock() == saw::deploy::Clock::stepped) {
    d->run_for(duration);
  } else {
    while (!stop_requested.load() && (duration <= 0 || std::chrono::steady_clock::now() - started <
                                                           std::chrono::duration<double>(duration)))
      std::this_thread::sleep_for(20ms);
  }
  saw::apps::notify_service("STOPPING=1");
  d->stop();
  const double ran = d->clock() == saw::deploy::Clock::stepped
                         ? duration
                         : std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  saw::apps::print_summary(stdout, *d, registry, ran);
  return 0;
}
