#include "listener.hpp"

#include <chrono>

#include "bus_config.hpp"
#include "saw/canopen/cob.hpp"
#include "saw/rt_thread.hpp"

namespace saw::bench::can_bench {

using namespace std::chrono_literals;

Listener::Listener(const std::string& uri, std::uint32_t rpdo_id, std::size_t capacity, int cpu)
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

void Listener::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

}  // namespace saw::bench::can_bench
