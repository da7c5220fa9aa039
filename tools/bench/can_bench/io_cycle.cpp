#include "io_cycle.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <span>
#include <stdexcept>
#include <thread>

#include "bus_config.hpp"
#include "listener.hpp"
#include "rt_warnings.hpp"
#include "saw/can/bus.hpp"
#include "saw/can/virtual_bus.hpp"
#include "saw/canopen/bus_master.hpp"
#include "saw/canopen/pdo_text.hpp"
#include "saw/canopen/startup.hpp"
#include "saw/manager.hpp"
#include "sim_process.hpp"

namespace saw::bench::can_bench {

using namespace std::chrono_literals;

namespace {

constexpr TimeNs period_ns = 1'000'000;

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

}  // namespace

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

}  // namespace saw::bench::can_bench
