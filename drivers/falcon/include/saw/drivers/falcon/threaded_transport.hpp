// ThreadedTransport: another transport's exchanges run in an I/O thread, so the cycle never waits on USB.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "saw/clock.hpp"
#include "saw/drivers/falcon/transport.hpp"

namespace saw::drivers::falcon {

// The cycle's exchange() posts its command and takes the newest report the I/O thread has
// received and not yet handed out (no_answer when there is none): atomics only, no lock, no
// wait, no allocation. The I/O thread exchanges the newest command with the inner transport,
// as fast as it answers and at most every `poll` — a report is one cycle older than inline.
// With `reconnect` set, a device that went away (unplugged) is looked for again by the I/O
// thread every `reconnect` and opened again (enumeration, firmware: the thread may wait and
// allocate there, the cycle never does); the cycle sees no report until then. So is a device that
// answers no exchange for a second (a replug that left it enumerated but silent).
class ThreadedTransport final : public FalconTransport {
 public:
  // priority: SCHED_FIFO priority of the I/O thread (0: the default policy); `poll`: how long
  // the thread sleeps when no new command has come.
  // `reconnect_ns`: 0, a disconnected device stays closed.
  ThreadedTransport(std::unique_ptr<FalconTransport> inner, int priority, TimeNs poll_ns = 100'000,
                    TimeNs reconnect_ns = 0);
  ~ThreadedTransport() override;

  void open() override;
  ExchangeResult exchange(const Packet& out, Packet& in) noexcept override;
  void close() noexcept override;
  std::string describe() const override;
  std::uint64_t reopened() const noexcept override { return reopened_.load(std::memory_order_relaxed); }
  bool connected() const noexcept override { return connected_.load(std::memory_order_acquire); }
  // What the thread could not get (SCHED_FIFO), empty if all; set by open().
  const std::string& setup_error() const noexcept { return setup_error_; }
  FalconTransport& inner() noexcept { return *inner_; }

 private:
  // A 16-byte packet with its status, published by a sequence lock over relaxed atomic words.
  struct Slot {
    std::atomic<std::uint64_t> seq{0};
    std::array<std::atomic<std::uint64_t>, 2> words{};
    std::atomic<std::uint32_t> status{0};
    std::atomic<std::int32_t> error{0};
    void store(const Packet& p, ExchangeStatus s, std::int32_t e) noexcept;
    // The packet of sequence `seq` (even), or false if a store was under way.
    bool load(Packet& p, ExchangeStatus& s, std::int32_t& e, std::uint64_t& at) const noexcept;
  };
  void loop() noexcept;
  // The inner transport closed, then opened again every reconnect_ns_ until it opens (true) or
  // the transport is closed (false).
  bool reopen() noexcept;

  std::unique_ptr<FalconTransport> inner_;
  int priority_;
  TimeNs poll_ns_;
  TimeNs reconnect_ns_;
  std::atomic<std::uint64_t> reopened_{0};
  std::atomic<bool> connected_{false};  // open, and no disconnect since
  std::string setup_error_;
  Slot command_, report_;
  std::uint64_t taken_ = 0;  // the cycle's: the last report sequence handed out
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace saw::drivers::falcon
