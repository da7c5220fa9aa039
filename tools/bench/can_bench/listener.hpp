// A listener: another attachment to the bus, keeping the bus's stamps of what it wants.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/clock.hpp"

namespace saw::bench::can_bench {

class Listener {
 public:
  // Keeps the bus's stamps of every SYNC and of the frames with identifier `rpdo_id` (0: none).
  Listener(const std::string& uri, std::uint32_t rpdo_id, std::size_t capacity, int cpu);
  ~Listener() { stop(); }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;
  void stop();
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

}  // namespace saw::bench::can_bench
