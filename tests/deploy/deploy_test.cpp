// Deployment files: every mistake is reported with file, line, column and key, before anything
// starts; a good file runs, records, and the saw-rt process behaves as documented.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "packages.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "text.hpp"

namespace {

using saw::deploy::ConfigError;

using saw::testing::build;
using saw::testing::registry;

const char* good = R"(deployment: {name: t, clock: stepped}
components:
  - name: master
    type: sim_haptic_device
    task: {period: 1ms}
    params: {model: omni, hand: {type: sinusoid, amplitude: [0.02, 0, 0], frequency: 0.5}}
  - name: slave
    type: sim_haptic_device
    task: {period: 1ms}
  - name: teleop
    type: teleop
    task: {period: 1ms}
    params: {gains: {master: 100, slave: 100}}
connections:
  - {client: teleop, required: master, server: master, provided: arm}
  - {client: teleop, required: slave, server: slave, provided: arm}
)";

// Replaces `from` by `to` once in the good file, parses it, and returns the error message.
std::string error_of(const std::string& from, const std::string& to) {
  std::string text = good;
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  try {
    (void)build(text, "cfg.yaml", registry());
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for: " << to;
  return "";
}

TEST(Deployment, GoodFileParsesAndNothingRunsYet) {
  auto d = build(good, "cfg.yaml", registry());
  EXPECT_EQ(d.components().size(), 3u);
  for (auto* c : d.components()) EXPECT_EQ(c->lifecycle(), saw::Lifecycle::constructed);
}

struct Case {
  const char* from;
  const char* to;
  const char* expect;  // regex the message must match
};

// Each case's edit of the good file fails with a message matching its pattern.
void expect_error(const Case& c) {
  const auto message = error_of(c.from, c.to);
  EXPECT_TRUE(std::regex_search(message, std::regex(c.expect)))
      << "message: " << message << "\nexpected: " << c.expect;
}

TEST(Deployment, EveryErrorNamesFileLineColumnAndKey) {
  const Case cases[] = {
      {"type: teleop", "type: telop",
       R"(^cfg\.yaml:11:11: key 'components\[2\]\.type': unknown component type 'telop' \(known: .*teleop)"},
      {"{model: omni,", "{model: omnni,",
       R"(^cfg\.yaml:6:21: key 'components\[0\]\.params\.model': 'omnni' is not one of: omni, falcon)"},
      {"frequency: 0.5", "frequency: fast",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.hand\.frequency': expected a number, got 'fast')"},
      {"amplitude: [0.02, 0, 0]", "amplitude: [0.02, 0]",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.hand\.amplitude': expected a list of exactly 3 numbers)"},
      {"task: {period: 1ms}\n    params: {gains", "task: {period: 1 ms}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.period': '1 ms' is not a duration)"},
      {"gains: {master: 100", "gainz: {master: 100",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.gainz': unknown parameter)"},
      {"name: slave", "name: master",
       R"(^cfg\.yaml:7:\d+: key 'components\[1\]\.name': a component named 'master' exists already)"},
      {"server: slave,", "server: slav,",
       R"(^cfg\.yaml:16:\d+: key 'connections\[1\]': .*no component named 'slav')"},
      {"provided: arm}\n  - {client: teleop, required: slave",
       "provided: sim}\n  - {client: teleop, required: slave",
       R"(^cfg\.yaml:15:\d+: key 'connections\[0\]': [\s\S]*'measured_cp'[\s\S]*no such command)"},
      {"deployment: {name: t, clock: stepped}", "deployment: {name: t, clock: [stepped}",
       R"(^cfg\.yaml:1:\d+: key '': YAML syntax)"},
      {"    params: {gains: {master: 100, slave: 100}}", "    params: {gains: {master: 100, slave: -5}}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.gains\.slave': .*out of range)"},
      {"task: {period: 1ms}\n    params: {gains", "task: {period: 1ms, offset: 1ms}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.offset': the phase must be at least 0 and less than the period)"},
  };
  for (const auto& c : cases) expect_error(c);
}

// Every periodic task has a deadline policy: the standard one unless its `task:` says another, or off.
TEST(Deployment, EveryPeriodicTaskHasADeadlinePolicyUnlessItSaysOff) {
  const std::string teleop_task = "task: {period: 1ms}\n    params: {gains";
  const Case cases[] = {
      {teleop_task.c_str(), "task: {period: 1ms, deadline: sometimes}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.deadline': expected off, or \{in_a_row: N, share: S, window: T\})"},
      {teleop_task.c_str(), "task: {period: 1ms, deadline: {in_a_row: 2.5}}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.deadline\.in_a_row': expected a whole number)"},
      {teleop_task.c_str(), "task: {period: 1ms, deadline: {share: 1.5}}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.deadline\.share': .*out of range)"},
      {teleop_task.c_str(), "task: {period: 1ms, deadline: {window: 5ms}}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.deadline\.window': the share is judged over at least 10 periods)"},
      {teleop_task.c_str(), "task: {period: 1ms, deadline: {in_a_row: 3, shares: 0.1}}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.deadline\.shares': unknown parameter)"},
  };
  for (const auto& c : cases) expect_error(c);

  std::string text = good;
  text.replace(text.find(teleop_task), teleop_task.size(),
               "task: {period: 2ms, deadline: {in_a_row: 3, share: 0.25, window: 1s}}\n    params: {gains");
  text.replace(text.find("task: {period: 1ms}"), 19, "task: {period: 1ms, deadline: off}");
  auto d = build(text, "cfg.yaml", registry());
  const auto policy = [&](const char* name) { return d.find<saw::Task>(name)->config().deadline; };
  EXPECT_FALSE(policy("master").enabled()) << "deadline: off";
  const auto standard = saw::DeadlinePolicy::standard();
  EXPECT_EQ(policy("slave").in_a_row, standard.in_a_row);
  EXPECT_EQ(policy("slave").share, standard.share);
  EXPECT_EQ(policy("slave").window, standard.window);
  EXPECT_EQ(policy("teleop").in_a_row, 3u);
  EXPECT_EQ(policy("teleop").share, 0.25);
  EXPECT_EQ(policy("teleop").window, 500u) << "1 s of 2 ms periods";
}

// `deployment: {deadline: ...}` is every periodic task's policy unless its `task:` says another;
// a task's keys override the deployment's one by one.
TEST(Deployment, TheDeploymentsDeadlineIsEveryTasksDefault) {
  const std::string head = "deployment: {name: t, clock: stepped}";
  const std::string teleop_task = "task: {period: 1ms}\n    params: {gains";
  std::string text = good;
  text.replace(text.find(head), head.size(),
               "deployment: {name: t, clock: stepped, deadline: {in_a_row: 5, share: 0.02, window: 2s}}");
  text.replace(text.find(teleop_task), teleop_task.size(),
               "task: {period: 2ms, deadline: {in_a_row: 7}}\n    params: {gains");
  text.replace(text.find("task: {period: 1ms}"), 19, "task: {period: 1ms, deadline: off}");
  auto d = build(text, "cfg.yaml", registry());
  const auto policy = [&](const char* name) { return d.find<saw::Task>(name)->config().deadline; };
  EXPECT_FALSE(policy("master").enabled()) << "its own deadline: off";
  EXPECT_EQ(policy("slave").in_a_row, 5u) << "the deployment's";
  EXPECT_EQ(policy("slave").share, 0.02);
  EXPECT_EQ(policy("slave").window, 2000u) << "2 s of 1 ms periods";
  EXPECT_EQ(policy("teleop").in_a_row, 7u) << "its own key";
  EXPECT_EQ(policy("teleop").share, 0.02) << "the deployment's key";
  EXPECT_EQ(policy("teleop").window, 1000u) << "2 s of 2 ms periods";

  std::string off = good;
  off.replace(off.find(head), head.size(), "deployment: {name: t, clock: stepped, deadline: off}");
  auto o = build(off, "cfg.yaml", registry());
  EXPECT_FALSE(o.find<saw::Task>("slave")->config().deadline.enabled());

  const Case cases[] = {
      {head.c_str(), "deployment: {name: t, clock: stepped, deadline: {window: 5ms}}",
       R"(^cfg\.yaml:1:\d+: key 'deployment\.deadline\.window': the share is judged over at least 10 periods)"},
      {head.c_str(), "deployment: {name: t, clock: stepped, deadline: sometimes}",
       R"(^cfg\.yaml:1:\d+: key 'deployment\.deadline': expected off, or)"},
  };
  for (const auto& c : cases) expect_error(c);
}

// `history:` sizes a task's state table: how far a recorder or another history reader may fall
// behind before it loses rows.
TEST(Deployment, ATasksHistoryIsAsLongAsItSays) {
  const std::string teleop_task = "task: {period: 1ms}\n    params: {gains";
  const Case cases[] = {
      {teleop_task.c_str(), "task: {period: 1ms, history: 2 min}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.history': '2 min' is not a duration)"},
      {teleop_task.c_str(), "task: {period: 1ms, history: 61s}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.history': a periodic task's history is at least a period and at most 60 s)"},
      {teleop_task.c_str(), "task: {period: 1ms, history: 100us}\n    params: {gains",
       R"(^cfg\.yaml:12:\d+: key 'components\[2\]\.task\.history': a periodic task's history)"},
  };
  for (const auto& c : cases) expect_error(c);
  std::string text = good;
  text.replace(text.find(teleop_task), teleop_task.size(),
               "task: {period: 2ms, history: 3s}\n    params: {gains");
  auto d = build(text, "cfg.yaml", registry());
  EXPECT_EQ(d.find<saw::Task>("teleop")->state_table().capacity(), 1500u) << "3 s of 2 ms periods";
  EXPECT_EQ(d.find<saw::Task>("master")->state_table().capacity(), saw::StateTable::default_rows);
}

// `law:` picks the teleoperation's law; its settings are its own parameters, checked as declared.
TEST(Deployment, TheLawIsChosenByNameAndItsSettingsChecked) {
  const std::string collaborative = "params: {gains: {master: 100, slave: 100}}";
  const Case cases[] = {
      {"params: {gains: {master: 100, slave: 100}}", "params: {law: springy}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.law': 'springy' is not one of: collaborative, passive_bilateral, position_position, surgical, wave_variables)"},
      {"params: {gains: {master: 100, slave: 100}}", "params: {law: position_position, stiffness: 1e9}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.stiffness': .*out of range)"},
      // Another law's setting is not this law's: an unknown parameter.
      {"params: {gains: {master: 100, slave: 100}}", "params: {law: position_position, gains: {master: 1}}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.gains': unknown parameter)"},
      // A slave that follows a pose needs a law that gives one.
      {"params: {gains: {master: 100, slave: 100}}", "params: {slave_command: servo_cp}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.slave_command': law 'collaborative' gives the slave a force only)"},
      {"params: {gains: {master: 100, slave: 100}}", "params: {law: surgical}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.law': law 'surgical' gives the slave a pose only: it needs slave_command: servo_cp)"},
      {"params: {gains: {master: 100, slave: 100}}", "params: {slave_command: servo_jp}",
       R"(key 'components\[2\]\.params\.slave_command': 'servo_jp' is not one of: servo_cf, servo_cp)"},
      {"params: {gains: {master: 100, slave: 100}}", "params: {mirror: [1, 0.5, 1]}",
       R"(^cfg\.yaml:13:\d+: key 'components\[2\]\.params\.mirror': each entry must be 1 or -1)"},
  };
  for (const auto& c : cases) {
    const auto message = error_of(c.from, c.to);
    EXPECT_TRUE(std::regex_search(message, std::regex(c.expect)))
        << "message: " << message << "\nexpected: " << c.expect;
  }
  std::string text = good;
  text.replace(text.find(collaborative), collaborative.size(),
               "params: {law: position_position, stiffness: 200, damping: 1}");
  auto d = build(text, "cfg.yaml", registry());
  d.start();
  d.run_for(1.0);
  d.stop();
  auto* t = d.find<saw::teleop::Teleoperation>("teleop");
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->law_name(), "position_position");
  EXPECT_EQ(t->operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_GT(t->enabled_cycles(), 900u);
  EXPECT_LT(t->tracking_rms(), 0.02) << "the slave follows the master";
}

// The human-like hand (reaches with dwells, tremor) and the virtual wall of the simulated device.
TEST(Deployment, HandAndWallParametersAreCheckedLikeTheRest) {
  const std::string hand = "hand: {type: sinusoid, amplitude: [0.02, 0, 0], frequency: 0.5}";
  const Case cases[] = {
      {hand.c_str(), "hand: {type: reach, targets: [[0.02, 0, 0], [0.01, 0]]}",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.hand\.targets': expected a point \[x, y, z\])"},
      {hand.c_str(), "hand: {type: reach}",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.hand\.targets')"},
      {hand.c_str(), "hand: {type: reach, targets: [[0.9, 0, 0]]}",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.hand\.targets': a target is more than 0\.5 m)"},
      {hand.c_str(), "hand: {type: line, tremor: {amplitude: 0.01}}",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.hand\.tremor\.amplitude': .*out of range)"},
      {hand.c_str(), "wall: {normal: [0, 0, 0]}",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.wall\.normal': must not be zero)"},
      {hand.c_str(), "wall: {normal: [1, 0, 0], stifness: 10}",
       R"(^cfg\.yaml:6:\d+: key 'components\[0\]\.params\.wall\.stifness': unknown parameter)"},
  };
  for (const auto& c : cases) expect_error(c);
  std::string text = good;
  text.replace(text.find(hand), hand.size(),
               "hand: {type: reach, targets: [[0.02, 0, 0], [0, 0.02, 0]], reach_time: 0.6, dwell: 0.3, "
               "tremor: {amplitude: 0.0003, frequency: 9}}, wall: {point: [0.01, 0, 0], normal: [-1, 0, 0], "
               "stiffness: 2500}");
  EXPECT_NO_THROW((void)build(text, "cfg.yaml", registry()));
}

TEST(Deployment, ConnectionTypeMismatchKeepsTheManagersMessage) {
  // teleop's required "master" wants measured_cp as read<Pose>; the device's "sim" interface has
  // set_button (write<ButtonCommand>) etc. but no measured_cp.
  const auto message = error_of("required: slave, server: slave, provided: arm",
                                "required: slave, server: teleop, provided: teleop");
  EXPECT_NE(message.find("'servo_cf'"), std::string::npos) << message;
  EXPECT_NE(message.find("'teleop'"), std::string::npos) << message;
}

// A disk that stops taking writes for longer than the state table's ring (256 rows, 256 ms at
// 1 kHz) delays the recorder's writer, not its collector: no row is lost. The file is a pipe of
// one page that nobody reads for 600 ms (a few dozen rows fill it).
TEST(Deployment, ARecordingToADiskThatStallsLosesNoRow) {
  const std::string fifo = ::testing::TempDir() + "deploy_test_stall.fifo";
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const int reader =
      ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);  // so that the recorder's open does not wait
  ASSERT_GE(reader, 0);
  ASSERT_GT(::fcntl(reader, F_SETPIPE_SZ, 4096), 0);
  std::string text = std::string(good) + "record: {file: " + fifo + ", columns: [master.measured_cp]}\n";
  text.replace(text.find("clock: stepped"), 14, "clock: real");
  auto d = build(text, "cfg.yaml", registry());
  d.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  std::uint64_t newlines = 0;
  std::thread drain([&] {  // the disk takes writes again, until the recorder closes the file
    ::fcntl(reader, F_SETFL, 0);
    char b[65536];
    for (ssize_t n; (n = ::read(reader, b, sizeof b)) > 0;)
      newlines += static_cast<std::uint64_t>(std::count(b, b + n, '\n'));
  });
  d.run_for(0.3);
  d.stop();
  drain.join();
  ::close(reader);
  std::filesystem::remove(fifo);
  ASSERT_NE(d.recorder(), nullptr);
  EXPECT_EQ(d.recorder()->lost_rows(), 0u);
  EXPECT_GT(d.recorder()->rows(), 700u);          // the 900 ms run's rows, give or take its start and stop
  EXPECT_EQ(newlines, d.recorder()->rows() + 1);  // and the header
}

TEST(Deployment, SteppedRunRecordsEveryRow) {
  const std::string csv = ::testing::TempDir() + "deploy_test.csv";
  std::string text = std::string(good) + "record: {file: " + csv +
                     ", columns: [master.measured_cp, teleop.tracking_error]}\n";
  auto d = build(text, "cfg.yaml", registry());
  d.start();
  d.run_for(1.0);
  d.stop();
  ASSERT_NE(d.recorder(), nullptr);
  EXPECT_EQ(d.recorder()->rows(), 1001u);
  EXPECT_EQ(d.recorder()->lost_rows(), 0u);
  std::ifstream in(csv);
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header,
            "time,master.measured_cp.x,master.measured_cp.y,master.measured_cp.z,master.measured_cp.qx,"
            "master.measured_cp.qy,master.measured_cp.qz,master.measured_cp.qw,teleop.tracking_error");
  int rows = 0;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 1001);
  auto* t = d.find<saw::teleop::Teleoperation>("teleop");
  ASSERT_NE(t, nullptr);
  EXPECT_LT(t->tracking_rms(), 1e-3);
}

int run(const std::string& args, std::string& output) {
  output.clear();
  FILE* p = popen((std::string(SAW_RT_PATH) + " " + args + " 2>&1").c_str(), "r");
  char buf[512];
  while (fgets(buf, sizeof buf, p) != nullptr) output += buf;
  return WEXITSTATUS(pclose(p));
}

TEST(SawRt, BadFileExitsTwoHavingStartedNothing) {
  const std::string path = ::testing::TempDir() + "bad.yaml";
  std::ofstream(path) << std::string(good).replace(std::string(good).find("type: teleop"), 12, "type: telop");
  std::string out;
  EXPECT_EQ(run(path + " --duration 5", out), 2);
  EXPECT_NE(out.find(path + ":11:11: key 'components[2].type'"), std::string::npos) << out;
  EXPECT_NE(out.find("nothing was started"), std::string::npos) << out;
}

TEST(SawRt, GoodFileRunsAndPrintsItsSummary) {
  const std::string path = ::testing::TempDir() + "good.yaml";
  std::ofstream(path) << good;
  std::string out;
  EXPECT_EQ(run(path + " --duration 0.5", out), 0) << out;  // stepped per the file
  EXPECT_TRUE(std::regex_search(out, std::regex(R"(teleop +1\.00ms +500 )"))) << out;
  EXPECT_NE(out.find("tracking error"), std::string::npos) << out;
}

}  // namespace

namespace {

// The shipped deployment, on the stepped clock: the slave tracks the master.
TEST(Integration, ShippedTeleopSimTracksInSteppedMode) {
  auto d = saw::deploy::load_deployment(SAW_SOURCE_DIR "/config/teleop-sim.yaml", registry());
  d.set_clock(saw::deploy::Clock::stepped);
  d.start();
  d.run_for(5.0);
  d.stop();
  auto* t = d.find<saw::teleop::Teleoperation>("teleop");
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_EQ(t->enabled_cycles(), 5001u);
  EXPECT_LT(t->tracking_rms(), 1e-3);
  EXPECT_GT(t->tracking_rms(), 0.0) << "the master does move";
}

// With 20 ms of delay on the master's positions, the local model removes most of the error.
double delayed_rms(bool predict) {
  std::string text = good;
  text.replace(
      text.find("connections:"), std::string("connections:").size(),
      "  - {name: master_delay, type: delay, task: {period: 1ms}, params: {delay: 20ms}}\nconnections:\n"
      "  - {client: master_delay, required: source, server: master, provided: arm}");
  text.replace(text.find("required: master, server: master"),
               std::string("required: master, server: master").size(),
               "required: master, server: master_delay");
  text.replace(text.find("gains: {master: 100, slave: 100}"),
               std::string("gains: {master: 100, slave: 100}").size(),
               std::string("gains: {master: 0, slave: 300}, stale_timeout: 100ms, prediction: {enabled: ") +
                   (predict ? "true" : "false") + ", master: 20ms}");
  auto d = build(text, "cfg.yaml", registry());
  const auto* master = d.find<saw::drivers::SimHapticDevice>("master");
  const auto* slave = d.find<saw::drivers::SimHapticDevice>("slave");
  d.start();
  // The real positions, not the teleop's (delayed) view of them.
  double sum = 0;
  int n = 0;
  for (int i = 0; i < 6000; ++i) {
    d.manager().step();
    saw::Pose m, s;
    if (i < 2000 || master->state_table().read_latest(master->columns().measured_cp, m) != saw::Status::ok ||
        slave->state_table().read_latest(slave->columns().measured_cp, s) != saw::Status::ok)
      continue;
    sum += std::pow(m.position[0] - s.position[0], 2);
    ++n;
  }
  d.stop();
  return std::sqrt(sum / n);
}

TEST(Integration, PredictionReducesTheTrackingErrorOfADelayedMaster) {
  const double without = delayed_rms(false), with = delayed_rms(true);
  EXPECT_GT(without, 0.5e-3) << "20 ms of delay on a 2 cm, 0.5 Hz sinusoid shows";
  EXPECT_LT(with, 0.5 * without);
}

}  // namespace

namespace {

using saw::testing::read_file;
using saw::testing::replace_all;

// The same teleoperation split over two saw-rt processes: only the deployment files differ.
TEST(Integration, TwoProcessesTeleoperateThroughTheBridge) {
  const std::string master = "master" + std::to_string(getpid());  // a name no other run uses
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "m.yaml") << replace_all(read_file(SAW_SOURCE_DIR "/config/teleop-sim-master.yaml"),
                                               "master", master);
  std::ofstream(dir + "s.yaml") << replace_all(read_file(SAW_SOURCE_DIR "/config/teleop-sim-slave.yaml"),
                                               "server: master", "server: " + master);
  const std::string server_cmd =
      std::string(SAW_RT_PATH) + " " + dir + "m.yaml --duration 8 > " + dir + "m.log 2>&1 &";
  ASSERT_EQ(std::system(server_cmd.c_str()), 0);
  std::string out;
  int rc = 2;
  for (int attempt = 0; attempt < 50 && rc != 0; ++attempt) {  // until the master has exported (bounded)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    rc = run(dir + "s.yaml --duration 1.5", out);
  }
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("teleop: ENABLED"), std::string::npos) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(RMS ([0-9.]+) mm)"))) << out;
  EXPECT_LT(std::stod(m[1]), 1.0) << out;
  EXPECT_TRUE(std::regex_search(out, std::regex(R"(slave +1\.00ms +1[45]\d\d )"))) << out;
}

}  // namespace

namespace {

TEST(Integration, OneFileOnTwoHostsRunsAsTwoProcessesWithHost) {
  const std::string tag = std::to_string(getpid());  // component names no other run uses
  const std::string dir = ::testing::TempDir();
  std::string text = read_file(SAW_SOURCE_DIR "/config/teleop-sim-hosts.yaml");
  for (const char* c : {"master", "slave", "teleop"}) {
    text = replace_all(text, std::string("name: ") + c, std::string("name: ") + c + tag);
    text = replace_all(text, std::string("server: ") + c, std::string("server: ") + c + tag);
    text = replace_all(text, std::string("client: ") + c, std::string("client: ") + c + tag);
    text = replace_all(text, std::string(c) + ".", std::string(c) + tag + ".");
  }
  std::ofstream(dir + "hosts.yaml") << text;
  const std::string operator_cmd = std::string(SAW_RT_PATH) + " " + dir +
                                   "hosts.yaml --host operator --duration 8 > " + dir + "op.log 2>&1 &";
  ASSERT_EQ(std::system(operator_cmd.c_str()), 0);
  std::string out;
  int rc = 2;
  for (int attempt = 0; attempt < 50 && rc != 0; ++attempt) {  // until the operator has exported (bounded)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    rc = run(dir + "hosts.yaml --host patient --duration 1.5", out);
  }
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("ENABLED"), std::string::npos) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(RMS ([0-9.]+) mm)"))) << out;
  EXPECT_LT(std::stod(m[1]), 1.0) << out;
}

std::string hosts_error(const std::string& text, const std::string& host) {
  try {
    (void)build(text, "cfg.yaml", registry(), host);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for host '" << host << "'";
  return "";
}

TEST(Deployment, HostsAreCheckedLikeTheRest) {
  const std::string placed =
      replace_all(
          replace_all(replace_all(std::string(good), "  - name: master\n", "  - name: master\n    host: a\n"),
                      "  - name: slave\n", "  - name: slave\n    host: b\n"),
          "  - name: teleop\n", "  - name: teleop\n    host: b\n") +
      "hosts: {a: {}, b: {}}\n";
  EXPECT_TRUE(
      std::regex_search(hosts_error(placed, ""), std::regex(R"(key 'hosts': .*run saw-rt with --host)")));
  EXPECT_TRUE(
      std::regex_search(hosts_error(placed, "c"), std::regex(R"(key 'hosts': no host 'c' \(hosts: a, b\))")));
  EXPECT_TRUE(std::regex_search(hosts_error(replace_all(placed, "host: a", "host: z"), "a"),
                                std::regex(R"(cfg\.yaml:4:\d+: key 'components\[0\]\.host': no host 'z')")));
  EXPECT_TRUE(std::regex_search(hosts_error(good, "a"), std::regex(R"(--host a given, but)")));
  // Host b builds its two components only, and its connections; a's master is someone else's.
  auto b = build(replace_all(placed, "server: master", "server: slave"), "cfg.yaml", registry(), "b");
  EXPECT_EQ(b.components().size(), 2u);
}

}  // namespace
