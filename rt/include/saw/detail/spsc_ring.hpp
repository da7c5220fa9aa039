// SpscRing: a bounded single-producer single-consumer ring of fixed-size byte slots (internal).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "saw/cache_line.hpp"

namespace saw::detail {

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
//
// Each side keeps its own index in private memory and only publishes it: a peer in another
// process that overwrites it cannot make this side replay or skip slots. The peer's index is
// checked before use: one that is more than a ring ahead of ours (or behind it) is corrupt —
// the producer then sees a full ring, the consumer an empty one, resynced to the peer's index
// so a live peer recovers — and counted in corrupt_count().
class SpscRing {
 public:
  static constexpr std::size_t slot_alignment = 16;

  // capacity is rounded up to a power of two; slot_size up to a multiple of 16.
  SpscRing(std::size_t capacity, std::size_t slot_size);
  // A view: `control` and `storage` (capacity × slot_size bytes, 16-aligned) live elsewhere.
  // capacity must be a power of two and slot_size a multiple of 16.
  SpscRing(SpscRingControl* control, std::byte* storage, std::size_t capacity, std::size_t slot_size)
      : SpscRing(&control->head, &control->tail, storage, capacity, slot_size) {}
  // A view whose two indices live apart (each on the page its writer may write).
  SpscRing(std::atomic<std::uint64_t>* head, std::atomic<std::uint64_t>* tail, std::byte* storage,
           std::size_t capacity, std::size_t slot_size);
  ~SpscRing();
  static std::size_t round_capacity(std::size_t capacity);
  static std::size_t round_slot_size(std::size_t slot_size) {
    return (slot_size + slot_alignment - 1) / slot_alignment * slot_alignment;
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const noexcept { return mask_ + 1; }
  // A view taken over from someone else (a reconnect, a re-claimed slot): reload both indices.
  void resync() noexcept {
    head_ = cached_head_ = head_word_->load(std::memory_order_acquire);
    tail_ = cached_tail_ = tail_word_->load(std::memory_order_acquire);
  }
  std::size_t slot_size() const noexcept { return slot_size_; }

  // Producer: a free slot to fill, or nullptr when the ring is full. Publish with commit().
  std::byte* try_reserve() noexcept {
    if (head_ - cached_tail_ > mask_) {
      cached_tail_ = tail_word_->load(std::memory_order_acquire);
      const std::uint64_t used = head_ - cached_tail_;
      if (used > mask_ + 1) {  // a consumer "ahead" of us, or far behind: not a count we published
        corrupt_.store(corrupt_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        cached_tail_ = head_ - (mask_ + 1);  // full until the consumer publishes a sane index
        return nullptr;
      }
      if (used > mask_) return nullptr;
    }
    return slot(head_);
  }
  void commit() noexcept { head_word_->store(++head_, std::memory_order_release); }

  // Consumer: the oldest filled slot, or nullptr when empty. Release it with pop().
  const std::byte* front() noexcept {
    if (tail_ == cached_head_) {
      cached_head_ = head_word_->load(std::memory_order_acquire);
      if (tail_ == cached_head_) return nullptr;
      if (cached_head_ - tail_ > mask_ + 1) {  // more than a ring's worth: not a producer's count
        corrupt_.store(corrupt_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        tail_ = cached_head_;  // drop it all; a live producer goes on from its own index
        tail_word_->store(tail_, std::memory_order_release);
        return nullptr;
      }
    }
    return slot(tail_);
  }
  void pop() noexcept { tail_word_->store(++tail_, std::memory_order_release); }

  // Approximate fill level, for statistics from any thread.
  std::size_t size_approx() const noexcept {
    return static_cast<std::size_t>(head_word_->load(std::memory_order_acquire) -
                                    tail_word_->load(std::memory_order_acquire));
  }
  // Times the peer's index was out of range (written by this view's user thread only).
  std::uint64_t corrupt_count() const noexcept { return corrupt_.load(std::memory_order_relaxed); }

 private:
  std::byte* slot(std::uint64_t index) const noexcept { return storage_ + (index & mask_) * slot_size_; }

  std::size_t mask_;
  std::size_t slot_size_;
  bool owned_;
  SpscRingControl* owned_control_ = nullptr;
  std::atomic<std::uint64_t>* head_word_;
  std::atomic<std::uint64_t>* tail_word_;
  std::byte* storage_;
  std::atomic<std::uint64_t> corrupt_{0};

  alignas(cache_line) std::uint64_t head_ = 0;  // producer's own index
  std::uint64_t cached_tail_ = 0;               // producer's copy of the consumer's
  alignas(cache_line) std::uint64_t tail_ = 0;  // consumer's own index
  std::uint64_t cached_head_ = 0;               // consumer's copy of the producer's
};

}  // namespace saw::detail
