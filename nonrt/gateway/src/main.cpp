// saw-gateway: maps components exported by an RT process on this host to DDS.
#include <sys/prctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include "saw/gateway/gateway.hpp"
#include "saw/gateway/settings.hpp"
#include "saw/gateway/type_map.hpp"
#include "security_cli.hpp"

namespace {
std::atomic<bool> stop_requested{false};
std::atomic<int> stop_signal{0};
void on_signal(int sig) {
  stop_signal.store(sig, std::memory_order_relaxed);
  stop_requested.store(true, std::memory_order_relaxed);
}
}  // namespace

// The gateway's configuration from its settings: the one place the two meet.
saw::gateway::GatewayConfig config_of(const saw::gateway::GatewaySettings& s) {
  saw::gateway::GatewayConfig c;
  c.attach = s.attach;
  c.mirrors = s.mirrors;
  for (const auto& im : s.imports) {
    saw::gateway::ImportConfig i;
    i.component = im.component;
    i.arm = im.arm;
    i.ros_namespace = s.ros_namespace;
    i.clutch_topic = s.clutch_topic;
    i.operator_present_topic = s.operator_present_topic;
    i.commands = im.commands;
    i.safe_command = im.safe_command;
    i.command_timeout = im.command_timeout;
    i.offset = im.offset;
    c.imports.push_back(i);
  }
  c.dds.domain = s.domain;
  c.dds.interfaces = s.interfaces;
  c.dds.peers = s.peers;
  if (!s.enclave.empty()) c.dds.enclave = s.enclave;
  c.decimation = static_cast<unsigned>(s.decimation);
  c.display_rate = s.display_rate;
  c.name = s.name;
  return c;
}

