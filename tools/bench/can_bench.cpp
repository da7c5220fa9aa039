// saw-bench-can: what CANopen costs the 1 kHz cycle on sawrt's virtual CAN bus, with the drives
// simulated by saw-can-sim in another process. Three figures, each beside a baseline from the
// same run (a noisy VM's absolute tails are the machine's, not the code's):
//   1. the BusMaster's receive + transmit per cycle (PDO unpack and pack, the CiA 402
//      controllers, SYNC) for 1, 3 and 6 drives, beside an empty cycle timed the same way;
//   2. the SYNC period as the bus stamped each SYNC, beside the sending task's wake-up latency;
//   3. end to end in config/canopen-sim.yaml's teleoperation: a master sample's row time to the
//      RPDO that carries the command computed from it, as the bus stamped that RPDO.
// Figures, not assertions: goals are printed as met or missed.
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/virtual_bus.hpp"
#include "saw/canopen/bus_master.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/pdo_text.hpp"
#include "saw/canopen/registration.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/drivers/sim_registration.hpp"
#include "saw/manager.hpp"
#include "saw/rt_context.hpp"
#include "saw/rt_thread.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "saw/teleop/registration.hpp"
#include "stats.hpp"

namespace {

using namespace std::chrono_literals;
using saw::TimeNs;
using saw::bench::summarize;
using saw::bench::Summary;
namespace canopen = saw::canopen;
namespace can = saw::can;

constexpr TimeNs period_ns = 1'000'000;

can::BusConfig bus_config(const std::string& uri) {
  can::BusConfig c;
  c.uri = uri;
  return c;
}

// ---- saw-can-sim, the drives, in a process of its own -------------------------------------

class SimProcess {
 public:
  // Starts `exe args...` (pinned to `cpu` unless -1) with stdout and stderr in `log`, and waits
  // for its line saying the drives are on the bus; throws std::runtime_error if it does not come.
  SimProcess(const std::string& exe, std::vector<std::string> args, int cpu, std::string log)
      : log_(std::move(log)) {
    args.insert(args.begin(), exe);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    cpu_set_t set;
    CPU_ZERO(&set);
    if (cpu >= 0) CPU_SET(cpu, &set);
    pid_ = fork();
    if (pid_ == 0) {
      // Only async-signal-safe calls between fork and exec: this process has threads.
      (void)prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (cpu >= 0) (void)sched_setaffinity(0, sizeof set, &set);
      const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
      }
      execv(argv[0], argv.data());
      _exit(127);
    }
    if (pid_ < 0) throw std::runtime_error("fork failed");
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (text().find(" on virtual:") == std::string::npos) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("saw-can-sim exited: " + text());
      }
      if (std::chrono::steady_clock::now() > deadline) {
        stop();
        throw std::runtime_error("saw-can-sim did not say it was ready within 5 s: " + text());
      }
      std::this_thread::sleep_for(5ms);
    }
  }
  ~SimProcess() { stop(); }
  SimProcess(const SimProcess&) = delete;
  SimProcess& operator=(const SimProcess&) = delete;

  // SIGTERM (it prints its summary), then reaped.
  void stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    const auto deadline = std::chrono::steady_clock::now() + 2s;
    while (waitpid(pid_, nullptr, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid_, SIGKILL);
        waitpid(pid_, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(2ms);
    }
    pid_ = -1;
  }
  std::string text() const {
    std::ifstream in(log_);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  // From its summary ("saw-can-sim: 1.234 s, N cycles, M overruns ..."), after stop().
  std::uint64_t overruns() const {
    const std::string t = text();
    const auto at = t.find(" cycles, ");
    return at == std::string::npos ? 0 : std::strtoull(t.c_str() + at + 9, nullptr, 10);
  }

 private:
  pid_t pid_ = -1;
  std::string log_;
};

// ---- a listener: another attachment to the bus, keeping the bus's stamps of what it wants ----

class Listener {
 public:
  // Keeps the bus's stamps of every SYNC and of the frames with identifier `rpdo_id` (0: none).
  Listener(const std::string& uri, std::uint32_t rpdo_id, std::size_t capacity, int cpu)
      : bus_(can::open_bus(bus_config(uri))), rpdo_id_(rpdo_id) {
    syncs_.reserve(capacity);
    rpdos_.reserve(capacity);
    thread_ = std::thread([this, cpu] {
      if (cpu >= 0) (void)saw::rt::set_affinity(cpu);
      std::vector<can::Received> in(256);
      while (!stop_.load(std::memory_order_relaxed)) {
        const std::size_t n = bus_->receive(in);
        for (std::size_t i = 0; i < n; ++i) {
          const std::uint32_t id = in[i].frame.can_id();
          // The virtual bus stamps a frame with its sender's CLOCK_MONOTONIC as send() took it.
          if (id == canopen::cob::sync && syncs_.size() < syncs_.capacity()) syncs_.push_back(in[i].time);
          if (rpdo_id_ != 0 && id == rpdo_id_ && rpdos_.size() < rpdos_.capacity())
            rpdos_.push_back(in[i].time);
        }
        // The stamps are the sender's: how late this thread reads them does not matter, as long
        // as the ring (4096 frames: 0.2 s of 6 drives' traffic) does not lap it (counted if so).
        if (n < in.size()) std::this_thread::sleep_for(500us);
      }
    });
  }
  ~Listener() { stop(); }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  const std::vector<TimeNs>& syncs() const { return syncs_; }
  const std::vector<TimeNs>& rpdos() const { return rpdos_; }
  std::uint64_t overruns() const { return bus_->counters().overruns; }

