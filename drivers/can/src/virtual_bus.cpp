// The virtual bus: a multi-producer broadcast ring in shared memory (design: docs/can.md).
#include "saw/can/virtual_bus.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace saw::can {
namespace {

using detail::VirtualBusHeader;
using detail::VirtualBusSlot;

std::string hex(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

bool valid_capacity(std::uint64_t c) noexcept {
  return std::has_single_bit(c) && c >= detail::virtual_bus_min_capacity &&
         c <= detail::virtual_bus_max_capacity;
}

// A descriptor closed on every path out of the constructor.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// The process's mappings, by inode: attachments in one process share one (fewer mappings, and
// the same addresses, so ThreadSanitizer sees attachments in two threads meet). Used at open
// only, never by receive() or send().
std::mutex registry_mutex;
std::vector<std::weak_ptr<detail::VirtualBusMapping>> registry;

std::shared_ptr<detail::VirtualBusMapping> find_mapping(dev_t dev, ino_t ino) {
  std::lock_guard lock(registry_mutex);
  std::erase_if(registry, [](const auto& w) { return w.expired(); });
  for (const auto& w : registry)
    if (auto m = w.lock(); m && m->dev == dev && m->ino == ino) return m;
  return nullptr;
}

std::shared_ptr<detail::VirtualBusMapping> share_mapping(std::shared_ptr<detail::VirtualBusMapping> m) {
  std::lock_guard lock(registry_mutex);
  for (const auto& w : registry)  // another thread of ours mapped it meanwhile: use that one
    if (auto other = w.lock(); other && other->dev == m->dev && other->ino == m->ino) return other;
  registry.push_back(m);
  return m;
}

// Sizes, maps and initialises a segment this process just created with O_EXCL, then publishes it.
template <class Fail>
std::shared_ptr<detail::VirtualBusMapping> create(int fd, std::uint64_t capacity, const Fail& fail) {
  const std::size_t size = detail::virtual_bus_size(capacity);
  struct stat st {};
  void* p = MAP_FAILED;
  std::string why;
  if (::ftruncate(fd, static_cast<off_t>(size)) != 0)
    why = std::string("ftruncate: ") + std::strerror(errno);
  else if (::fstat(fd, &st) != 0)
    why = std::string("fstat: ") + std::strerror(errno);
  else if (p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0); p == MAP_FAILED)
    why = std::string("mmap: ") + std::strerror(errno);
  if (!why.empty()) throw fail(why);
  auto m = std::make_shared<detail::VirtualBusMapping>(p, size, st.st_dev, st.st_ino);
  m->capacity = capacity;
  auto* h = static_cast<VirtualBusHeader*>(p);
  // ftruncate zero-filled the slots (sequence 0: never written). Relaxed: nobody reads these
  // before the release store of the magic below, which publishes them.
  h->version.store(detail::virtual_bus_version, std::memory_order_relaxed);
  h->slot_size.store(sizeof(VirtualBusSlot), std::memory_order_relaxed);
  h->capacity.store(capacity, std::memory_order_relaxed);
  h->total_size.store(size, std::memory_order_relaxed);
  h->write_ticket.store(0, std::memory_order_relaxed);
  h->attachments.store(0, std::memory_order_relaxed);
  // Release, last: an attacher that acquires the magic sees every field above.
  h->magic.store(detail::virtual_bus_magic, std::memory_order_release);
  return share_mapping(std::move(m));
}

}  // namespace

namespace detail {
VirtualBusMapping::~VirtualBusMapping() {
  if (base != nullptr) ::munmap(base, size);
}
}  // namespace detail

std::string virtual_bus_shm_name(std::string_view name) {
  const bool ok_chars = std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
  });
  if (name.empty() || name.size() > 64 || !ok_chars)
    throw std::invalid_argument("virtual CAN bus name '" + std::string(name) +
                                "': 1 to 64 characters from [A-Za-z0-9_.-] expected");
  return "/saw-can." + std::string(name);
}

bool remove_virtual_bus(std::string_view name) {
  const std::string shm = virtual_bus_shm_name(name);
  if (::shm_unlink(shm.c_str()) == 0) return true;
  if (errno == ENOENT) return false;
  throw std::runtime_error("remove virtual CAN bus '" + std::string(name) + "': shm_unlink " + shm + ": " +
                           std::strerror(errno));
}

