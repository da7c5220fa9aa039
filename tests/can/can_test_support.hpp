// Helpers of the CAN tests: unique virtual bus names removed afterwards, frames that say who sent them.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/virtual_bus.hpp"
#include "saw/testing/unique_name.hpp"

namespace saw::can::testing {

// A virtual bus name no other test process uses, unlinked when the scope ends.
class ScopedBusName {
 public:
  explicit ScopedBusName(const std::string& prefix = "t") {
    static std::atomic<int> counter{0};
    name_ =
        saw::testing::unique_name("sawcantest-" + prefix + "-") + "-" + std::to_string(counter.fetch_add(1));
    (void)remove_virtual_bus(name_);
  }
  ~ScopedBusName() { (void)remove_virtual_bus(name_); }
  ScopedBusName(const ScopedBusName&) = delete;
  ScopedBusName& operator=(const ScopedBusName&) = delete;
  const std::string& name() const { return name_; }
  std::string uri() const { return "virtual:" + name_; }

 private:
  std::string name_;
};

// The segment as a peer sees it: its own mapping, written without any of the bus's rules.
class RawSegment {
 public:
  explicit RawSegment(const std::string& name) {
    const std::string shm = virtual_bus_shm_name(name);
    const int fd = ::shm_open(shm.c_str(), O_RDWR, 0);
    EXPECT_GE(fd, 0) << shm;
    struct stat st {};
    ::fstat(fd, &st);
    size_ = static_cast<std::size_t>(st.st_size);
    base_ = ::mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);
    EXPECT_NE(base_, MAP_FAILED);
  }
  ~RawSegment() { ::munmap(base_, size_); }
  detail::VirtualBusHeader& header() { return *static_cast<detail::VirtualBusHeader*>(base_); }
  detail::VirtualBusSlot& slot(std::uint64_t i) {
    return reinterpret_cast<detail::VirtualBusSlot*>(static_cast<std::byte*>(base_) +
                                                     detail::virtual_bus_slots_offset)[i];
  }
  std::byte* bytes() { return static_cast<std::byte*>(base_); }
  std::size_t size() const { return size_; }

 private:
  void* base_ = nullptr;
  std::size_t size_ = 0;
};

inline BusConfig config(const std::string& uri, bool fd = false, std::size_t ring = 4096) {
  BusConfig c;
  c.uri = uri;
  c.fd = fd;
  c.ring = ring;
  return c;
}

// A classic frame from `producer` (its identifier) carrying `sequence` in its first 4 bytes.
inline Frame numbered(std::uint32_t producer, std::uint32_t sequence) {
  Frame f;
  f.id = producer & CAN_SFF_MASK;
  f.len = 4;
  std::memcpy(f.data, &sequence, 4);
  return f;
}

inline std::uint32_t sequence_of(const Frame& f) {
  std::uint32_t s = 0;
  std::memcpy(&s, f.data, 4);
  return s;
}

// Everything a bus has for us now, in order.
inline std::vector<Received> drain(Bus& bus, std::size_t batch = 16) {
  std::vector<Received> all, some(batch);
  for (;;) {
    const std::size_t n = bus.receive(some);
    all.insert(all.end(), some.begin(), some.begin() + static_cast<std::ptrdiff_t>(n));
    if (n == 0) return all;
  }
}

inline bool same_frame(const Frame& a, const Frame& b) {
  return a.id == b.id && a.len == b.len && a.flags == b.flags && std::memcmp(a.data, b.data, a.len) == 0;
}

}  // namespace saw::can::testing
