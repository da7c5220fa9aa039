#include "saw/bridge/shm_segment.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace saw::bridge {
namespace {
std::string errno_text(const std::string& what) { return what + ": " + std::strerror(errno); }
}  // namespace

bool process_alive(int pid) noexcept { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

ShmSegment ShmSegment::create(const std::string& name, std::size_t size,
                              bool (*owner_alive)(const void* mapping, std::size_t size)) {
  int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  if (fd < 0 && errno == EEXIST) {
    // Someone left this name: take it over only if its owner is gone.
    ShmSegment old = attach(name);
    if (owner_alive != nullptr && owner_alive(old.data(), old.size()))
      throw BridgeError("shared-memory segment " + name +
                        " is in use by a live process, or is not a sawrt segment: left as it is");
    old.owner_ = true;  // unlinked when `old` goes
    old.release();
    fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  }
  if (fd < 0) throw BridgeError(errno_text("shm_open " + name));
  if (::ftruncate(fd, static_cast<off_t>(size)) != 0) {
    const auto e = errno_text("ftruncate " + name);
    ::close(fd);
    ::shm_unlink(name.c_str());
    throw BridgeError(e);
  }
  void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED) {
    ::shm_unlink(name.c_str());
    throw BridgeError(errno_text("mmap " + name));
  }
  return ShmSegment(name, p, size, true);
}

ShmSegment ShmSegment::attach(const std::string& name, bool writable) {
  const int fd = ::shm_open(name.c_str(), O_RDWR, 0);
  if (fd < 0) throw BridgeError(errno_text("shm_open " + name));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const auto e = errno_text("fstat " + name);
    ::close(fd);
    throw BridgeError(e);
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size == 0) {
    ::close(fd);
    throw BridgeError("shared-memory segment " + name + " is empty (truncated)");
  }
  void* p = ::mmap(nullptr, size, writable ? PROT_READ | PROT_WRITE : PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED) throw BridgeError(errno_text("mmap " + name));
  return ShmSegment(name, p, size, false);
}

void ShmSegment::make_writable(std::size_t offset, std::size_t length) {
  if (offset > size_ || length > size_ - offset) throw BridgeError("make_writable: range outside " + name_);
  if (::mprotect(static_cast<std::byte*>(data_) + offset, length, PROT_READ | PROT_WRITE) != 0)
    throw BridgeError(errno_text("mprotect " + name_));
}

ShmSegment::ShmSegment(ShmSegment&& o) noexcept
    : name_(std::move(o.name_)), data_(o.data_), size_(o.size_), owner_(o.owner_) {
  o.data_ = nullptr;
  o.owner_ = false;
}

ShmSegment& ShmSegment::operator=(ShmSegment&& o) noexcept {
  if (this != &o) {
    release();
    name_ = std::move(o.name_);
    data_ = o.data_;
    size_ = o.size_;
    owner_ = o.owner_;
    o.data_ = nullptr;
    o.owner_ = false;
  }
  return *this;
}

ShmSegment::~ShmSegment() { release(); }

void ShmSegment::release() noexcept {
  if (data_ != nullptr) ::munmap(data_, size_);
  if (owner_) ::shm_unlink(name_.c_str());
  data_ = nullptr;
  owner_ = false;
}

}  // namespace saw::bridge
