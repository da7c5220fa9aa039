// DdsDomain: a DDS domain id that no other test or benchmark running on this host holds.
//
// Held by an exclusive, non-blocking flock(2) on the lock file DIR/<id> (/tmp/sawrt-test-domains,
// or $SAW_TEST_DOMAIN_DIR): the kernel drops the lock when its process ends, however it ends, so a
// killed test never leaks its domain and nothing of a claim outlives it (process ids are reused
// over a CI run; locks are not). tests/support/python/saw_testing/dds_domain.py is the same
// protocol for the Python tests: C++ and Python claimers exclude each other. The pool, the
// reserved ids and why are described there. Header-only: the benchmarks in tools/ use it too.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace saw::testing {

// Where claims are made and which ids they take.
struct DomainPool {
  std::string dir;
  std::vector<int> ids;

  // $SAW_TEST_DOMAIN_DIR or /tmp/sawrt-test-domains; ids 1-228 (Fast DDS's default ports allow
  // 0-232, a default keystore's governance 0-230) less the repository's fixed defaults: 0 (every
  // tool's), 3 and 7 (docs' examples, a refused domain in tests/security), 42 (examples/lab_message),
  // 229 (tests/python's headless sawgui).
  static DomainPool standard() {
    DomainPool p;
    const char* env = std::getenv("SAW_TEST_DOMAIN_DIR");
    p.dir = env && *env ? env : "/tmp/sawrt-test-domains";
    for (int id = 1; id <= 228; ++id)
      if (id != 3 && id != 7 && id != 42) p.ids.push_back(id);
    return p;
  }
};

class DdsDomain {
 public:
  // A free id of the standard pool.
  DdsDomain() : DdsDomain(DomainPool::standard()) {}

  // A free id of `pool`, the ids tried in a random order; std::runtime_error if every one is held.
  explicit DdsDomain(const DomainPool& pool) {
    ensure_dir(pool.dir);
    std::vector<int> order = pool.ids;
    std::shuffle(order.begin(), order.end(), std::mt19937(std::random_device{}()));
    for (const int id : order) {
      if (try_lock(pool.dir, id)) return;
    }
    throw std::runtime_error("no free DDS domain: all " + std::to_string(order.size()) +
                             " of the pool are held (lock files in " + pool.dir + ")");
  }

  // `id` itself, for a test that needs that id, if nobody holds it now.
  static std::optional<DdsDomain> try_fixed(int id, const std::string& dir = DomainPool::standard().dir) {
    ensure_dir(dir);
    DdsDomain d(Unclaimed{});
    if (!d.try_lock(dir, id)) return std::nullopt;
    return d;
  }

  // `id` itself, waiting up to `timeout` for its holder to end; std::runtime_error after.
  static DdsDomain fixed(int id, std::chrono::milliseconds timeout,
                         const std::string& dir = DomainPool::standard().dir) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (auto d = try_fixed(id, dir)) return std::move(*d);
      if (std::chrono::steady_clock::now() >= deadline)
        throw std::runtime_error("DDS domain " + std::to_string(id) + " still held (" + dir + "/" +
                                 std::to_string(id) + ")");
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }

  ~DdsDomain() { release(); }
  DdsDomain(DdsDomain&& o) noexcept : fd_(std::exchange(o.fd_, -1)), id_(o.id_) {}
  DdsDomain& operator=(DdsDomain&& o) noexcept {
    if (this != &o) {
      release();
      fd_ = std::exchange(o.fd_, -1);
      id_ = o.id_;
    }
    return *this;
  }
  DdsDomain(const DdsDomain&) = delete;
  DdsDomain& operator=(const DdsDomain&) = delete;

  int id() const noexcept { return id_; }

  // Closing the only descriptor drops the lock: the id is free for the next claimer.
  void release() noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  struct Unclaimed {};
  explicit DdsDomain(Unclaimed) {}

  // The shared directory, world-writable and sticky (made so by whoever makes it first).
  static void ensure_dir(const std::string& dir) {
    if (::mkdir(dir.c_str(), 0777) == 0) {
      (void)::chmod(dir.c_str(), 01777);  // mkdir's mode went through the umask
    } else if (errno != EEXIST) {
      throw std::system_error(errno, std::generic_category(), "DDS domain locks: " + dir);
    }
  }

  // The lock file, opened read-only (flock needs no more) and made if missing. An existing file
  // is opened without O_CREAT: in a sticky world-writable directory the kernel refuses O_CREAT on
  // a file another user owns (fs.protected_regular), even though it exists.
  static int open_lock_file(const std::string& dir, int id) {
    const std::string path = dir + "/" + std::to_string(id);
    for (;;) {
      int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd >= 0 || errno != ENOENT) return fd;
      fd = ::open(path.c_str(), O_RDONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (fd >= 0) {
        (void)::fchmod(fd, 0644);  // whatever the umask: other users open it to lock it
        return fd;
      }
      if (errno != EEXIST) return -1;  // (EEXIST: made by another claimer in between: open theirs)
    }
  }

  bool try_lock(const std::string& dir, int id) {
    const int fd = open_lock_file(dir, id);
    if (fd < 0)
      throw std::system_error(errno, std::generic_category(),
                              "DDS domain lock " + dir + "/" + std::to_string(id));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int e = errno;
      ::close(fd);
      if (e == EWOULDBLOCK) return false;
      throw std::system_error(e, std::generic_category(), "flock " + dir + "/" + std::to_string(id));
    }
    fd_ = fd;
    id_ = id;
    return true;
  }

  int fd_ = -1;
  int id_ = -1;
};

// This process's DDS domain: claimed on the first call, held until the process ends.
inline int process_dds_domain() {
  static const DdsDomain claimed;
  return claimed.id();
}

}  // namespace saw::testing
