// An in-memory CAN bus for the CANopen tests: every frame one port sends, every other port receives.
#pragma once

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"

namespace saw::canopen::fake {

class FakeNetwork;

// One node's connection to a FakeNetwork, behind the same seam as a real bus.
class FakeBus final : public can::Bus {
 public:
  FakeBus(FakeNetwork& network, std::string name) : network_(network), name_(std::move(name)) {}
  std::size_t receive(std::span<can::Received> out) noexcept override {
    std::size_t n = 0;
    while (n < out.size() && !inbox_.empty()) {
      out[n++] = inbox_.front();
      inbox_.pop_front();
    }
    counters_.received += n;
    return n;
  }
  std::size_t send(std::span<const can::Frame> frames) noexcept override;
  can::BusState state() const noexcept override { return can::BusState::error_active; }
  can::BusCounters counters() const noexcept override { return counters_; }
  const std::string& name() const noexcept override { return name_; }

  // Everything this port sent, oldest first (tests inspect the frames themselves).
  std::vector<can::Frame> sent;
  TimeNs now = 0;  // the time stamped on frames this port sends

 private:
  friend class FakeNetwork;
  FakeNetwork& network_;
  std::string name_;
  std::deque<can::Received> inbox_;
  can::BusCounters counters_;
};

class FakeNetwork {
 public:
  FakeBus& attach(std::string name) {
    ports_.push_back(std::make_unique<FakeBus>(*this, std::move(name)));
    return *ports_.back();
  }
  void deliver(const FakeBus& from, const can::Frame& f, TimeNs t) {
    for (auto& p : ports_)
      if (p.get() != &from) p->inbox_.push_back({f, t});
  }

 private:
  std::vector<std::unique_ptr<FakeBus>> ports_;
};

inline std::size_t FakeBus::send(std::span<const can::Frame> frames) noexcept {
  for (const auto& f : frames) {
    sent.push_back(f);
    network_.deliver(*this, f, now);
  }
  counters_.sent += frames.size();
  return frames.size();
}

// Moves frames between protocol objects through their buses: each object's poll() output is
// sent on its port, and each port's received frames go to its object's on_frame(). Runs until
// nothing moves (returns the rounds it took).
template <class... Endpoint>
int exchange(TimeNs now, Endpoint... ends) {
  int rounds = 0;
  for (bool moved = true; moved && rounds < 10000; ++rounds) {
    moved = false;
    const auto step = [&](auto& end) {
      end.bus.now = now;
      while (auto f = end.object.poll(now)) {
        end.bus.send(std::span(&*f, 1));
        moved = true;
      }
      can::Received r[16];
      for (std::size_t n; (n = end.bus.receive(r)) > 0; moved = true)
        for (std::size_t i = 0; i < n; ++i) end.object.on_frame(r[i].frame, r[i].time);
    };
    (step(ends), ...);
  }
  return rounds;
}

template <class Object>
struct Endpoint {
  Object& object;
  FakeBus& bus;
};

}  // namespace saw::canopen::fake
