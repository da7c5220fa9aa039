// Mailbox: one connection's bounded queue of commands or events, drained by its consumer (internal).
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "saw/detail/invoker.hpp"
#include "saw/detail/spsc_ring.hpp"
#include "saw/status.hpp"

namespace saw::detail {

// The producer is the thread of the calling component (commands) or of the emitting
// component (events); the consumer is the thread of the component that executes them.
class Mailbox {
 public:
  Mailbox(std::string name, std::size_t capacity, std::size_t max_payload);
  // Over a ring placed elsewhere (shared memory); see SpscRing's view constructor.
  Mailbox(std::string name, SpscRingControl* control, std::byte* storage, std::size_t capacity,
          std::size_t slot_size);
  Mailbox(std::string name, std::atomic<std::uint64_t>* head, std::atomic<std::uint64_t>* tail,
          std::byte* storage, std::size_t capacity, std::size_t slot_size);
  static constexpr std::size_t header_bytes() { return header_size; }

  const std::string& name() const noexcept { return name_; }

  // Setup: adds a call target and returns its index in this mailbox.
  std::uint32_t add_target(Invoker target);
  // Setup: replaces the call target at `index` (for targets numbered by someone else).
  void set_target(std::uint32_t index, Invoker target);
  std::size_t target_count() const noexcept { return targets_.size(); }

  // Setup: a component drains this mailbox (set when it becomes one's inbound mailbox).
  void set_consumer_attached() noexcept { consumer_attached_.store(true, std::memory_order_release); }
  bool consumer_attached() const noexcept { return consumer_attached_.load(std::memory_order_acquire); }

  // Non-RT, for a mailbox whose producer is another process (a reconnected server): hands the
  // consumer a ring to switch to at the start of its next drain(). Returns false while an
  // earlier offer is still pending. The caller keeps `ring` (and its memory) alive as long as
  // the consumer may use it: until a later offer has been taken, or the mailbox is destroyed.
  bool offer_ring(SpscRing* ring) noexcept {
    SpscRing* expected = nullptr;
    return offered_.compare_exchange_strong(expected, ring, std::memory_order_acq_rel);
  }
  // False once the consumer has switched: from then on it never touches the previous ring.
  bool offer_pending() const noexcept { return offered_.load(std::memory_order_acquire) != nullptr; }

  // Producer side. Never blocks: a full mailbox is an error, counted.
  Status push(std::uint32_t target, const void* payload, std::size_t size) noexcept {
    std::byte* slot = ring_->try_reserve();
    if (slot == nullptr) {
      full_count_.store(full_count_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      return Status::queue_full;
    }
    std::memcpy(slot, &target, sizeof target);
    if (size != 0) std::memcpy(slot + header_size, payload, size);
    ring_->commit();
    return Status::ok;
  }

  // Consumer side: runs every queued call (at most one ring's worth); returns how many.
  std::size_t drain() noexcept;

  std::uint64_t full_count() const noexcept { return full_count_.load(std::memory_order_relaxed); }
  std::uint64_t executed_count() const noexcept { return executed_.load(std::memory_order_relaxed); }
  // From the consumer's thread, or any thread for a mailbox that is never offered a ring.
  std::size_t capacity() const noexcept { return ring_->capacity(); }
  std::size_t pending() const noexcept { return ring_->size_approx(); }

 private:
  static constexpr std::size_t header_size = SpscRing::slot_alignment;

  std::string name_;
  SpscRing own_;
  SpscRing* ring_ = &own_;  // the consumer's; switched by drain() when a ring is offered
  std::atomic<SpscRing*> offered_{nullptr};
  std::atomic<bool> consumer_attached_{false};
  std::vector<Invoker> targets_;
  std::atomic<std::uint64_t> full_count_{0};  // written by the producer only
  std::atomic<std::uint64_t> executed_{0};    // written by the consumer only
};

}  // namespace saw::detail
