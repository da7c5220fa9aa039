// A process for the bridge tests: `NAME` exports task NAME's "arm" until killed; `client NAME`
// sends to it; `sleeper NAME` waits for its updates until killed; `v2 NAME` exports a type with another
// layout version.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/manager.hpp"

namespace {

std::atomic<bool> stop{false};

class Device : public saw::Task {
 public:
  explicit Device(std::string name)
      : Task(std::move(name), saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& p = provide("arm");
    p.add_command_read("count", state_table().add_column("count", &count_));
    p.add_command_write<std::int64_t>("add", [this](const std::int64_t& v) { count_ += v; });
    p.add_command_void("reset", [this] { count_ = 0; });
    ticked_ = &p.add_event_write<std::int64_t>("ticked");
    p.add_command_qualified_read<std::int64_t, std::int64_t>(
        "tripled", [](const std::int64_t& q, std::int64_t& r) { r = 3 * q; });
  }
  void run() override {
    ++count_;
    if (count_ % 10 == 0) (void)(*ticked_)(count_);
  }

 private:
  std::int64_t count_ = 0;
  saw::EventWrite<std::int64_t>* ticked_;
};

// Client mode: connects to NAME.arm through the bridge and sends add(1) every cycle.
class Sender : public saw::Task {
 public:
  Sender() : Task("sender", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    require("arm").add_function("add", add_);
  }
  void run() override { (void)add_(1); }

 private:
  saw::FunctionWrite<std::int64_t> add_;
};

int run_client(const char* name) {
  Sender sender;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(sender);
  try {
    m.connect("sender", "arm", name, "arm");
  } catch (const saw::ConnectError& e) {
    std::printf("connect failed: %s\n", e.what());
    return 3;
  }
  m.start();
  std::printf("connected\n");
  std::fflush(stdout);
  while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  m.stop();
  return 0;
}

}  // namespace

// The same type name as the test's, with another layout version (a process built from newer code).
namespace probe {
struct Sample {
  static constexpr std::string_view type_name = "probe::Sample";
  static constexpr std::uint32_t layout_version = 2;
  double a = 0, b = 0;
};
}  // namespace probe

namespace {

class Versioned : public saw::Task {
 public:
  explicit Versioned(std::string name)
      : Task(std::move(name), saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    provide("arm").add_command_write<probe::Sample>("set", [](const probe::Sample&) {});
  }
};

int serve(saw::Task& task) {
  saw::bridge::Exporter exporter(task, "arm");
  saw::Manager m;
  m.add(task);
  m.start();
  std::printf("ready %s\n", exporter.segment_name().c_str());
  std::fflush(stdout);
  while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  m.stop();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  std::signal(SIGTERM, [](int) { stop.store(true); });
  if (std::string(argv[1]) == "v2" && argc == 3) {
    Versioned task(argv[2]);
    return serve(task);
  }
  if (std::string(argv[1]) == "client" && argc == 3) return run_client(argv[2]);
  if (std::string(argv[1]) == "sleeper" && argc == 3) {  // a non-RT consumer asleep on the update bell
    auto c = saw::bridge::ShmResolver().resolve(argv[2]);
    auto* proxy = dynamic_cast<saw::bridge::Proxy*>(c.get());
    if (proxy == nullptr) return 3;
    std::uint32_t seen = 0;
    for (;;) (void)proxy->wait_for_update(seen, 60'000'000'000);
  }
  Device device(argv[1]);
  return serve(device);
}
