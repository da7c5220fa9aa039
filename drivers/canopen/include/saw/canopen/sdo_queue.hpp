// Runtime SDO transfers: asked by non-RT code, run by the RT cycle, through two bounded lock-free rings.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string_view>
#include <tuple>

#include "saw/clock.hpp"
#include "saw/detail/spsc_ring.hpp"
#include "saw/status.hpp"

namespace saw::canopen {

// An SDO upload (read) or download (write) of one object of one drive on the bus.
struct SdoRequest {
  static constexpr std::string_view type_name = "saw::canopen::SdoRequest";
  static constexpr std::uint32_t layout_version = 1;
  std::uint32_t tag = 0;  // the caller's; echoed in the reply (transfer() sets it)
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  std::uint8_t node = 0;
  bool write = false;     // download data[0..size), else upload
  std::uint8_t size = 0;  // download: 1..8 bytes
  std::array<std::uint8_t, 8> data{};
  static constexpr auto fields =
      std::tuple{&SdoRequest::tag,   &SdoRequest::index, &SdoRequest::subindex, &SdoRequest::node,
                 &SdoRequest::write, &SdoRequest::size,  &SdoRequest::data};
};
static_assert(sizeof(SdoRequest) == 20);

struct SdoReply {
  static constexpr std::string_view type_name = "saw::canopen::SdoReply";
  static constexpr std::uint32_t layout_version = 1;
  std::uint32_t tag = 0;
  // ok: the transfer ran (abort says how it ended); queue_full: the request queue was full and
  // nothing was asked; invalid: no drive with that node on this bus, or a bad size; timeout:
  // the caller stopped waiting (the transfer may still complete; its reply is then dropped).
  Status status = Status::ok;
  bool remote = false;      // the drive aborted (else this master did: a timeout, a bad response)
  std::uint8_t size = 0;    // upload: bytes in data
  std::uint32_t abort = 0;  // SdoAbort code; 0: the transfer completed
  std::uint32_t total = 0;  // upload: the object's size (above 8, data holds its first 8 bytes)
  std::array<std::uint8_t, 8> data{};
  static constexpr auto fields =
      std::tuple{&SdoReply::tag,   &SdoReply::status, &SdoReply::remote, &SdoReply::size,
                 &SdoReply::abort, &SdoReply::total,  &SdoReply::data};
  bool ok() const noexcept { return status == Status::ok && abort == 0; }
};
static_assert(sizeof(SdoReply) == 24);

// Requests flow from non-RT callers to the RT cycle and replies back, each through an SpscRing
// (its own memory orders: the slot is published by the producer's release store of its index
// and taken by the consumer's acquire load). The RT side never blocks, allocates or locks; a
// full ring is an error returned and counted, never a wait.
class SdoQueue {
 public:
  explicit SdoQueue(std::size_t capacity = 16);

  // --- the non-RT side -------------------------------------------------------------------
  // One request; queue_full (counted in refused()) when the ring is full. For a single caller
  // thread that also takes the replies; transfer() is the way for several.
  Status submit(const SdoRequest& request) noexcept;
  // The oldest reply, if any.
  bool take_reply(SdoReply& out) noexcept;
  // Submits with a fresh tag and waits (polling every 100 µs) up to `timeout` for its reply;
  // replies to requests whose callers gave up are dropped on the way. Any thread; callers are
  // serialised by a mutex that the RT side never touches.
  SdoReply transfer(SdoRequest request, TimeNs timeout);

  // --- the RT side -----------------------------------------------------------------------
  // The oldest request, or nullptr; pop() once it is taken.
  const SdoRequest* front() noexcept { return reinterpret_cast<const SdoRequest*>(requests_.front()); }
  void pop() noexcept { requests_.pop(); }
  // Queues a reply; false (counted in lost_replies()) when the reply ring is full.
  bool reply(const SdoReply& r) noexcept;

  std::uint64_t refused() const noexcept { return refused_.load(std::memory_order_relaxed); }
  std::uint64_t lost_replies() const noexcept { return lost_.load(std::memory_order_relaxed); }

 private:
  detail::SpscRing requests_, replies_;
  std::mutex callers_;  // transfer()'s callers, all non-RT
  std::uint32_t next_tag_ = 1;
  // Figures for any thread: relaxed, they order nothing. refused_ may be bumped by several
  // non-RT callers (an RMW); lost_ only by the RT thread (a load and a store, no RMW there).
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<std::uint64_t> lost_{0};
};

}  // namespace saw::canopen
