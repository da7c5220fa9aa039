#include "saw/canopen/sdo_queue.hpp"

#include <chrono>
#include <cstring>
#include <thread>

namespace saw::canopen {

SdoQueue::SdoQueue(std::size_t capacity)
    : requests_(capacity, sizeof(SdoRequest)), replies_(capacity, sizeof(SdoReply)) {}

Status SdoQueue::submit(const SdoRequest& request) noexcept {
  std::byte* slot = requests_.try_reserve();
  if (slot == nullptr) {
    refused_.fetch_add(1, std::memory_order_relaxed);
    return Status::queue_full;
  }
  std::memcpy(slot, &request, sizeof request);
  requests_.commit();
  return Status::ok;
}

bool SdoQueue::take_reply(SdoReply& out) noexcept {
  const std::byte* slot = replies_.front();
  if (slot == nullptr) return false;
  std::memcpy(&out, slot, sizeof out);
  replies_.pop();
  return true;
}

bool SdoQueue::reply(const SdoReply& r) noexcept {
  std::byte* slot = replies_.try_reserve();
  if (slot == nullptr) {
    lost_.store(lost_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    return false;
  }
  std::memcpy(slot, &r, sizeof r);
  replies_.commit();
  return true;
}

SdoReply SdoQueue::transfer(SdoRequest request, TimeNs timeout) {
  const std::lock_guard lock(callers_);
  request.tag = next_tag_++;
  SdoReply out;
  out.tag = request.tag;
  if ((out.status = submit(request)) != Status::ok) return out;
  const TimeNs deadline = monotonic_now() + timeout;
  while (true) {
    SdoReply r;
    while (take_reply(r))
      if (r.tag == request.tag) return r;  // others: late replies to callers that gave up
    if (monotonic_now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  out.status = Status::timeout;
  return out;
}

}  // namespace saw::canopen