 private:
  std::unique_ptr<can::Bus> bus_;
  std::uint32_t rpdo_id_;
  std::vector<TimeNs> syncs_, rpdos_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// ---- 1 and 2: the CAN I/O of a 1 kHz cycle ----------------------------------------------

struct IoSample {
  TimeNs io = 0, rx = 0, tx = 0;  // receive + setpoints + transmit; receive; setpoints + transmit
  TimeNs bus_rx = 0, bus_tx = 0;  // of which inside the bus's receive() and send()
  TimeNs floor = 0;               // the same three clock reads around nothing
  TimeNs wakeup = 0;              // the previous cycle's wake-up latency (the task's statistics)
  TimeNs compute = 0;             // the whole cycle two cycles back, wake-up to sleep (ditto)
  std::uint32_t frames_in = 0, frames_out = 0;
};

std::vector<canopen::AxisConfig> axes(int drives) {
  std::vector<canopen::AxisConfig> out;
  for (int i = 1; i <= drives; ++i) {
    canopen::AxisConfig a;
    a.name = "joint" + std::to_string(i);
    a.node = static_cast<std::uint8_t>(i);
    a.mode = canopen::cia402::csp;
    // saw-can-sim's built-in EDS, as config/canopen-sim.yaml has it.
    a.units = canopen::DriveUnits::rotary(4096, 100, 0.318);
    a.pdos = canopen::default_pdo_mappings(a.mode, a.node);
    out.push_back(std::move(a));
  }
  return out;
}

// The bus as the master sees it, with the time spent inside its receive() and send() added up:
// the ring's share of the CAN I/O (the rest is the BusMaster's). Its own clock reads (two per
// call, one receive and one send a cycle) are inside the CAN I/O figure.
class TimedBus final : public can::Bus {
 public:
  explicit TimedBus(can::Bus& bus) : bus_(bus) {}
  std::size_t receive(std::span<can::Received> out) noexcept override {
    const TimeNs t0 = saw::monotonic_now();
    const std::size_t n = bus_.receive(out);
    receive_ns += saw::monotonic_now() - t0;
    return n;
  }
  std::size_t send(std::span<const can::Frame> frames) noexcept override {
    const TimeNs t0 = saw::monotonic_now();
    const std::size_t n = bus_.send(frames);
    send_ns += saw::monotonic_now() - t0;
    return n;
  }
  can::BusState state() const noexcept override { return bus_.state(); }
  can::BusCounters counters() const noexcept override { return bus_.counters(); }
  const std::string& name() const noexcept override { return bus_.name(); }
  TimeNs receive_ns = 0, send_ns = 0;  // since the owner last zeroed them

 private:
  can::Bus& bus_;
};

// The master of `drives` drives as a periodic task, as CanopenArm runs it (receive, the owner's
// setpoints, transmit), each part timed with the clock read around it; with no drives, the same
// clock reads around nothing: the empty cycle.
class CanIoTask : public saw::Task {
 public:
  CanIoTask(saw::TaskConfig task, can::Bus* bus, int drives, std::size_t capacity)
      : Task("can_io", task), bus_(bus), axes_(axes(drives)) {
    if (bus_ != nullptr) {
      canopen::BusMasterConfig c;
      c.period = task.period.count();
      timed_ = std::make_unique<TimedBus>(*bus_);
      master_ = std::make_unique<canopen::BusMaster>(*timed_, c, axes_);
    }
    samples_.reserve(capacity);
  }
  void startup() override {
    if (bus_ == nullptr) return;
    canopen::StartupSequence s(*bus_, axes_);
    canopen::run_startup(s);
  }
  void run() override {
    const TimeNs t = now();
    // The framework's own figures of earlier cycles (its statistics row of the last one).
    saw::TaskStatistics st;
    (void)state_table().read_latest(statistics_column(), st);
    bool enabled = true;
    TimeNs rx = 0, tx = 0;
    if (timed_) timed_->receive_ns = timed_->send_ns = 0;
    const TimeNs t0 = saw::monotonic_now();
    if (master_) {
      master_->receive(t);
      const TimeNs t1 = saw::monotonic_now();
      for (std::size_t i = 0; i < master_->size(); ++i) {
        const auto& f = master_->feedback(i);
        enabled = enabled && f.state == canopen::cia402::State::operation_enabled;
        (void)master_->set_setpoint(i, f.position);  // csp: hold where the drive is
      }
      master_->transmit(t);
      const TimeNs t2 = saw::monotonic_now();
      rx = t1 - t0;
      tx = t2 - t1;
    } else {
      const TimeNs t1 = saw::monotonic_now();
      const TimeNs t2 = saw::monotonic_now();
      rx = t1 - t0;
      tx = t2 - t1;
    }
    const TimeNs e0 = saw::monotonic_now();
    const TimeNs e1 = saw::monotonic_now();
    const TimeNs e2 = saw::monotonic_now();
    if (!started_) {  // walk every drive to operation enabled
      started_ = true;
      for (std::size_t i = 0; master_ && i < master_->size(); ++i)
        master_->set_state_target(i, canopen::cia402::Target::operation_enabled, t);
    }
    if (enabled) enabled_.store(true, std::memory_order_release);
    std::uint64_t in = 0, out = 0;
    if (master_) in = master_->counters().frames_received, out = master_->counters().frames_sent;
    if (measure_.load(std::memory_order_relaxed) && samples_.size() < samples_.capacity()) {
      if (first_ == 0) first_ = t;
      last_ = t;
      samples_.push_back({rx + tx, rx, tx, timed_ ? timed_->receive_ns : 0, timed_ ? timed_->send_ns : 0,
                          (e1 - e0) + (e2 - e1), st.last_wakeup_latency, st.last_compute,
                          static_cast<std::uint32_t>(in - in_), static_cast<std::uint32_t>(out - out_)});
    }
    in_ = in;
    out_ = out;
  }

