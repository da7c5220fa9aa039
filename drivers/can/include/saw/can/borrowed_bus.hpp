// A bus that forwards to one the caller owns: for what takes ownership of its bus (a BusTask, a
// component alone on its bus) given one that lives elsewhere (a test's in-memory port).
#pragma once

#include <span>
#include <string>

#include "saw/can/bus.hpp"

namespace saw::can {

class BorrowedBus final : public Bus {
 public:
  explicit BorrowedBus(Bus& b) noexcept : b_(b) {}
  std::size_t receive(std::span<Received> out) noexcept override { return b_.receive(out); }
  std::size_t send(std::span<const Frame> f) noexcept override { return b_.send(f); }
  BusState state() const noexcept override { return b_.state(); }
  BusCounters counters() const noexcept override { return b_.counters(); }
  const std::string& name() const noexcept override { return b_.name(); }

 private:
  Bus& b_;
};

}  // namespace saw::can
