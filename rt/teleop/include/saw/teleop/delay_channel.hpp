// DelayChannel: one direction of a simulated network link — delay, jitter and loss — for samples of T.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "saw/clock.hpp"

namespace saw::teleop {

// What a link does to each sample: it arrives `delay` plus a uniform [0, jitter] later, unless it
// is lost (probability `loss`). Each sample's fate is a function of `seed` and its sequence
// number only, so a run is repeatable.
struct LinkConfig {
  TimeNs delay = 0;
  TimeNs jitter = 0;
  double loss = 0;  // 0 ≤ loss < 1
  std::uint64_t seed = 1;
};

// The receiving end keeps the newest sample that has arrived (by send order: a sample overtaken
// by a newer one on the way is dropped on arrival, as a receiver that checks sequence numbers
// does). Capacity is fixed at construction; send() and receive() neither allocate nor block.
template <class T>
class DelayChannel {
 public:
  DelayChannel(LinkConfig link, TimeNs period) : link_(link) {
    if (period <= 0) throw std::invalid_argument("a delay channel needs a period");
    if (link.delay < 0 || link.jitter < 0)
      throw std::invalid_argument("delay and jitter must not be negative");
    if (!(link.loss >= 0 && link.loss < 1)) throw std::invalid_argument("loss must be in [0, 1)");
    // Every sample still on the way: sent within the last delay + jitter, one per period, and margin.
    ring_.resize(static_cast<std::size_t>((link.delay + link.jitter) / period) + 8);
  }

  // Puts a sample on the link at `now`. With more in flight than the capacity (a sender faster
  // than its period) the oldest in flight is overwritten: counted, never a stall.
  void send(TimeNs now, const T& value) noexcept {
    const std::uint64_t n = sent_++;
    const std::uint64_t r1 = mix(link_.seed ^ (n * 0x9e3779b97f4a7c15ULL));
    const std::uint64_t r2 = mix(r1);
    if (unit(r2) < link_.loss) {
      ++lost_;
      return;
    }
    const auto extra = static_cast<TimeNs>(unit(r1) * static_cast<double>(link_.jitter));
    Slot& s = ring_[head_ % ring_.size()];
    if (head_ - tail_ == ring_.size()) {
      ++overwritten_;
      ++tail_;
    }
    s = Slot{n, now + link_.delay + extra, now + link_.delay, value};
    ++head_;
  }

  // The newest sample that has arrived by `now` and is newer than the last one received: true
  // and `out` set, or false (nothing new: the receiver holds what it has).
  bool receive(TimeNs now, T& out) noexcept {
    bool got = false;
    // In flight in send order; arrival times are not in order (jitter), so each that may have
    // arrived is looked at. Once a sample's send time plus delay is past `now`, none sent after it
    // can have arrived (sent no earlier, it arrives no earlier): the scan stops there, and covers
    // the jitter window from the oldest sample not yet delivered, not every sample in flight.
    for (std::uint64_t i = tail_; i < head_; ++i) {
      Slot& s = ring_[i % ring_.size()];
      if (s.earliest > now) break;
      ++scanned_;
      if (s.arrival == kDelivered || s.arrival > now) continue;
      if (!have_ || s.sequence > last_) {
        out = s.value;  // the newest arrived so far (later ones in the loop are newer still)
        last_ = s.sequence;
        have_ = got = true;
      } else {
        ++late_;  // arrived after a newer one: too late to matter
      }
      s.arrival = kDelivered;
    }
    while (tail_ < head_ && ring_[tail_ % ring_.size()].arrival == kDelivered) ++tail_;
    return got;
  }

  std::uint64_t sent() const noexcept { return sent_; }
  std::uint64_t lost() const noexcept { return lost_; }
  std::uint64_t late() const noexcept { return late_; }
  std::uint64_t overwritten() const noexcept { return overwritten_; }
  // Slots receive() has looked at, in all: its cost (bounded per call by the jitter window).
  std::uint64_t scanned() const noexcept { return scanned_; }
  const LinkConfig& link() const noexcept { return link_; }

 private:
  static constexpr TimeNs kDelivered = -1;
  struct Slot {
    std::uint64_t sequence = 0;
    TimeNs arrival = kDelivered;
    TimeNs earliest = 0;  // sent + delay: no sample sent after this one arrives before it
    T value{};
  };
  // splitmix64's finaliser: a well-mixed 64-bit value from any input.
  static std::uint64_t mix(std::uint64_t z) noexcept {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  static double unit(std::uint64_t r) noexcept { return static_cast<double>(r >> 11) * 0x1.0p-53; }

  LinkConfig link_;
  std::vector<Slot> ring_;
  std::uint64_t head_ = 0, tail_ = 0;  // sequence of slots: [tail_, head_) in flight or delivered
  std::uint64_t sent_ = 0, lost_ = 0, late_ = 0, overwritten_ = 0, scanned_ = 0;
  std::uint64_t last_ = 0;
  bool have_ = false;
};

}  // namespace saw::teleop
