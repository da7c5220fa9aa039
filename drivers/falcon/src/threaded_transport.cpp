#include "saw/drivers/falcon/threaded_transport.hpp"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <cstring>
#include <stdexcept>

#include "saw/clock.hpp"

namespace saw::drivers::falcon {
namespace {

void to_words(const Packet& p, std::uint64_t (&w)[2]) noexcept { std::memcpy(w, p.data(), sizeof w); }
void from_words(const std::uint64_t (&w)[2], Packet& p) noexcept { std::memcpy(p.data(), w, sizeof w); }
static_assert(sizeof(Packet) == 2 * sizeof(std::uint64_t));

// A Falcon answers every exchange within a millisecond: a second of silence is a device that is
// not there, however it still enumerates.
constexpr TimeNs silence_ns = 1'000'000'000;

}  // namespace

void ThreadedTransport::Slot::store(const Packet& p, ExchangeStatus s, std::int32_t e) noexcept {
  const std::uint64_t n = seq.load(std::memory_order_relaxed);  // one writer: this thread's own
  seq.store(n + 1, std::memory_order_relaxed);                  // odd: a store under way
  // Each word is stored with release, so a reader that sees any of them also sees the odd
  // sequence before it (a release store orders the writes before it): no fence needed, which
  // TSan could not check.
  std::uint64_t w[2];
  to_words(p, w);
  words[0].store(w[0], std::memory_order_release);
  words[1].store(w[1], std::memory_order_release);
  status.store(static_cast<std::uint32_t>(s), std::memory_order_release);
  error.store(e, std::memory_order_release);
  seq.store(n + 2, std::memory_order_release);  // even: complete; publishes the words
}

bool ThreadedTransport::Slot::load(Packet& p, ExchangeStatus& s, std::int32_t& e,
                                   std::uint64_t& at) const noexcept {
  const std::uint64_t a = seq.load(std::memory_order_acquire);
  if (a & 1) return false;
  // Acquire loads: the sequence re-read below cannot move before them, and a word from a newer
  // store brings that store's odd sequence with it, so the re-read sees the change.
  std::uint64_t w[2] = {words[0].load(std::memory_order_acquire), words[1].load(std::memory_order_acquire)};
  const auto st = status.load(std::memory_order_acquire);
  const auto er = error.load(std::memory_order_acquire);
  if (seq.load(std::memory_order_relaxed) != a) return false;
  from_words(w, p);
  s = static_cast<ExchangeStatus>(st);
  e = er;
  at = a;
  return true;
}

ThreadedTransport::ThreadedTransport(std::unique_ptr<FalconTransport> inner, int priority, TimeNs poll_ns,
                                     TimeNs reconnect_ns)
    : inner_(std::move(inner)), priority_(priority), poll_ns_(poll_ns), reconnect_ns_(reconnect_ns) {
  if (!inner_) throw std::invalid_argument("ThreadedTransport: no transport");
}

ThreadedTransport::~ThreadedTransport() { close(); }

std::string ThreadedTransport::describe() const { return inner_->describe() + " (I/O thread)"; }

void ThreadedTransport::open() {
  close();
  inner_->open();
  command_.store(encode_command(MotorCommand{}), ExchangeStatus::ok, 0);  // zero force until told
  taken_ = report_.seq.load(std::memory_order_acquire);
  connected_.store(true, std::memory_order_release);
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] { loop(); });
  setup_error_.clear();
  if (priority_ > 0) {
    sched_param sp{};
    sp.sched_priority = priority_;
    if (const int r = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &sp); r != 0)
      setup_error_ = "Falcon I/O thread: SCHED_FIFO " + std::to_string(priority_) + ": " + std::strerror(r);
  }
}

void ThreadedTransport::loop() noexcept {
  std::uint64_t done = 0;  // the command sequence last exchanged
  const timespec nap{0, static_cast<long>(poll_ns_)};
  TimeNs answered = monotonic_now();  // of the last exchange the device answered (or failed)
  while (running_.load(std::memory_order_acquire)) {
    Packet out{}, in{};
    ExchangeStatus unused{};
    std::int32_t e = 0;
    std::uint64_t at = 0;
    if (!command_.load(out, unused, e, at) || at == done) {
      nanosleep(&nap, nullptr);
      continue;
    }
    done = at;
    const ExchangeResult r = inner_->exchange(out, in);
    if (r.status == ExchangeStatus::no_answer) {  // the cycle sees no new report
      if (reconnect_ns_ > 0 && monotonic_now() - answered > silence_ns && reopen()) {
        reopened_.fetch_add(1, std::memory_order_relaxed);
        answered = monotonic_now();
      }
      continue;
    }
    answered = monotonic_now();
    if (r.status == ExchangeStatus::ok && r.bytes < packet_size)
      std::memset(in.data() + r.bytes, 0, packet_size - r.bytes);  // short: the codec refuses it
    // Not connected before the cycle can see the disconnect: its next enable is refused.
    if (r.status == ExchangeStatus::disconnected) connected_.store(false, std::memory_order_release);
    report_.store(in, r.status, r.error);
    // The cycle has the disconnect (its FAULT); until a device is back, it sees no report.
    if (r.status == ExchangeStatus::disconnected && reconnect_ns_ > 0 && reopen()) {
      reopened_.fetch_add(1, std::memory_order_relaxed);
      connected_.store(true, std::memory_order_release);
    }
  }
}

bool ThreadedTransport::reopen() noexcept {
  inner_->close();
  const timespec step{0, 10'000'000};  // close() waits at most this long for the thread
  while (running_.load(std::memory_order_acquire)) {
    for (TimeNs slept = 0; slept < reconnect_ns_ && running_.load(std::memory_order_acquire);
         slept += 10'000'000)
      nanosleep(&step, nullptr);
    if (!running_.load(std::memory_order_acquire)) break;
    try {
      inner_->open();  // finds the device, loads its firmware if it has none running
      return true;
    } catch (...) {  // not there yet (TransportError), or out of memory: tried again
      inner_->close();
    }
  }
  return false;
}

ExchangeResult ThreadedTransport::exchange(const Packet& out, Packet& in) noexcept {
  if (!running_.load(std::memory_order_relaxed)) return {ExchangeStatus::disconnected, 0, 0};
  command_.store(out, ExchangeStatus::ok, 0);
  ExchangeStatus s{};
  std::int32_t e = 0;
  std::uint64_t at = 0;
  Packet p{};
  // Two tries: the thread stores for a few nanoseconds only; losing both is a missed report.
  if (!report_.load(p, s, e, at) && !report_.load(p, s, e, at)) return {ExchangeStatus::no_answer, 0, 0};
  if (at == taken_) return {ExchangeStatus::no_answer, 0, 0};
  taken_ = at;
  in = p;
  return {s, s == ExchangeStatus::ok ? packet_size : 0, e};
}

void ThreadedTransport::close() noexcept {
  connected_.store(false, std::memory_order_release);
  if (running_.exchange(false, std::memory_order_acq_rel) && thread_.joinable()) {
    thread_.join();
    // The thread may have stopped before the cycle's last (zero) command went out: leave the
    // motors unpowered from here.
    Packet in{};
    (void)inner_->exchange(encode_command(MotorCommand{}), in);
  }
  inner_->close();
}

}  // namespace saw::drivers::falcon
