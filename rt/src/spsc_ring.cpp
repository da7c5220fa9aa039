#include "saw/spsc_ring.hpp"

#include <bit>
#include <stdexcept>

namespace saw {

SpscRing::SpscRing(std::size_t capacity, std::size_t slot_size)
    : mask_(std::bit_ceil(capacity < 2 ? std::size_t{2} : capacity) - 1),
      slot_size_((slot_size + slot_alignment - 1) / slot_alignment * slot_alignment),
      storage_(static_cast<std::byte*>(
          ::operator new((mask_ + 1) * slot_size_, std::align_val_t{64}))) {
  if (slot_size == 0) throw std::invalid_argument("SpscRing: slot size must not be zero");
}

SpscRing::~SpscRing() { ::operator delete(storage_, std::align_val_t{64}); }

}  // namespace saw
