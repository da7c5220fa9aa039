#include "saw/detail/spsc_ring.hpp"

#include <bit>
#include <cstdint>
#include <stdexcept>

namespace saw::detail {

std::size_t SpscRing::round_capacity(std::size_t capacity) {
  return std::bit_ceil(capacity < 2 ? std::size_t{2} : capacity);
}

SpscRing::SpscRing(std::size_t capacity, std::size_t slot_size)
    : mask_(round_capacity(capacity) - 1),
      slot_size_(round_slot_size(slot_size)),
      owned_(true),
      owned_control_(new SpscRingControl),
      head_word_(&owned_control_->head),
      tail_word_(&owned_control_->tail),
      storage_(static_cast<std::byte*>(::operator new ((mask_ + 1) * slot_size_, std::align_val_t{64}))) {
  if (slot_size == 0) throw std::invalid_argument("SpscRing: slot size must not be zero");
}

SpscRing::SpscRing(std::atomic<std::uint64_t>* head, std::atomic<std::uint64_t>* tail, std::byte* storage,
                   std::size_t capacity, std::size_t slot_size)
    : mask_(capacity - 1),
      slot_size_(slot_size),
      owned_(false),
      head_word_(head),
      tail_word_(tail),
      storage_(storage) {
  if (capacity < 2 || !std::has_single_bit(capacity) || slot_size == 0 || slot_size % slot_alignment != 0 ||
      reinterpret_cast<std::uintptr_t>(storage) % slot_alignment != 0)
    throw std::invalid_argument(
        "SpscRing view: capacity must be a power of two, slots 16-aligned multiples of 16");
  // The indices may already be in use (a process re-attaching): start from where they are.
  resync();
}

SpscRing::~SpscRing() {
  if (!owned_) return;
  ::operator delete (storage_, std::align_val_t{64});
  delete owned_control_;
}

}  // namespace saw::detail
