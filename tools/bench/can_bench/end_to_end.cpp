#include "end_to_end.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "listener.hpp"
#include "rt_warnings.hpp"
#include "saw/can/virtual_bus.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/canopen/registration.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/drivers/sim_registration.hpp"
#include "saw/teleop/registration.hpp"
#include "saw/teleop/teleoperation.hpp"
#include "sim_process.hpp"

namespace saw::bench::can_bench {

using namespace std::chrono_literals;

namespace {

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

}  // namespace

const saw::RtCycleObserver cycle_observer{&on_cycle_begin, &on_cycle_end};

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

}  // namespace saw::bench::can_bench
