// saw-bench-shm: round trips between two processes over shared memory — the floors for the
// bridge: a bare futex ping-pong, a spinning atomic ping-pong, and the bridge's own
// command ring + event ring (spinning, and sleeping on a futex), measured in one run.
#include <linux/futex.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstring>

#include "ping_pong.hpp"
#include "saw/bridge/layout.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/clock.hpp"
#include "saw/rt_thread.hpp"
#include "stats.hpp"

namespace {

using saw::TimeNs;

// Two words in a shared anonymous mapping: ping (parent → child) and pong (child → parent).
struct PingPong {
  alignas(64) std::atomic<std::uint32_t> ping{0};
  alignas(64) std::atomic<std::uint32_t> pong{0};
};

template <class Child, class Parent>
std::vector<std::int64_t> two_processes(int n, int cpu_parent, int cpu_child, Child child, Parent parent) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (cpu_child >= 0) (void)saw::rt::set_affinity(cpu_child);
    child(n);
    _exit(0);
  }
  if (cpu_parent >= 0) (void)saw::rt::set_affinity(cpu_parent);
  std::vector<std::int64_t> samples(static_cast<std::size_t>(n));
  parent(n, samples);
  waitpid(pid, nullptr, 0);
  return samples;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-bench-shm: shared-memory round trips between two processes"};
  int n = 10000, reps = 5;
  bool markdown = false;
  app.add_option("--calls", n, "round trips per repetition");
  app.add_option("--reps", reps, "repetitions");
  app.add_flag("--markdown", markdown, "Markdown table");
  CLI11_PARSE(app, argc, argv);
  // As saw-rt does while it runs: keep CPUs out of deep idle states, or every wake-up pays for it.
  saw::rt::DmaLatencyHold dma;
  if (!dma.error().empty()) std::printf("# warning: %s\n", dma.error().c_str());
  const int ncpu = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  const int cpu_a = ncpu > 1 ? 0 : -1, cpu_b = ncpu > 1 ? 1 : -1;
  if (cpu_a >= 0) (void)saw::rt::set_affinity(cpu_a);  // the ping-pongs' parent side
  std::printf("# saw-bench-shm: %d × %d round trips between two processes on CPUs %d and %d\n", reps, n,
              cpu_a, cpu_b);

  auto* pp = static_cast<PingPong*>(
      mmap(nullptr, sizeof(PingPong), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0));
  std::vector<std::int64_t> futex_all, spin_all, ring_spin_all, ring_futex_all;

  // The bridge segment: one slot; commands carry a sequence number, events echo it back.
  saw::bridge::LayoutParams params;
  params.mirror_bytes = 8;
  params.slot_count = 1;
  params.ring_capacity = 64;
  params.command_payload = params.event_payload = 16;
  saw::bridge::Layout layout;
  (void)saw::bridge::Layout::compute(params, layout);
  auto seg =
      saw::bridge::ShmSegment::create("/saw.bench." + std::to_string(getpid()), layout.total_size, nullptr);
  const saw::bridge::SegmentView view(seg.data(), layout);
  saw::bridge::initialize(view, "bench", "p", 0, getpid());
  (void)saw::bridge::claim_slot(view, 1, getpid(), saw::monotonic_now());

  for (int r = 0; r < reps; ++r) {
    auto futex = saw::bench::futex_ping_pong(n, cpu_b);
    auto spin = saw::bench::spin_ping_pong(n, cpu_b);
    // The bridge's rings: the parent (client) pushes a command, the child (server) answers with
    // an event. Spinning first, then sleeping on the futex words beside the rings.
    for (bool sleep : {false, true}) {
      new (pp) PingPong{};
      auto rings = two_processes(
          n, cpu_a, cpu_b,
          [&](int count) {
            auto in = saw::bridge::command_ring(view, 0);
            auto out = saw::bridge::event_ring(view, 0);
            for (int i = 0; i < count; ++i) {
              // Eventcount: read the futex word before looking at the ring, so a command that
              // lands in between changes the word and the wait returns at once.
              const std::byte* s;
              for (;;) {
                const auto seen = pp->ping.load(std::memory_order_acquire);
                if ((s = in.front()) != nullptr) break;
                if (sleep) saw::bridge::futex_wait(pp->ping, seen, 0);
              }
              std::uint64_t v;
              std::memcpy(&v, s, sizeof v);
              in.pop();
              std::byte* e;
              while ((e = out.try_reserve()) == nullptr) {
              }
              std::memcpy(e, &v, sizeof v);
              out.commit();
              if (sleep) {
                pp->pong.fetch_add(1, std::memory_order_release);
                saw::bridge::futex_wake_all(pp->pong);
              }
            }
          },
          [&](int count, std::vector<std::int64_t>& samples) {
            auto out = saw::bridge::command_ring(view, 0);
            auto in = saw::bridge::event_ring(view, 0);
            for (int i = 0; i < count; ++i) {
              const TimeNs t0 = saw::monotonic_now();
              std::byte* c;
              while ((c = out.try_reserve()) == nullptr) {
              }
              const auto v = static_cast<std::uint64_t>(i);
              std::memcpy(c, &v, sizeof v);
              out.commit();
              if (sleep) {
                pp->ping.fetch_add(1, std::memory_order_release);
                saw::bridge::futex_wake_all(pp->ping);
              }
              const std::byte* e;
              for (;;) {
                const auto seen = pp->pong.load(std::memory_order_acquire);
                if ((e = in.front()) != nullptr) break;
                if (sleep) saw::bridge::futex_wait(pp->pong, seen, 0);
              }
              in.pop();
              samples[static_cast<std::size_t>(i)] = saw::monotonic_now() - t0;
            }
          });
      (sleep ? ring_futex_all : ring_spin_all)
          .insert((sleep ? ring_futex_all : ring_spin_all).end(), rings.begin(), rings.end());
    }
    futex_all.insert(futex_all.end(), futex.begin(), futex.end());
    spin_all.insert(spin_all.end(), spin.begin(), spin.end());
  }
  saw::bench::print_header(markdown);
  saw::bench::print_row(markdown, "bare futex ping-pong (round trip)", saw::bench::summarize(futex_all));
  saw::bench::print_row(markdown, "shared atomic spin ping-pong (round trip)",
                        saw::bench::summarize(spin_all));
  saw::bench::print_row(markdown, "bridge rings, spinning (command + event)",
                        saw::bench::summarize(ring_spin_all));
  saw::bench::print_row(markdown, "bridge rings, futex sleep (command + event)",
                        saw::bench::summarize(ring_futex_all));
  return 0;
}