int main(int argc, char** argv) {
  CLI::App app{"saw-gateway: maps components exported through the shared-memory bridge to DDS"};
  saw::gateway::GatewaySettings s;
  std::string settings;
  double duration = 0, wait = 5;
  std::vector<std::string> imports;
  app.add_option("--settings", settings,
                 "all settings at once, as a deployment's gateway: section (YAML; saw-rt passes them so)");
  app.add_option("--attach", s.attach, "exported component to map to DDS (repeatable)");
  app.add_option("--import", imports,
                 "foreign CRTK arm to present through the bridge: NAME or NAME=ARM (topics rt/[NS/]ARM/...; "
                 "repeatable)");
  app.add_option(
      "--mirror", s.mirrors,
      "component served by a gateway on another host, to present on this host: NAME, or NAME=LOCAL to "
      "present it under another name (repeatable)");
  app.add_option("--ros-namespace", s.ros_namespace, "namespace of the imported arms' topics");
  app.add_option("--clutch-topic", s.clutch_topic, "sensor_msgs/Joy topic of the clutch (\"\": none)");
  app.add_option("--operator-present-topic", s.operator_present_topic,
                 "sensor_msgs/Joy topic of the operator-present sensor (\"\": none)");
  app.add_option("--domain", s.domain, "DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--interface", s.interfaces,
                 "IPv4 address of a network interface DDS may use (repeatable; default loopback only)");
  app.add_option("--peer", s.peers,
                 "a peer beyond this subnet, found by unicast: ADDRESS or ADDRESS:PORT (repeatable; default "
                 "$ROS_STATIC_PEERS)");
  app.add_option("--decimation", s.decimation, "publish state every Nth row")->check(CLI::PositiveNumber);
  app.add_option("--display-rate", s.display_rate,
                 "Hz of each state's display stream <topic>/display, what live views read (0: none)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--name", s.name, "gateway name, unique per host (default gateway.<pid>)");
  app.add_option("--wait", wait, "seconds to wait for the components to be exported")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--duration", duration, "seconds to run (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_option(
         "--enclave", s.enclave,
         "DDS Security enclave KEYSTORE/enclaves/NAME (default: ROS_SECURITY_* environment, else none)")
      ->type_name("DIR");
  bool exit_with_parent = false;
  app.add_flag("--exit-with-parent", exit_with_parent,
               "stop when the parent process (saw-rt) is gone: SIGTERM then means it died (FAULT is said), "
               "SIGINT is its orderly stop");
  CLI11_PARSE(app, argc, argv);
  const pid_t parent = getppid();
  if (exit_with_parent) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);                  // the RT process died (even kill -9): go too
    if (getppid() != parent || parent == 1) return 0;  // it died before we asked
  }
  if (!settings.empty()) {
    for (const char* o :
         {"--attach", "--import", "--mirror", "--ros-namespace", "--clutch-topic", "--operator-present-topic",
          "--peer", "--domain", "--interface", "--decimation", "--display-rate", "--name", "--enclave"})
      if (app.count(o) != 0) {
        std::fprintf(stderr, "saw-gateway: --settings gives every setting; %s too is ambiguous\n", o);
        return 2;
      }
    try {
      s = saw::gateway::settings_from_yaml(settings, "--settings");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "saw-gateway: %s\n", e.what());
      return 2;
    }
  }
  for (const auto& i : imports) {
    const auto eq = i.find('=');
    saw::gateway::ImportSettings im;
    im.component = i.substr(0, eq);
    im.arm = eq == std::string::npos ? im.component : i.substr(eq + 1);
    s.imports.push_back(im);
  }
  if (s.attach.empty() && s.imports.empty() && s.mirrors.empty()) {
    std::fprintf(stderr, "saw-gateway: nothing to do: give --attach, --import or --mirror\n");
    return 2;
  }
  saw::gateway::GatewayConfig config = config_of(s);
  config.attach_timeout = static_cast<saw::TimeNs>(wait * 1e9);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    // The rt core's types and the packages' (the teleoperation's settings, a lab's).
    auto mappings = std::make_shared<saw::gateway::MappingRegistry>(saw::gateway::core_mappings());
    saw::gateway::load_mapping_modules(*mappings);
    config.mappings = std::move(mappings);
    saw::gateway::Gateway gateway(config);
    std::printf("saw-gateway %s: %zu endpoints\n", gateway.name().c_str(), gateway.endpoints().size());
    saw::gateway::print_security(config.dds);
    for (const auto& e : gateway.endpoints())
      std::printf("  %-14s %-26s %-24s %s\n", e.kind.c_str(), (e.component + "." + e.name).c_str(),
                  e.label().c_str(), e.topic.empty() ? "(not mapped)" : e.topic.c_str());
    std::fflush(stdout);
    const auto started = std::chrono::steady_clock::now();
    while (!stop_requested.load() && (duration <= 0 || std::chrono::steady_clock::now() - started <
                                                           std::chrono::duration<double>(duration)))
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    // Orphaned: the RT process died. Say so before leaving: peers then see FAULT and why, where
    // they would otherwise see only this participant gone.
    // SIGTERM is the death signal: getppid() may still name the dying RT process, whose other
    // threads the kernel reparents us to first (the thread that started us died first).
    if (exit_with_parent && (stop_signal.load() == SIGTERM || getppid() != parent))
      gateway.announce_exit("the RT process (pid " + std::to_string(parent) + ") exited");
    const auto st = gateway.stats();
    const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
    std::printf(
        "saw-gateway: published %llu state samples (and %llu on display streams; %llu rows skipped), %llu "
        "events; %llu commands in, %llu rejected; %llu reconnects; %llu queries; imported %llu samples, "
        "%llu rejected, %llu badly stamped; %llu commands to arms (%llu safe, of the imports' own); mirrored "
        "%llu samples\n",
        u(st.published), u(st.displayed), u(st.rows_skipped), u(st.events), u(st.commands), u(st.rejected),
        u(st.reconnects), u(st.queries), u(st.imported), u(st.imported_rejected), u(st.imported_bad_stamps),
        u(st.arm_commands), u(st.arm_safe_commands), u(st.mirrored));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-gateway: %s\n", e.what());
    return 1;
  }
  return 0;
}
