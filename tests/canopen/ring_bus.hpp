// An in-memory CAN network for the RT tests: fixed rings per port (no allocation after set-up) and
// a bus state the test sets. One thread: the test steps every port itself.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"

namespace saw::canopen::test {

class RingNetwork;

class RingPort final : public can::Bus {
 public:
  RingPort(RingNetwork& network, std::string name, std::size_t capacity)
      : network_(network), name_(std::move(name)), ring_(capacity) {}

  std::size_t receive(std::span<can::Received> out) noexcept override {
    std::size_t n = 0;
    while (n < out.size() && head_ != tail_) {
      out[n++] = ring_[tail_ % ring_.size()];
      ++tail_;
    }
    counters_.received += n;
    return n;
  }
  std::size_t send(std::span<const can::Frame> frames) noexcept override;
  can::BusState state() const noexcept override;
  can::BusCounters counters() const noexcept override { return counters_; }
  const std::string& name() const noexcept override { return name_; }

  TimeNs now = 0;  // stamped on frames this port sends
  std::uint64_t sent_frames = 0;

 private:
  friend class RingNetwork;
  void push(const can::Frame& f, TimeNs t) noexcept {
    if (head_ - tail_ == ring_.size()) {
      ++counters_.overruns;
      return;
    }
    ring_[head_ % ring_.size()] = {f, t};
    ++head_;
  }

  RingNetwork& network_;
  std::string name_;
  std::vector<can::Received> ring_;
  std::size_t head_ = 0, tail_ = 0;
  can::BusCounters counters_;
};

class RingNetwork {
 public:
  explicit RingNetwork(std::size_t ring = 1024) : ring_(ring) {}
  RingPort& attach(std::string name) {
    ports_.push_back(std::make_unique<RingPort>(*this, std::move(name), ring_));
    return *ports_.back();
  }
  // What every port reports; bus_off and down make send() refuse everything.
  can::BusState state = can::BusState::error_active;
  // Frames sent by any port, oldest first, while `record` is set (allocates: not in a guarded cycle).
  bool record = false;
  std::vector<can::Frame> log;

 private:
  friend class RingPort;
  std::size_t ring_;
  std::vector<std::unique_ptr<RingPort>> ports_;
};

inline can::BusState RingPort::state() const noexcept { return network_.state; }

inline std::size_t RingPort::send(std::span<const can::Frame> frames) noexcept {
  if (network_.state == can::BusState::bus_off || network_.state == can::BusState::down) {
    counters_.send_refused += frames.size();
    return 0;
  }
  for (const can::Frame& f : frames) {
    for (auto& p : network_.ports_)
      if (p.get() != this) p->push(f, now);
    if (network_.record) network_.log.push_back(f);
  }
  counters_.sent += frames.size();
  sent_frames += frames.size();
  return frames.size();
}

}  // namespace saw::canopen::test
