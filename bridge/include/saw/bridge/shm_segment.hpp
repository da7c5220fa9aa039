// ShmSegment: a named POSIX shared-memory mapping, created by its owner or attached by peers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace saw::bridge {

class BridgeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Set-up only (never on an RT path): every call may block or allocate.
class ShmSegment {
 public:
  // Creates /name of `size` bytes, zero-filled. A segment already under that name is replaced
  // only if `owner_alive` says its owner is gone; otherwise it is an error and the segment stays.
  static ShmSegment create(const std::string& name, std::size_t size,
                           bool (*owner_alive)(const ShmSegment& old));
  // Maps an existing /name, read-only unless `writable`; throws if absent.
  static ShmSegment attach(const std::string& name, bool writable = true);
  // Makes [offset, offset + length) of a read-only mapping writable (page-aligned offset).
  void make_writable(std::size_t offset, std::size_t length);

  ShmSegment() = default;  // no mapping
  ShmSegment(ShmSegment&& other) noexcept;
  ShmSegment& operator=(ShmSegment&& other) noexcept;
  ~ShmSegment();

  void* data() const noexcept { return data_; }
  std::size_t size() const noexcept { return size_; }
  const std::string& name() const noexcept { return name_; }
  bool owner() const noexcept { return owner_; }
  // When the name's contents were last changed (CLOCK_REALTIME ns, as attached): sized, written,
  // or a page first stored to through a mapping. Never before its creation.
  std::int64_t modified_ns() const noexcept { return modified_ns_; }

 private:
  ShmSegment(std::string name, void* data, std::size_t size, bool owner) noexcept
      : name_(std::move(name)), data_(data), size_(size), owner_(owner) {}
  void release() noexcept;

  std::string name_;
  void* data_ = nullptr;
  std::size_t size_ = 0;
  bool owner_ = false;  // the owner unlinks the name when it goes
  std::int64_t modified_ns_ = 0;
};

// True if a process with this pid exists (kill(pid, 0)).
bool process_alive(int pid) noexcept;
// True if the process now holding `pid` began more than a second after `realtime_ns`
// (CLOCK_REALTIME): it cannot have written something dated then, whatever pid it has. False when
// unknown (no such process, /proc unreadable).
bool process_started_after(int pid, std::int64_t realtime_ns) noexcept;

}  // namespace saw::bridge
