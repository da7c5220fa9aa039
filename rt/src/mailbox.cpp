#include "saw/detail/mailbox.hpp"

namespace saw::detail {

Mailbox::Mailbox(std::string name, std::size_t capacity, std::size_t max_payload)
    : name_(std::move(name)), own_(capacity, header_size + max_payload) {}

Mailbox::Mailbox(std::string name, SpscRingControl* control, std::byte* storage, std::size_t capacity,
                 std::size_t slot_size)
    : name_(std::move(name)), own_(control, storage, capacity, slot_size) {}

Mailbox::Mailbox(std::string name, std::atomic<std::uint64_t>* head, std::atomic<std::uint64_t>* tail,
                 std::byte* storage, std::size_t capacity, std::size_t slot_size)
    : name_(std::move(name)), own_(head, tail, storage, capacity, slot_size) {}

void Mailbox::set_target(std::uint32_t index, Invoker target) {
  if (index >= targets_.size()) targets_.resize(index + 1, Invoker{[](void*, const void*) {}, nullptr});
  targets_[index] = target;
}

std::uint32_t Mailbox::add_target(Invoker target) {
  targets_.push_back(target);
  return static_cast<std::uint32_t>(targets_.size() - 1);
}

std::size_t Mailbox::drain() noexcept {
  // Bounded: calls queued while draining wait for the next cycle, so a chatty producer
  // cannot keep the consumer here forever.
  if (offered_.load(std::memory_order_relaxed) != nullptr) {
    ring_ = offered_.load(std::memory_order_acquire);
    ring_->resync();
    offered_.store(nullptr, std::memory_order_release);  // the offerer may now retire the old ring
  }
  const std::size_t limit = ring_->capacity();
  std::size_t n = 0;
  while (n < limit) {
    const std::byte* slot = ring_->front();
    if (slot == nullptr) break;
    std::uint32_t target = 0;
    std::memcpy(&target, slot, sizeof target);
    if (target < targets_.size())
      targets_[target](slot + header_size);  // (the index may come from another process)
    ring_->pop();
    ++n;
  }
  if (n != 0) executed_.store(executed_.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
  return n;
}

}  // namespace saw::detail
