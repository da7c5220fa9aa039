#include "saw/bridge/shm_segment.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

namespace saw::bridge {
namespace {
std::string errno_text(const std::string& what) { return what + ": " + std::strerror(errno); }
}  // namespace

bool process_alive(int pid) noexcept { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

bool process_started_after(int pid, std::int64_t realtime_ns) noexcept {
  if (pid <= 0) return false;
  char path[32];
  std::snprintf(path, sizeof path, "/proc/%d/stat", pid);
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char buf[1024];
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return false;
  buf[n] = '\0';
  // The command name may hold spaces and parentheses: fields are counted from the last ')'.
  const char* p = std::strrchr(buf, ')');
  if (p == nullptr) return false;
  for (int field = 2; field < 22 && p != nullptr; ++field) p = std::strchr(p + 1, ' ');
  if (p == nullptr) return false;
  char* end = nullptr;
  const unsigned long long ticks = std::strtoull(p + 1, &end, 10);  // field 22: start, in ticks after boot
  const long hz = ::sysconf(_SC_CLK_TCK);
  if (end == p + 1 || hz <= 0) return false;
  timespec boot{}, wall{};
  if (::clock_gettime(CLOCK_BOOTTIME, &boot) != 0 || ::clock_gettime(CLOCK_REALTIME, &wall) != 0)
    return false;
  const auto ns = [](const timespec& t) { return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec; };
  const std::int64_t started_after_boot = static_cast<std::int64_t>(ticks / hz) * 1'000'000'000 +
                                          static_cast<std::int64_t>(ticks % hz) * 1'000'000'000 / hz;
  // A tick's truncation dates the start early, never late; the second absorbs a clock step.
  const std::int64_t started = ns(wall) - (ns(boot) - started_after_boot);
  return started > realtime_ns + 1'000'000'000;
}

ShmSegment ShmSegment::create(const std::string& name, std::size_t size,
                              bool (*owner_alive)(const ShmSegment& old)) {
  int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  if (fd < 0 && errno == EEXIST) {
    // Someone left this name: take it over only if its owner is gone.
    ShmSegment old = attach(name);
    if (owner_alive != nullptr && owner_alive(old))
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
  ShmSegment s(name, p, size, false);
  s.modified_ns_ = std::int64_t{st.st_mtim.tv_sec} * 1'000'000'000 + st.st_mtim.tv_nsec;
  return s;
}

void ShmSegment::make_writable(std::size_t offset, std::size_t length) {
  if (offset > size_ || length > size_ - offset) throw BridgeError("make_writable: range outside " + name_);
  if (::mprotect(static_cast<std::byte*>(data_) + offset, length, PROT_READ | PROT_WRITE) != 0)
    throw BridgeError(errno_text("mprotect " + name_));
}

ShmSegment::ShmSegment(ShmSegment&& o) noexcept
    : name_(std::move(o.name_)),
      data_(o.data_),
      size_(o.size_),
      owner_(o.owner_),
      modified_ns_(o.modified_ns_) {
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
    modified_ns_ = o.modified_ns_;
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
