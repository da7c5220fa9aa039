// SpscRing: a bounded single-producer single-consumer ring of fixed-size byte slots.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "saw/cache_line.hpp"

namespace saw {

// The two indices of a ring, each on its own cache line. Standard layout and address-free,
// so it can live in shared memory between processes.
struct SpscRingControl {
  alignas(cache_line) std::atomic<std::uint64_t> head{0};  // written by the producer
  alignas(cache_line) std::atomic<std::uint64_t> tail{0};  // written by the consumer
};

// Lamport's ring with cached indices (each side re-reads the other's index only when it
// looks full or empty). Slot memory is owned by whichever side the indices give it to: the
// producer until the release store of head, the consumer after its acquire load. A ring either
// owns its memory or is a view of memory placed elsewhere (a shared-memory segment); each
// process's view keeps its own cached index.
class SpscRing {
 public:
  static constexpr std::size_t slot_alignment = 16;

  // capacity is rounded up to a power of two; slot_size up to a multiple of 16.
  SpscRing(std::size_t capacity, std::size_t slot_size);
  // A view: `control` and `storage` (capacity × slot_size bytes, 16-aligned) live elsewhere.
  // capacity must be a power of two and slot_size a multiple of 16.
  SpscRing(SpscRingControl* control, std::byte* storage, std::size_t capacity, std::size_t slot_size);
  ~SpscRing();
  static std::size_t round_capacity(std::size_t capacity);
  static std::size_t round_slot_size(std::size_t slot_size) {
    return (slot_size + slot_alignment - 1) / slot_alignment * slot_alignment;
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const noexcept { return mask_ + 1; }
  // A view whose indices were reset by someone else (a shared slot re-claimed): reload them.
  void resync() noexcept {
    cached_tail_ = control_->tail.load(std::memory_order_acquire);
    cached_head_ = control_->head.load(std::memory_order_acquire);
  }
  std::size_t slot_size() const noexcept { return slot_size_; }

  // Producer: a free slot to fill, or nullptr when the ring is full. Publish with commit().
  std::byte* try_reserve() noexcept {
    const auto head = control_->head.load(std::memory_order_relaxed);
    if (head - cached_tail_ > mask_) {
      cached_tail_ = control_->tail.load(std::memory_order_acquire);
      if (head - cached_tail_ > mask_) return nullptr;
    }
    return slot(head);
  }
  void commit() noexcept {
    control_->head.store(control_->head.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Consumer: the oldest filled slot, or nullptr when empty. Release it with pop().
  const std::byte* front() noexcept {
    const auto tail = control_->tail.load(std::memory_order_relaxed);
    if (tail == cached_head_) {
      cached_head_ = control_->head.load(std::memory_order_acquire);
      if (tail == cached_head_) return nullptr;
    }
    return slot(tail);
  }
  void pop() noexcept {
    control_->tail.store(control_->tail.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Approximate fill level, for statistics from any thread.
  std::size_t size_approx() const noexcept {
    return static_cast<std::size_t>(control_->head.load(std::memory_order_acquire) -
                                    control_->tail.load(std::memory_order_acquire));
  }

 private:
  std::byte* slot(std::uint64_t index) const noexcept { return storage_ + (index & mask_) * slot_size_; }

  std::size_t mask_;
  std::size_t slot_size_;
  bool owned_;
  SpscRingControl* control_;
  std::byte* storage_;

  alignas(cache_line) std::uint64_t cached_tail_ = 0;  // producer's copy
  alignas(cache_line) std::uint64_t cached_head_ = 0;  // consumer's copy
};

}  // namespace saw
