// saw-socketcand: serves sawrt CAN buses to socketcand clients (python-can, Kayak) on 127.0.0.1.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>

#include "socketcand_server.hpp"

namespace {
std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true, std::memory_order_relaxed); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-socketcand: the socketcand protocol (raw mode) for sawrt CAN buses, on 127.0.0.1 only"};
  saw::can::SocketcandOptions options;
  app.add_option("--bus", options.buses,
                 "a bus to serve: virtual:<name>, socketcan:<ifname>, or a bare name (virtual); repeatable. "
                 "Clients open it by its name.")
      ->required();
  app.add_option("--port", options.port, "TCP port on 127.0.0.1 (0: any free port)")->capture_default_str();
  app.add_option("--log", options.log, "write every frame on the served buses to this candump -L file");
  app.add_option("--max-clients", options.max_clients, "clients served at once")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);
  try {
    saw::can::SocketcandServer server(options);
    // One line on stdout, for scripts that asked for port 0.
    std::printf("saw-socketcand: listening on 127.0.0.1:%u\n", static_cast<unsigned>(server.port()));
    std::fflush(stdout);
    server.run(stop_requested);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-socketcand: %s\n", e.what());
    return 2;
  }
  return 0;
}