VirtualBus::VirtualBus(const BusConfig& config, std::string_view bus_name, const VirtualBusOptions& options)
    : name_("virtual:" + std::string(bus_name)), fd_(config.fd), filters_(config.filters), options_(options) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("CAN bus '" + name_ + "' (/dev/shm" + shm_name_ + "): " + why);
  };
  try {
    shm_name_ = virtual_bus_shm_name(bus_name);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("CAN bus '" + name_ + "': " + e.what());
  }
  if (!valid_capacity(config.ring))
    throw fail("ring " + std::to_string(config.ring) + " is not a power of two from " +
               std::to_string(detail::virtual_bus_min_capacity) + " to " +
               std::to_string(detail::virtual_bus_max_capacity));

  const TimeNs deadline = monotonic_now() + options_.attach_timeout;
  std::string waiting_for;  // why the last attempt to attach had to wait
  const auto wait = [&](std::string why) {
    waiting_for = std::move(why);
    if (monotonic_now() > deadline)
      throw fail(waiting_for + " for " + std::to_string(options_.attach_timeout / 1'000'000) +
                 " ms (did its creator die while creating it?); remove it with saw::can::remove_virtual_bus "
                 "or rm /dev/shm" +
                 shm_name_);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  while (mapping_ == nullptr) {
    Fd f;
    // The first opener creates it. O_EXCL makes exactly one process the creator; the others
    // attach and wait for the creator's release store of the magic.
    f.fd = ::shm_open(shm_name_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (f.fd >= 0) {
      try {
        mapping_ = create(f.fd, config.ring, fail);
      } catch (...) {
        ::shm_unlink(shm_name_.c_str());  // a half-made segment would stall the next opener
        throw;
      }
      created_ = true;
      break;
    }
    if (errno != EEXIST) throw fail(std::string("shm_open: ") + std::strerror(errno));
    f.fd = ::shm_open(shm_name_.c_str(), O_RDWR | O_CLOEXEC, 0);
    if (f.fd < 0) {
      if (errno == ENOENT) continue;  // removed between the two calls: create it ourselves
      throw fail(std::string("shm_open: ") + std::strerror(errno));
    }
    struct stat st {};
    if (::fstat(f.fd, &st) != 0) throw fail(std::string("fstat: ") + std::strerror(errno));
    if (auto shared = find_mapping(st.st_dev, st.st_ino)) {  // validated when this process mapped it
      mapping_ = std::move(shared);
      break;
    }
    const auto size = static_cast<std::size_t>(st.st_size);
    if (size < sizeof(VirtualBusHeader)) {  // the creator has not sized it yet
      wait("the segment stayed " + std::to_string(size) + " bytes");
      continue;
    }
    void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, f.fd, 0);
    if (p == MAP_FAILED) throw fail(std::string("mmap: ") + std::strerror(errno));
    auto m = std::make_shared<detail::VirtualBusMapping>(p, size, st.st_dev, st.st_ino);
    auto* h = static_cast<VirtualBusHeader*>(p);
    // Acquire: pairs with the creator's release store; the fields below are then its values
    // (or a peer's later scribbles, which the checks below catch).
    const std::uint64_t magic = h->magic.load(std::memory_order_acquire);
    if (magic == 0) {
      wait("the segment was not published (its magic stayed 0)");
      continue;
    }
    // Read once into private memory; from here on only the copies are used.
    const std::uint32_t version = h->version.load(std::memory_order_relaxed);
    const std::uint32_t slot_size = h->slot_size.load(std::memory_order_relaxed);
    const std::uint64_t capacity = h->capacity.load(std::memory_order_relaxed);
    const std::uint64_t total = h->total_size.load(std::memory_order_relaxed);
    std::string bad;
    if (magic != detail::virtual_bus_magic)
      bad = "not a sawrt virtual CAN bus (magic " + hex(magic) + ")";
    else if (version != detail::virtual_bus_version)
      bad = "layout version " + std::to_string(version) + ", this build reads version " +
            std::to_string(detail::virtual_bus_version);
    else if (slot_size != sizeof(VirtualBusSlot))
      bad = "slot size " + std::to_string(slot_size) + ", expected " + std::to_string(sizeof(VirtualBusSlot));
    else if (!valid_capacity(capacity))
      bad = "capacity " + std::to_string(capacity) + " is not a power of two from " +
            std::to_string(detail::virtual_bus_min_capacity) + " to " +
            std::to_string(detail::virtual_bus_max_capacity);
    else if (total != detail::virtual_bus_size(capacity) || size != total)
      bad = "size " + std::to_string(size) + " bytes (its header says " + std::to_string(total) +
            ") does not match " + std::to_string(capacity) + " slots (" +
            std::to_string(detail::virtual_bus_size(capacity)) + " bytes)";
    if (!bad.empty())
      throw fail(bad + "; remove it with saw::can::remove_virtual_bus or rm /dev/shm" + shm_name_);
    m->capacity = capacity;
    mapping_ = share_mapping(std::move(m));
  }
  header_ = static_cast<VirtualBusHeader*>(mapping_->base);
  slots_ = reinterpret_cast<VirtualBusSlot*>(static_cast<std::byte*>(mapping_->base) +
                                             detail::virtual_bus_slots_offset);
  mask_ = mapping_->capacity - 1;
  // Relaxed: the id only has to be unique among attachments (0 means "nobody").
  do {
    id_ = static_cast<std::uint32_t>(header_->attachments.fetch_add(1, std::memory_order_relaxed) + 1);
  } while (id_ == 0);
  // A reader sees what is sent after it attached, as a socket bound later does. Relaxed: the
  // ticket is a position, the slots' sequences publish their contents.
  next_ = header_->write_ticket.load(std::memory_order_relaxed);
}

