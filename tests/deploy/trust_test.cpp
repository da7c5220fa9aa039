// Trust boundaries seen from outside, with real saw-rt processes: a device never keeps pushing
// when the teleoperation process dies, and a FAULT says why in the summary. Also: the bounds of
// the teleop and device parameters are deployment-file errors with file:line:key.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <thread>

#include "packages.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/crtk.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/fault.hpp"
#include "saw/gateway/type_map.hpp"
#include "saw/type_info.hpp"
#include "text.hpp"

extern char** environ;

namespace {

using namespace std::chrono_literals;

using saw::testing::read_file;
using saw::testing::replace_all;

// A saw-rt process, its output in `log`; SIGKILLed and reaped when the handle goes.
struct SawRt {
  SawRt(const std::string& file, const std::string& duration, std::string log_path)
      : log(std::move(log_path)) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    std::vector<std::string> args{SAW_RT_PATH, file, "--duration", duration};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid, SAW_RT_PATH, &fa, nullptr, argv.data(), environ) != 0) pid = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~SawRt() { kill9(); }
  void kill9() {
    if (pid <= 0) return;
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    pid = -1;
  }
  // Waits (bounded) for the process to exit by itself; its exit code, or -1.
  int wait_exit(std::chrono::milliseconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    int status = 0;
    while (std::chrono::steady_clock::now() < deadline) {
      if (waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }
  pid_t pid = -1;
  std::string log;
};

bool poll_until(const std::function<bool()>& done, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

// The master device of config/teleop-sim-master.yaml, read from this process through the bridge.
struct RemoteMaster {
  explicit RemoteMaster(const std::string& name) {
    poll_until(
        [&] {
          try {
            component = saw::bridge::ShmResolver().resolve(name);
          } catch (const std::exception&) {  // not exported yet
          }
          return component != nullptr;
        },
        20s);
    if (component == nullptr) return;
    const auto& arm = *component->provided_interfaces().front();
    servo_force_ = arm.find_command("servo_force");
    command_timeout_ = arm.find_command("command_timeout");
    trips_ = arm.find_command("watchdog_trips");
  }
  bool ready() const { return servo_force_ != nullptr && command_timeout_ != nullptr && trips_ != nullptr; }
  // The force applied in the master's newest row (NaN if the read failed: never zero by accident).
  saw::Vec3 servo_force() const {
    saw::Vec3 f{NAN, NAN, NAN};
    if (servo_force_->read(nullptr, &f) != saw::Status::ok) f = {NAN, NAN, NAN};
    return f;
  }
  bool timed_out() const {
    bool t = false;
    (void)command_timeout_->read(nullptr, &t);
    return t;
  }
  std::uint64_t trips() const {
    std::uint64_t n = 0;
    (void)trips_->read(nullptr, &n);
    return n;
  }
  std::unique_ptr<saw::Component> component;

 private:
  const saw::Command *servo_force_ = nullptr, *command_timeout_ = nullptr, *trips_ = nullptr;
};

double norm(const saw::Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The two-process deployment of the README, under names no other run uses.
struct TwoProcesses {
  explicit TwoProcesses(const std::string& tag) : master("master" + tag + std::to_string(getpid())) {
    const std::string dir = ::testing::TempDir();
    std::ofstream(dir + master + "-m.yaml")
        << replace_all(read_file(SAW_SOURCE_DIR "/config/teleop-sim-master.yaml"), "master", master);
    std::ofstream(dir + master + "-s.yaml") << replace_all(
        read_file(SAW_SOURCE_DIR "/config/teleop-sim-slave.yaml"), "server: master", "server: " + master);
    master_path = dir + master + "-m.yaml";
    slave_path = dir + master + "-s.yaml";
  }
  std::string master, master_path, slave_path;
};

// kill -9 of the teleoperation process: the master's own watchdog drops its force to zero.
TEST(TrustBoundaries, KillingTheTeleopProcessLeavesTheMasterPushingNothing) {
  TwoProcesses p("wd");
  SawRt master(p.master_path, "120", p.master_path + ".log");
  ASSERT_GT(master.pid, 0);
  RemoteMaster remote(p.master);
  ASSERT_TRUE(remote.ready()) << "the master's arm (servo_force, command_timeout, watchdog_trips) is not "
                                 "exported\n"
                              << read_file(master.log);
  SawRt teleop(p.slave_path, "120", p.slave_path + ".log");
  ASSERT_GT(teleop.pid, 0);
  // The teleoperation pushes the master back as the scripted hand drags it.
  ASSERT_TRUE(poll_until([&] { return norm(remote.servo_force()) > 1e-3; }, 20s)) << read_file(teleop.log);
  EXPECT_FALSE(remote.timed_out());
  teleop.kill9();
  ASSERT_TRUE(poll_until([&] { return remote.timed_out() && norm(remote.servo_force()) == 0.0; }, 10s))
      << "the master kept pushing with " << norm(remote.servo_force()) << " N";
  EXPECT_EQ(remote.trips(), 1u);
  // And it holds: zero on every row read for the next 200 ms.
  saw::Vec3 pushed{};
  poll_until(
      [&] {
        // A read may fail (a row being written, many retries on this 2-core VM): skip it, it is NaN.
        if (const saw::Vec3 f = remote.servo_force(); !std::isnan(norm(f)) && norm(f) != 0.0) pushed = f;
        return false;
      },
      200ms);
  EXPECT_EQ(pushed, (saw::Vec3{}));
  master.kill9();
}

// kill -9 of the master process: the teleop FAULTs, and its summary says why.
TEST(TrustBoundaries, AFaultSaysWhyInTheSummary) {
  TwoProcesses p("ft");
  SawRt master(p.master_path, "120", p.master_path + ".log");
  ASSERT_GT(master.pid, 0);
  RemoteMaster remote(p.master);
  ASSERT_TRUE(remote.ready()) << read_file(master.log);
  SawRt teleop(p.slave_path, "4", p.slave_path + ".log");
  ASSERT_TRUE(poll_until([&] { return norm(remote.servo_force()) > 1e-3; }, 20s)) << read_file(teleop.log);
  master.kill9();
  ASSERT_EQ(teleop.wait_exit(60s), 0) << read_file(teleop.log);
  const std::string out = read_file(teleop.log);
  EXPECT_TRUE(std::regex_search(
      out, std::regex(R"(teleop: FAULT \(master input stale: [0-9.]+ ms old.*, at t=[0-9.]+ s\), tracking)")))
      << out;
  EXPECT_TRUE(std::regex_search(out, std::regex(R"(error teleop: FAULT: master input stale: \d+ ns old)")))
      << "the RT log says it too\n"
      << out;
}

// ---- Parameter bounds are deployment-file errors ------------------------------------------------

const char* good = R"(deployment: {name: t, clock: stepped}
components:
  - name: master
    type: sim_haptic_device
    task: {period: 1ms}
    params: {command_timeout: 3ms}
  - name: slave
    type: sim_haptic_device
    task: {period: 1ms}
  - name: teleop
    type: teleop
    task: {period: 1ms}
    params: {gains: {master: 100, slave: 100}, prediction: {enabled: true, master: 20ms}}
connections:
  - {client: teleop, required: master, server: master, provided: arm}
  - {client: teleop, required: slave, server: slave, provided: arm}
)";

std::string error_of(const std::string& from, const std::string& to) {
  std::string text = good;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  try {
    (void)saw::testing::build(text, "cfg.yaml", saw::testing::registry());
  } catch (const saw::deploy::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for: " << to;
  return "";
}

TEST(TrustBoundaries, ParameterBoundsAreFileErrors) {
  const auto expect = [](const std::string& message, const char* pattern) {
    EXPECT_TRUE(std::regex_search(message, std::regex(pattern))) << message;
  };
  expect(error_of("command_timeout: 3ms", "command_timeout: 500us"),
         R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.command_timeout': must be at least one period)");
  expect(error_of("command_timeout: 3ms", "command_timeout: 20s"),
         R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.command_timeout')");
  expect(error_of("master: 20ms}", "master: 5s}"),
         R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.prediction\.master': 5 s is out of range)");
  expect(error_of("gains: {master: 100", "gains: {master: 20000"),
         R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.gains\.master')");
  expect(error_of("gains: {master: 100, slave: 100}", "gains: {master: 100, slave: 100}, stale_timeout: 0s"),
         R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.stale_timeout')");
}

}  // namespace

namespace {

// The gateway publishes read commands and events by type: a FaultInfo goes to DDS as the
// text of crtk_msgs/StringStamped, on rt/<component>/fault (and on rt/<component>/error, see
// tests/gateway/error_topic_test.cpp), whoever raised it.
TEST(TrustBoundaries, TheGatewayMapsAFaultToText) {
  const saw::gateway::MappingRegistry mappings = saw::gateway::core_mappings();
  const auto* m = mappings.find(saw::type_info_of<saw::FaultInfo>().name);
  ASSERT_NE(m, nullptr);
  const auto* command = mappings.find(saw::type_info_of<saw::StateCommand>().name);
  ASSERT_NE(command, nullptr);
  EXPECT_EQ(m->dds_type(), command->dds_type()) << "crtk_msgs/StringStamped";
  EXPECT_EQ(mappings.find_by_dds(m->dds_type()), command) << "state commands still decode";
  saw::FaultInfo f;  // the teleoperation task's
  f.code = saw::FaultCode::input_stale;
  f.set_source("master");
  f.last_read = saw::Status::disconnected;
  f.age_ns = 23'400'000;
  f.since_start_ns = 4'512'000'000;
  EXPECT_EQ(m->to_text(&f), "master input stale: 23.4 ms old (last read: disconnected), at t=4.512 s");
  saw::FaultInfo drive;  // a CANopen drive's emergency: its error code says why
  drive.code = saw::FaultCode::device_error;
  drive.set_source("node 5");
  drive.detail = 0x2310;
  drive.since_start_ns = 1'000'000'000;
  EXPECT_EQ(m->to_text(&drive), "node 5 device error (code 0x2310), at t=1.000 s");
}

}  // namespace