  bool enabled() const noexcept { return enabled_.load(std::memory_order_acquire); }
  void measure(bool on) noexcept { measure_.store(on, std::memory_order_relaxed); }
  // After the manager stopped: the samples, and the first and last measured cycle's time.
  const std::vector<IoSample>& samples() const noexcept { return samples_; }
  TimeNs first() const noexcept { return first_; }
  TimeNs last() const noexcept { return last_; }
  const canopen::MasterCounters* counters() const { return master_ ? &master_->counters() : nullptr; }

 private:
  can::Bus* bus_;
  std::vector<canopen::AxisConfig> axes_;
  std::unique_ptr<TimedBus> timed_;
  std::unique_ptr<canopen::BusMaster> master_;
  std::vector<IoSample> samples_;
  std::atomic<bool> enabled_{false}, measure_{false};
  bool started_ = false;
  TimeNs first_ = 0, last_ = 0;
  std::uint64_t in_ = 0, out_ = 0;
};

// One drive count, pooled over its windows.
struct IoRun {
  int drives = 0;
  std::vector<IoSample> samples;
  std::vector<std::int64_t> sync_deviation;  // |SYNC interval − period|, ns
  std::uint64_t syncs = 0, sync_gaps = 0;    // intervals counted; intervals ≥ 1.5 periods
  std::uint64_t send_refused = 0, listener_overruns = 0, sim_overruns = 0, windows = 0;
  std::vector<std::string> failures;
};

// What the tasks could not get (SCHED_FIFO, affinity, locked memory), said once in the header.
std::vector<std::string> rt_warnings;
void note_warnings(const saw::Manager& m) {
  for (const auto& w : m.rt_warnings())
    if (std::find(rt_warnings.begin(), rt_warnings.end(), w) == rt_warnings.end()) rt_warnings.push_back(w);
}

struct Options {
  double seconds = 1.0;
  int rounds = 2, priority = 80, cpu = 1, other_cpu = 0, sim_priority = 70, max_drives = 6;
  std::string sim_exe, config = "config/canopen-sim.yaml", log_dir;
};

void io_window(const Options& o, IoRun& run, int round) {
  const std::string bus =
      "canbench-" + std::to_string(getpid()) + "-" + std::to_string(run.drives) + "-" + std::to_string(round);
  const std::string uri = "virtual:" + bus;
  // Room for every cycle measured, and for every SYNC from the start-up on.
  const auto capacity = static_cast<std::size_t>((o.seconds + 5) * 1200);
  try {
    // The empty cycle has the same company as the others (saw-can-sim with the most drives, left
    // unconfigured, and the listener, on the other CPU): only the CAN work differs.
    std::vector<std::string> args{"--bus", uri, "--priority", std::to_string(o.sim_priority)};
    for (int i = 1; i <= (run.drives > 0 ? run.drives : o.max_drives); ++i)
      args.insert(args.end(), {"--node", std::to_string(i)});
    SimProcess sim(o.sim_exe, args, o.other_cpu, o.log_dir + "/" + bus + ".log");
    Listener listener(uri, 0, capacity, o.other_cpu);
    std::unique_ptr<can::Bus> master_bus;
    if (run.drives > 0) master_bus = can::open_bus(bus_config(uri));
    CanIoTask task(saw::TaskConfig::periodic(1ms, o.priority, o.cpu), master_bus.get(), run.drives, capacity);
    saw::Manager m;
    m.add(task);
    m.start();  // the drives' start-up: NMT reset, SDO configuration, NMT start
    note_warnings(m);
    const auto deadline = std::chrono::steady_clock::now() + 3s;
    while (!task.enabled() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(5ms);
    if (!task.enabled()) {
      m.stop();
      throw std::runtime_error("the drives did not reach operation enabled within 3 s");
    }
    std::this_thread::sleep_for(100ms);  // past the enable's transients
    task.measure(true);
    std::this_thread::sleep_for(std::chrono::duration<double>(o.seconds));
    task.measure(false);
    m.stop();
    run.samples.insert(run.samples.end(), task.samples().begin(), task.samples().end());
    ++run.windows;
    if (task.counters() != nullptr) run.send_refused += task.counters()->send_refused;
    listener.stop();
    run.listener_overruns += listener.overruns();
    // The intervals between SYNCs sent in the measured cycles, as the bus stamped them.
    TimeNs previous = 0;
    for (const TimeNs s : listener.syncs()) {
      if (s < task.first() || s > task.last() + period_ns) continue;
      if (previous != 0) {
        const TimeNs interval = s - previous;
        run.sync_deviation.push_back(std::abs(interval - period_ns));
        ++run.syncs;
        if (2 * interval >= 3 * period_ns) ++run.sync_gaps;
      }
      previous = s;
    }
    sim.stop();
    run.sim_overruns += sim.overruns();
  } catch (const std::exception& e) {
    run.failures.push_back(e.what());
  }
  (void)can::remove_virtual_bus(bus);
}

// ---- 3: end to end in the canopen-sim teleoperation ----------------------------------------

// One cycle of a task as the RT cycle observer brackets it (wake-up to sleep), and for the
// teleoperation the master's newest row at both ends.
struct Cycle {
  TimeNs begin = 0, end = 0;
  std::uint64_t master_tick_begin = 0, master_tick_end = 0;
  TimeNs master_time = 0;
};

struct E2eRecorder {
  const char* slave_name = nullptr;
  const char* teleop_name = nullptr;
  const saw::Task* master = nullptr;
  std::atomic<bool> recording{false};
  std::vector<Cycle> slave, teleop;
  bool slave_open = false, teleop_open = false;  // each written by its task's thread only
};

std::atomic<E2eRecorder*> e2e_recorder{nullptr};

void master_row(const E2eRecorder& r, std::uint64_t& tick, TimeNs& time) noexcept {
  saw::TaskStatistics st;
  saw::RowStamp stamp;
  if (r.master->state_table().read_latest(r.master->statistics_column(), st, &stamp) == saw::Status::ok) {
    tick = stamp.tick;
    time = stamp.time;
  }
}

// The observer's calls come from each task's own thread: every vector has one writer, and the
// main thread reads them after the tasks are joined.
void on_cycle_begin(const char* task) noexcept {
  E2eRecorder* r = e2e_recorder.load(std::memory_order_acquire);
  if (r == nullptr || !r->recording.load(std::memory_order_relaxed)) return;
  if (task == r->slave_name && r->slave.size() < r->slave.capacity()) {
    r->slave.push_back({saw::monotonic_now()});
    r->slave_open = true;
  } else if (task == r->teleop_name && r->teleop.size() < r->teleop.capacity()) {
    Cycle c{saw::monotonic_now()};
    master_row(*r, c.master_tick_begin, c.master_time);
    r->teleop.push_back(c);
    r->teleop_open = true;
  }
}

void on_cycle_end(const char* task) noexcept {
  E2eRecorder* r = e2e_recorder.load(std::memory_order_acquire);
  if (r == nullptr) return;
  if (task == r->slave_name && r->slave_open) {
    r->slave.back().end = saw::monotonic_now();
    r->slave_open = false;
  } else if (task == r->teleop_name && r->teleop_open) {
    Cycle& c = r->teleop.back();
    TimeNs unused = 0;
    master_row(*r, c.master_tick_end, unused);
    c.end = saw::monotonic_now();
    r->teleop_open = false;
  }
}

const saw::RtCycleObserver cycle_observer{&on_cycle_begin, &on_cycle_end};

struct E2eRun {
  bool ran = false;
  std::string failure;
  std::vector<std::int64_t> total, to_command, to_rpdo;  // ns
  std::uint64_t teleop_cycles = 0, matched = 0, superseded = 0, ambiguous = 0, row_changed = 0;
  double teleop_age_mean_us = 0, teleop_age_max_us = 0;
  double master_p99 = 0, slave_p99 = 0, teleop_p99 = 0;  // wake-up latency, µs
  std::uint64_t sim_overruns = 0, listener_overruns = 0;
  std::string bus;
};

bool enabled(const saw::Component& c) {
  const int col = c.state_table().find_column("operating_state");
  saw::OperatingState s;
  return col >= 0 &&
         c.state_table().read_latest_erased(static_cast<std::uint32_t>(col), &s, nullptr) ==
             saw::Status::ok &&
         s.state == saw::OperatingStateValue::enabled;
}

// Which RPDO carried the command of each teleoperation cycle. The slave runs the commands
// queued for it at the start of its cycle (after its wake-up, before its RPDOs), so command k
// (sent between teleop cycle k's begin and end) is in the first slave cycle j that began after
// teleop cycle k ended, provided slave cycle j−1 had sent its RPDOs before teleop cycle k began
// (else it may have run it), and the command is what RPDO j carries unless teleop cycle k+1's
// command came before slave cycle j began (superseded) or may have (ambiguous: not counted).
void associate(const E2eRecorder& r, const std::vector<TimeNs>& rpdos, E2eRun& out) {
  // Each slave cycle's RPDO: the bus stamp inside its bracket (one send() for all its frames).
  std::vector<TimeNs> frame(r.slave.size(), 0);
  std::size_t f = 0;
  for (std::size_t j = 0; j < r.slave.size(); ++j) {
    while (f < rpdos.size() && rpdos[f] < r.slave[j].begin) ++f;
    if (f < rpdos.size() && rpdos[f] <= r.slave[j].end) frame[j] = rpdos[f];
  }
  for (std::size_t k = 0; k + 1 < r.teleop.size(); ++k) {
    const Cycle& c = r.teleop[k];
    if (c.end == 0) continue;
    ++out.teleop_cycles;
    if (c.master_tick_begin != c.master_tick_end) {  // a new master row came during the cycle
      ++out.row_changed;
      continue;
    }
    const auto it = std::upper_bound(r.slave.begin(), r.slave.end(), c.end,
                                     [](TimeNs t, const Cycle& s) { return t < s.begin; });
    if (it == r.slave.begin() || it == r.slave.end()) continue;  // outside the recording
    const auto j = static_cast<std::size_t>(it - r.slave.begin());
    if (frame[j] == 0 || frame[j - 1] == 0 || frame[j - 1] >= c.begin) {
      ++out.ambiguous;
      continue;
    }
    const Cycle& next = r.teleop[k + 1];
    if (next.end != 0 && next.end < r.slave[j].begin) {
      ++out.superseded;
      continue;
    }
    if (next.begin <= frame[j]) {
      ++out.ambiguous;
      continue;
    }
    ++out.matched;
    out.total.push_back(frame[j] - c.master_time);
    out.to_command.push_back(c.end - c.master_time);
    out.to_rpdo.push_back(frame[j] - c.end);
  }
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void e2e(const Options& o, double seconds, E2eRun& out) {
  out.ran = true;
  const std::string bus = "canbench-" + std::to_string(getpid()) + "-e2e";
  out.bus = "virtual:" + bus;
  const auto capacity = static_cast<std::size_t>(seconds * 1200) + 1000;
  E2eRecorder rec;
  try {
    // The deployment file as it is, on a bus of this run's own (tests may use canopen-sim).
    std::string yaml = read_text(o.config);
    const std::string from = "virtual:canopen-sim";
    std::size_t replaced = 0;
    for (auto at = yaml.find(from); at != std::string::npos; at = yaml.find(from, at + out.bus.size())) {
      yaml.replace(at, from.size(), out.bus);
      ++replaced;
    }
    if (replaced == 0) throw std::runtime_error(o.config + " has no bus " + from);
    // As the file's comment starts the drives (not pinned, as there).
    SimProcess sim(o.sim_exe,
                   {"--bus", out.bus, "--node", "1", "--node", "2", "--node", "3", "--load-inertia", "0.002",
                    "--friction", "2e-6", "--priority", std::to_string(o.sim_priority)},
                   -1, o.log_dir + "/" + bus + ".log");
    // Node 1's RPDO: a slave cycle sends all its RPDOs in one send(), stamped once.
    Listener listener(out.bus, canopen::cob::rpdo1 + 1, static_cast<std::size_t>((seconds + 15) * 1200), -1);
    saw::deploy::ComponentRegistry registry;
    saw::canopen::register_components(registry);
    saw::drivers::sim::register_components(registry);
    saw::teleop::register_components(registry);
    auto d = saw::deploy::make_deployment(yaml, o.config, registry);
    auto* master = d.find<saw::Task>("master");
    auto* slave = d.find<canopen::CanopenArm>("slave");
    auto* teleop = d.find<saw::teleop::Teleoperation>("teleop");
    if (master == nullptr || slave == nullptr || teleop == nullptr)
      throw std::runtime_error(o.config + ": expected components master, slave (canopen_arm) and teleop");
    rec.slave_name = slave->name().c_str();
    rec.teleop_name = teleop->name().c_str();
    rec.master = master;
    rec.slave.reserve(capacity);
    rec.teleop.reserve(capacity);
    e2e_recorder.store(&rec, std::memory_order_release);
    d.start();
    note_warnings(d.manager());
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (!(enabled(*slave) && enabled(*teleop)) && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(10ms);
    const bool up = enabled(*slave) && enabled(*teleop);
    if (up) {
      std::this_thread::sleep_for(200ms);
      rec.recording.store(true);
      std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
      rec.recording.store(false);
    }
    d.stop();
    e2e_recorder.store(nullptr, std::memory_order_release);
    listener.stop();
    sim.stop();
    out.sim_overruns = sim.overruns();
    out.listener_overruns = listener.overruns();
    if (!up) throw std::runtime_error("the arm or the teleoperation was not ENABLED within 10 s");
    out.teleop_age_mean_us = teleop->master_age_mean() / 1e3;
    out.teleop_age_max_us = static_cast<double>(teleop->master_age_max()) / 1e3;
    out.master_p99 = static_cast<double>(master->wakeup_histogram().percentile(0.99)) / 1e3;
    out.slave_p99 = static_cast<double>(slave->wakeup_histogram().percentile(0.99)) / 1e3;
    out.teleop_p99 = static_cast<double>(teleop->wakeup_histogram().percentile(0.99)) / 1e3;
    associate(rec, listener.rpdos(), out);
  } catch (const std::exception& e) {
    e2e_recorder.store(nullptr, std::memory_order_release);
    out.failure = e.what();
  }
  (void)can::remove_virtual_bus(bus);
}

// ---- output -------------------------------------------------------------------------------

std::string json_summary(const Summary& s) {
  char b[200];
  std::snprintf(b, sizeof b, R"({"p50": %.3f, "p99": %.3f, "max": %.3f, "n": %zu})", s.median_us, s.p99_us,
                s.max_us, s.n);
  return b;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out + "\"";
}

template <class F>
Summary column(const std::vector<IoSample>& v, F field) {
  std::vector<std::int64_t> x;
  x.reserve(v.size());
  for (const auto& s : v) x.push_back(field(s));
  return summarize(x);
}

double mean_frames(const std::vector<IoSample>& v, bool in) {
  double sum = 0;
  for (const auto& s : v) sum += in ? s.frames_in : s.frames_out;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

struct IoFigures {
  Summary io, rx, tx, bus_rx, bus_tx, floor, compute, wakeup, sync;
  double in = 0, out = 0;
};

IoFigures figures(const IoRun& r) {
  IoFigures f;
  f.io = column(r.samples, [](const IoSample& s) { return s.io; });
  f.rx = column(r.samples, [](const IoSample& s) { return s.rx; });
  f.tx = column(r.samples, [](const IoSample& s) { return s.tx; });
  f.bus_rx = column(r.samples, [](const IoSample& s) { return s.bus_rx; });
  f.bus_tx = column(r.samples, [](const IoSample& s) { return s.bus_tx; });
  f.floor = column(r.samples, [](const IoSample& s) { return s.floor; });
  f.compute = column(r.samples, [](const IoSample& s) { return s.compute; });
  f.wakeup = column(r.samples, [](const IoSample& s) { return s.wakeup; });
  auto dev = r.sync_deviation;
  f.sync = summarize(dev);
  f.in = mean_frames(r.samples, true);
  f.out = mean_frames(r.samples, false);
  return f;
}

// "0.52 0.58 0.59": the 1, 5 and 15 minute load averages (this benchmark's company).
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

const char* verdict(bool met) { return met ? "met" : "missed"; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "saw-bench-can: the CANopen cycle's cost, SYNC jitter and end-to-end latency on a virtual bus"};
  Options o;
  std::vector<int> drive_counts{1, 3, 6};
  double e2e_seconds = 4;
  std::string json;
  app.add_option("--seconds", o.seconds, "measured seconds per window (each drive count, each round)")
      ->check(CLI::PositiveNumber);
  app.add_option("--rounds", o.rounds, "windows per drive count, taken in turns")->check(CLI::PositiveNumber);
  app.add_option("--drives", drive_counts, "drive counts (each beside the empty cycle)")
      ->check(CLI::Range(1, 64));
  app.add_option("--e2e-seconds", e2e_seconds, "measured seconds of the teleoperation (0: skip it)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--config", o.config,
                 "the teleoperation's deployment (its bus virtual:canopen-sim is renamed)");
  app.add_option("--priority", o.priority, "SCHED_FIFO priority of the master's task")
      ->check(CLI::Range(1, 99));
  app.add_option("--cpu", o.cpu, "CPU of the master's task (saw-can-sim and the listener: the other one)");
  app.add_option("--sim-priority", o.sim_priority, "SCHED_FIFO priority of saw-can-sim")
      ->check(CLI::Range(0, 99));
  app.add_option("--json", json, "also write the figures as JSON here (tools/write_performance.py)");
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGPIPE, SIG_IGN);

  const auto bin = std::filesystem::canonical("/proc/self/exe").parent_path() / "../../bin";
  o.sim_exe = (bin / "saw-can-sim").lexically_normal().string();
  if (!std::filesystem::exists(o.sim_exe)) {
    std::fprintf(stderr, "saw-bench-can: %s not found (build the saw-can-sim target)\n", o.sim_exe.c_str());
    return 2;
  }
  o.log_dir =
      (std::filesystem::temp_directory_path() / ("saw-bench-can-" + std::to_string(getpid()))).string();
  std::filesystem::create_directories(o.log_dir);
  const int ncpu = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  if (ncpu < 2) {
    o.cpu = o.other_cpu = -1;
  } else {
    o.other_cpu = o.cpu == 0 ? 1 : 0;
  }
  if (o.other_cpu >= 0) (void)saw::rt::set_affinity(o.other_cpu);
  saw::set_rt_cycle_observer(&cycle_observer);  // installed before any task starts

  // 1 and 2: the empty cycle and each drive count in turns, so that a slow stretch of the
  // machine falls on all of them alike.
  o.max_drives = *std::max_element(drive_counts.begin(), drive_counts.end());
  const std::string load_before = load_average();
  std::vector<IoRun> runs(1 + drive_counts.size());
  for (std::size_t i = 0; i < drive_counts.size(); ++i) runs[i + 1].drives = drive_counts[i];
  for (int r = 0; r < o.rounds; ++r)
    for (auto& run : runs) io_window(o, run, r);
  E2eRun e2e_run;
  if (e2e_seconds > 0) e2e(o, e2e_seconds, e2e_run);
  std::filesystem::remove_all(o.log_dir);
  const std::string load_after = load_average();

  std::vector<IoFigures> fig;
  for (const auto& r : runs) fig.push_back(figures(r));
  std::printf(
      "# saw-bench-can: %d × %.1f s per drive count in turns; master task 1 kHz SCHED_FIFO %d on CPU %d; "
      "saw-can-sim (250 µs cycle, SCHED_FIFO %d) and the listener on CPU %d; virtual bus\n",
      o.rounds, o.seconds, o.priority, o.cpu, o.sim_priority, o.other_cpu);
  std::printf("# load average (1, 5, 15 min) before %s, after %s; %d CPUs\n", load_before.c_str(),
              load_after.c_str(), ncpu);
  for (const auto& w : rt_warnings) std::printf("# warning: %s\n", w.c_str());
  std::printf("\n");
  std::printf(
      "CAN I/O per cycle (receive + setpoints + transmit; bus: inside the bus's receive() and send()), µs;\n"
      "whole cycle: wake-up to sleep\n");
  std::printf("%-18s %8s %8s %8s %8s %8s %8s %8s %9s %9s %9s %8s %7s %7s\n", "drives", "I/O p50", "p99",
              "max", "rx p50", "bus rx", "tx p50", "bus tx", "cycle p50", "p99", "max", "wake p99", "in/cyc",
              "out/cyc");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& f = fig[i];
    const std::string label = runs[i].drives == 0 ? "0 (empty cycle)" : std::to_string(runs[i].drives);
    std::printf("%-18s %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %9.3f %9.3f %9.3f %8.1f %7.1f %7.1f\n",
                label.c_str(), f.io.median_us, f.io.p99_us, f.io.max_us, f.rx.median_us, f.bus_rx.median_us,
                f.tx.median_us, f.bus_tx.median_us, f.compute.median_us, f.compute.p99_us, f.compute.max_us,
                f.wakeup.p99_us, f.in, f.out);
  }
  std::printf("the same three clock reads around nothing, in the %d-drive cycles: p50 %.3f p99 %.3f µs\n",
              runs.back().drives, fig.back().floor.median_us, fig.back().floor.p99_us);
  std::printf(
      "\nSYNC period as the bus stamped it: |interval − 1 ms|, µs, beside the same cycles' wake-up\n");
  std::printf("%-8s %8s %8s %8s %8s %6s %9s %9s %9s\n", "drives", "n", "p50", "p99", "max", "gaps",
              "wake p99", "wake max", "ratio");
  for (std::size_t i = 1; i < runs.size(); ++i) {
    const auto& f = fig[i];
    std::printf("%-8d %8zu %8.1f %8.1f %8.1f %6llu %9.1f %9.1f %9.2f\n", runs[i].drives, f.sync.n,
                f.sync.median_us, f.sync.p99_us, f.sync.max_us,
                static_cast<unsigned long long>(runs[i].sync_gaps), f.wakeup.p99_us, f.wakeup.max_us,
                f.wakeup.p99_us > 0 ? f.sync.p99_us / f.wakeup.p99_us : 0.0);
  }
  for (const auto& r : runs) {
    for (const auto& e : r.failures) std::printf("window with %d drives failed: %s\n", r.drives, e.c_str());
    // A lapped listener misses SYNCs: its gaps would be its own, not the sender's.
    if (r.listener_overruns > 0)
      std::printf("the listener lost %llu frames with %d drives: its SYNC gaps are not all the sender's\n",
                  static_cast<unsigned long long>(r.listener_overruns), r.drives);
  }

  // The goals, on the largest drive count.
  const std::size_t big = runs.size() - 1;
  const double add50 = fig[big].io.median_us - fig[0].io.median_us;
  const double add99 = fig[big].io.p99_us - fig[0].io.p99_us;
  const double sync_ratio = fig[big].wakeup.p99_us > 0 ? fig[big].sync.p99_us / fig[big].wakeup.p99_us : 0;
  const bool io_met = !runs[big].samples.empty() && add99 <= 10.0;
  const bool io_met_p50 = !runs[big].samples.empty() && add50 <= 10.0;
  const bool sync_met = fig[big].sync.n > 0 && sync_ratio <= 1.2;
  std::printf(
      "\ngoal: CAN I/O with %d drives adds ≤ 10 µs to a cycle: +%.3f µs at p50 (%s), +%.3f µs at p99 (%s)\n",
      runs[big].drives, add50, verdict(io_met_p50), add99, verdict(io_met));
  std::printf(
      "goal: SYNC jitter p99 ≤ 1.2 × the task's wake-up p99 (%d drives): %.1f / %.1f µs = %.2f (%s)\n",
      runs[big].drives, fig[big].sync.p99_us, fig[big].wakeup.p99_us, sync_ratio, verdict(sync_met));

  Summary total, to_command, to_rpdo;
  if (e2e_run.ran) {
    total = summarize(e2e_run.total);
    to_command = summarize(e2e_run.to_command);
    to_rpdo = summarize(e2e_run.to_rpdo);
    std::printf("\nEnd to end, %s on %s (%.1f s): µs\n", o.config.c_str(), e2e_run.bus.c_str(), e2e_seconds);
    if (!e2e_run.failure.empty()) std::printf("failed: %s\n", e2e_run.failure.c_str());
    std::printf("%-46s %9s %9s %9s %7s\n", "path", "p50", "p99", "max", "n");
    const auto row = [](const char* name, const Summary& s) {
      std::printf("%-46s %9.1f %9.1f %9.1f %7zu\n", name, s.median_us, s.p99_us, s.max_us, s.n);
    };
    row("master row -> RPDO on the bus (end to end)", total);
    row("master row -> teleop cycle's end (command sent)", to_command);
    row("teleop cycle's end -> RPDO on the bus", to_rpdo);
    std::printf(
        "teleop cycles %llu: matched %llu, superseded %llu, ambiguous %llu, master row changed mid-cycle "
        "%llu\n",
        static_cast<unsigned long long>(e2e_run.teleop_cycles),
        static_cast<unsigned long long>(e2e_run.matched), static_cast<unsigned long long>(e2e_run.superseded),
        static_cast<unsigned long long>(e2e_run.ambiguous),
        static_cast<unsigned long long>(e2e_run.row_changed));
    std::printf("teleop's own figure, master sample -> force command: mean %.1f µs, max %.1f µs\n",
                e2e_run.teleop_age_mean_us, e2e_run.teleop_age_max_us);
    std::printf("wake-up p99 µs: master %.1f, slave %.1f, teleop %.1f; saw-can-sim overruns %llu\n",
                e2e_run.master_p99, e2e_run.slave_p99, e2e_run.teleop_p99,
                static_cast<unsigned long long>(e2e_run.sim_overruns));
  }

  if (!json.empty()) {
    std::ofstream j(json);
    j << "{\n  \"command\": " << json_string([&] {
      std::string c;
      for (int i = 0; i < argc; ++i) c += (i ? " " : "") + std::string(argv[i]);
      return c;
    }())
      << ",\n";
    j << "  \"seconds\": " << o.seconds << ", \"rounds\": " << o.rounds << ", \"priority\": " << o.priority
      << ", \"load_before\": " << json_string(load_before) << ", \"load_after\": " << json_string(load_after)
      << ", \"cpus\": " << ncpu << ", \"cpu\": " << o.cpu << ", \"other_cpu\": " << o.other_cpu
      << ", \"sim_priority\": " << o.sim_priority << ",\n  \"warnings\": [";
    for (std::size_t k = 0; k < rt_warnings.size(); ++k) j << (k ? ", " : "") << json_string(rt_warnings[k]);
    j << "],\n  \"io\": [\n";
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const auto& f = fig[i];
      const auto& r = runs[i];
      j << "    {\"drives\": " << r.drives << ", \"windows\": " << r.windows
        << ", \"io\": " << json_summary(f.io) << ", \"rx\": " << json_summary(f.rx)
        << ", \"tx\": " << json_summary(f.tx) << ", \"bus_rx\": " << json_summary(f.bus_rx)
        << ", \"bus_tx\": " << json_summary(f.bus_tx) << ", \"floor\": " << json_summary(f.floor)
        << ", \"cycle\": " << json_summary(f.compute) << ", \"wakeup\": " << json_summary(f.wakeup)
        << ", \"sync\": " << json_summary(f.sync) << ", \"sync_gaps\": " << r.sync_gaps
        << ", \"frames_in\": " << f.in << ", \"frames_out\": " << f.out
        << ", \"send_refused\": " << r.send_refused << ", \"listener_overruns\": " << r.listener_overruns
        << ", \"sim_overruns\": " << r.sim_overruns << ", \"failures\": [";
      for (std::size_t k = 0; k < r.failures.size(); ++k) j << (k ? ", " : "") << json_string(r.failures[k]);
      j << "]}" << (i + 1 < runs.size() ? "," : "") << "\n";
    }
    j << "  ],\n  \"goals\": {\"io\": {\"drives\": " << runs[big].drives << ", \"added_p50\": " << add50
      << ", \"added_p99\": " << add99 << ", \"limit\": 10, \"met_p50\": " << (io_met_p50 ? "true" : "false")
      << ", \"met\": " << (io_met ? "true" : "false") << "}, \"sync\": {\"drives\": " << runs[big].drives
      << ", \"sync_p99\": " << fig[big].sync.p99_us << ", \"wakeup_p99\": " << fig[big].wakeup.p99_us
      << ", \"ratio\": " << sync_ratio << ", \"limit\": 1.2, \"met\": " << (sync_met ? "true" : "false")
      << "}}";
    if (e2e_run.ran) {
      j << ",\n  \"e2e\": {\"config\": " << json_string(o.config) << ", \"bus\": " << json_string(e2e_run.bus)
        << ", \"seconds\": " << e2e_seconds << ", \"failure\": " << json_string(e2e_run.failure)
        << ", \"total\": " << json_summary(total) << ", \"to_command\": " << json_summary(to_command)
        << ", \"to_rpdo\": " << json_summary(to_rpdo) << ", \"teleop_cycles\": " << e2e_run.teleop_cycles
        << ", \"matched\": " << e2e_run.matched << ", \"superseded\": " << e2e_run.superseded
        << ", \"ambiguous\": " << e2e_run.ambiguous << ", \"row_changed\": " << e2e_run.row_changed
        << ", \"teleop_age_mean\": " << e2e_run.teleop_age_mean_us
        << ", \"teleop_age_max\": " << e2e_run.teleop_age_max_us
        << ", \"wakeup_p99\": {\"master\": " << e2e_run.master_p99 << ", \"slave\": " << e2e_run.slave_p99
        << ", \"teleop\": " << e2e_run.teleop_p99 << "}, \"sim_overruns\": " << e2e_run.sim_overruns << "}";
    }
    j << "\n}\n";
  }
  bool failed = !e2e_run.failure.empty();
  for (const auto& r : runs) failed = failed || !r.failures.empty();
  return failed ? 1 : 0;
}