// Never unlinked here: the bus outlives its users, as vcan does (remove_virtual_bus does it).
VirtualBus::~VirtualBus() = default;

bool VirtualBus::accepts(const Frame& f) const noexcept {
  if (f.fd() && !fd_) return false;  // a CAN_RAW socket without CAN_RAW_FD_FRAMES sees no FD frames
  if (filters_.empty()) return true;
  for (const auto& filter : filters_)
    if ((f.id & filter.mask) == (filter.id & filter.mask)) return true;
  return false;
}

bool VirtualBus::write_one(const Frame& f, TimeNs now) noexcept {
  // Relaxed: the ticket only has to be unique; what readers may read is published by the slot's
  // sequence, not by the ticket.
  const std::uint64_t ticket = header_->write_ticket.fetch_add(1, std::memory_order_relaxed);
  VirtualBusSlot& s = slots_[ticket & mask_];
  const std::uint64_t writing = 2 * ticket + 1;
  std::uint64_t seen = s.sequence.load(std::memory_order_relaxed);
  do {
    // A newer lap already has the slot: we were a full ring late between fetch_add and here.
    if (seen >= writing) {
      bump(lapped_);
      return false;
    }
    // Claimed even when `seen` is odd: that is a producer a full ring behind us, dead or stalled;
    // waiting for it could be forever. Its frame is lost (its completion CAS fails) and any of its
    // late payload stores are caught by the check word. Acquire: when the previous owner
    // completed normally, our payload stores come after its stores in each word's order.
    // Release: a reader that sees our claim also sees our ticket taken from write_ticket, so it
    // can tell a claim from garbage (a sequence beyond every ticket handed out).
  } while (
      !s.sequence.compare_exchange_weak(seen, writing, std::memory_order_acq_rel, std::memory_order_relaxed));
  const auto words = detail::frame_to_words(f);
  const auto time = static_cast<std::uint64_t>(now);
  // Release (seqlock writer, without a fence): a reader whose acquire load sees any of these
  // stores also sees our claim above when it re-reads the sequence, and drops its copy. On
  // x86 these are plain stores.
  s.time.store(time, std::memory_order_release);
  s.writer.store(id_, std::memory_order_release);
  for (std::size_t i = 0; i < words.size(); ++i) s.frame[i].store(words[i], std::memory_order_release);
  s.check.store(detail::slot_check(ticket, time, id_, words), std::memory_order_release);
  // Release: a reader that acquires 2t+2 sees the payload. Fails only when a producer a full ring
  // ahead took the slot over meanwhile: the frame is then lost, as an overwritten one is.
  std::uint64_t expected = writing;
  if (!s.sequence.compare_exchange_strong(expected, writing + 1, std::memory_order_release,
                                          std::memory_order_relaxed)) {
    bump(lapped_);
    return false;
  }
  return true;
}

std::size_t VirtualBus::send(std::span<const Frame> frames) noexcept {
  const TimeNs now = monotonic_now();
  std::size_t accepted = 0;
  for (const Frame& f : frames) {
    // The caller's mistakes are refused, never put on the bus; a full ring is not one: the
    // broadcast never refuses, the slowest readers lose the oldest frames instead.
    if (!well_formed(f) || f.error() || (f.fd() && !fd_)) break;
    (void)write_one(f, now);
    ++accepted;
  }
  if (accepted > 0) bump(sent_, accepted);
  if (accepted < frames.size()) bump(refused_, frames.size() - accepted);
  return accepted;
}

