// A server process for the bridge tests: task NAME exports interface "arm" until killed.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "saw/bridge/exporter.hpp"
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
  }
  void run() override {
    ++count_;
    if (count_ % 10 == 0) (void)(*ticked_)(count_);
  }

 private:
  std::int64_t count_ = 0;
  saw::EventWrite<std::int64_t>* ticked_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  std::signal(SIGTERM, [](int) { stop.store(true); });
  Device device(argv[1]);
  saw::bridge::Exporter exporter(device, "arm");
  saw::Manager m;
  m.add(device);
  m.start();
  std::printf("ready %s\n", exporter.segment_name().c_str());
  std::fflush(stdout);
  while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  m.stop();
  return 0;
}