std::size_t VirtualBus::receive(std::span<Received> out) noexcept {
  const std::uint64_t capacity = mask_ + 1;
  std::size_t n = 0;
  std::uint64_t malformed = 0, overruns = 0;
  // Each pass returns a frame, moves the cursor or stops, except a torn copy, retried once. The
  // budget bounds a call's work whatever the segment holds (a ring of our own frames to pass
  // over, or a peer's garbage).
  std::uint64_t budget = out.size() + 2 * capacity;
  bool retried = false;
  while (n < out.size() && budget-- > 0) {
    const std::uint64_t ticket = next_;
    VirtualBusSlot& s = slots_[ticket & mask_];
    const std::uint64_t complete = 2 * ticket + 2;
    // Acquire: pairs with the producer's release completion, so the payload loads below see
    // what it wrote.
    const std::uint64_t seq = s.sequence.load(std::memory_order_acquire);
    if (seq == complete) {
      // Acquire (seqlock reader, without a fence): if any of these loads sees a newer producer's
      // store, the re-read of the sequence below sees that producer's claim, and the copy is
      // dropped; the acquire loads also keep the re-read from moving before them.
      std::array<std::uint64_t, detail::frame_words> words;
      const std::uint64_t check = s.check.load(std::memory_order_acquire);
      const std::uint64_t time = s.time.load(std::memory_order_acquire);
      const std::uint64_t writer = s.writer.load(std::memory_order_acquire);
      for (std::size_t i = 0; i < words.size(); ++i) words[i] = s.frame[i].load(std::memory_order_acquire);
      if (s.sequence.load(std::memory_order_relaxed) != complete) {
        // Torn: a newer lap took the slot while we copied. The next pass sees its sequence and
        // resyncs; a sequence that flips back and forth (a peer) costs the frame.
        if (!retried) {
          retried = true;
          continue;
        }
        retried = false;
        ++malformed;
        ++next_;
        continue;
      }
      retried = false;
      ++next_;
      if (check != detail::slot_check(ticket, time, writer, words)) {
        ++malformed;  // a torn mix of two producers, or a peer's garbage
        continue;
      }
      if (writer == id_) continue;  // our own frame: a CAN_RAW socket does not receive its own
      const Frame f = detail::words_to_frame(words);
      if (!well_formed(f) || f.error()) {
        ++malformed;
        continue;
      }
      if (!accepts(f)) continue;
      out[n].frame = f;
      out[n].time = static_cast<TimeNs>(time);
      ++n;
      continue;
    }
    retried = false;
    // Relaxed: the newest ticket is only compared with ours; no data is read on its strength.
    const std::uint64_t head = header_->write_ticket.load(std::memory_order_relaxed);
    if (seq > complete) {
      // A newer lap wrote (or is writing) this slot: we are more than a ring behind. Resume half
      // a ring behind the newest ticket, so that we are not lapped again at once.
      if (seq / 2 > head) {  // no producer holds such a ticket: a peer's garbage
        ++malformed;
        ++next_;
        continue;
      }
      std::uint64_t resume = head > capacity / 2 ? head - capacity / 2 : 0;
      if (resume <= ticket) resume = ticket + 1;
      overruns += resume - ticket;
      next_ = resume;
      continue;
    }
    // The slot still holds an older lap (or ticket `ticket` is being written): not complete.
    if (head - ticket - 1 >= (std::uint64_t{1} << 63)) {  // head <= ticket: nothing more was sent
      if (ticket - head > capacity) {  // the ticket went back by more than a ring: a peer reset it
        ++malformed;
        next_ = head;
      }
      break;
    }
    if (head - ticket > capacity) {
      // Tickets before head - capacity have lost their slots to newer ones, whether they were
      // ever completed or not (the first half of the dead-producer rule).
      const std::uint64_t resume = head - capacity;
      bump(abandoned_);
      overruns += resume - ticket;
      next_ = resume;
      continue;
    }
    // Ticket `ticket` was taken and is not complete yet. Later frames wait behind it: when they
    // do and it stays incomplete for the grace period, its producer is taken for dead and the
    // ticket skipped (the second half of the rule). Otherwise we stop here; the frame will be
    // there on a later call.
    if (head - ticket == 1) break;
    const TimeNs now = monotonic_now();
    if (waiting_ticket_ != ticket) {
      waiting_ticket_ = ticket;
      waiting_since_ = now;
      break;
    }
    if (now - waiting_since_ < options_.incomplete_grace) break;
    bump(abandoned_);
    ++overruns;
    ++next_;
  }
  if (n > 0) bump(received_, n);
  if (malformed > 0) bump(malformed_, malformed);
  if (overruns > 0) bump(overruns_, overruns);
  return n;
}

BusCounters VirtualBus::counters() const noexcept {
  BusCounters c;
  c.received = received_.load(std::memory_order_relaxed);
  c.sent = sent_.load(std::memory_order_relaxed);
  c.send_refused = refused_.load(std::memory_order_relaxed);
  c.overruns = overruns_.load(std::memory_order_relaxed);
  c.malformed = malformed_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace saw::can
