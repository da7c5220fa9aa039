// Fuzz target: a client attaching to a shared-memory segment whose every byte another process wrote.
// validate() must refuse it with a reason, or accept only a segment whose every region and index
// lies inside the mapping; an accepted segment is then attached as a client attaches, and read.
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>

#include "saw/bridge/layout.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/clock.hpp"

namespace {

using saw::bridge::ClientSlot;
using saw::bridge::Layout;
using saw::bridge::ManifestEntry;
using saw::bridge::SegmentHeader;
using saw::bridge::ServerSlot;
__extension__ using u128 = unsigned __int128;  // offsets times counts cannot wrap

[[noreturn]] void defect(const char* what, std::uint64_t a, std::uint64_t b) {
  std::fprintf(stderr, "validate() accepted a segment it must refuse: %s (%llu, %llu)\n", what,
               static_cast<unsigned long long>(a), static_cast<unsigned long long>(b));
  std::abort();
}

bool terminated(const char* s, std::size_t n) { return std::memchr(s, '\0', n) != nullptr; }

// What a client may assume of a segment validate() accepted: every region of the layout it
// returned lies inside the mapping, aligned, and the manifest's names and offsets are sound.
void check_accepted(const void* memory, std::size_t size, const Layout& l) {
  const auto inside = [&](const char* what, u128 offset, u128 bytes) {
    if (offset + bytes > size || offset + bytes > l.total_size)
      defect(what, static_cast<std::uint64_t>(offset), static_cast<std::uint64_t>(bytes));
  };
  inside("manifest", l.manifest_offset, u128{l.manifest_count} * sizeof(ManifestEntry));
  if (l.mirror_words == 0) defect("a mirror without its sequence word", 0, 0);
  if (l.mirror_rows == 0) defect("a mirror without a row", 0, 0);
  inside("state mirror", l.mirror_offset, u128{l.mirror_words} * l.mirror_rows * 8);
  inside("server slots", l.server_slots_offset, u128{l.slot_count} * l.server_slot_stride);
  inside("client slots", l.client_slots_offset, u128{l.slot_count} * l.client_slot_stride);
  if (sizeof(ServerSlot) + u128{l.ring_capacity} * l.event_slot_size > l.server_slot_stride)
    defect("event ring overflows its slot", l.ring_capacity, l.server_slot_stride);
  if (sizeof(ClientSlot) + u128{l.ring_capacity} * l.command_slot_size > l.client_slot_stride)
    defect("command ring overflows its slot", l.ring_capacity, l.client_slot_stride);
  if (l.server_slots_offset + u128{l.slot_count} * l.server_slot_stride > l.client_offset)
    defect("server region overlaps the client region", l.server_slots_offset, l.client_offset);
  if (l.ring_capacity < 2 || (l.ring_capacity & (l.ring_capacity - 1)) != 0)
    defect("ring capacity not a power of two", l.ring_capacity, 0);
  for (const std::uint32_t s : {l.command_slot_size, l.event_slot_size})
    if (s == 0 || s % 16 != 0) defect("ring slot size not a multiple of 16", s, 0);
  if (l.client_offset % saw::bridge::page_size != 0 || l.mirror_offset % 8 != 0 ||
      l.server_slots_offset % alignof(ServerSlot) != 0 || l.server_slot_stride % alignof(ServerSlot) != 0 ||
      l.client_slots_offset % alignof(ClientSlot) != 0 || l.client_slot_stride % alignof(ClientSlot) != 0)
    defect("misaligned region", l.mirror_offset, l.client_offset);
  const auto& h = *static_cast<const SegmentHeader*>(memory);
  if (!terminated(h.component, sizeof h.component) || !terminated(h.interface, sizeof h.interface))
    defect("unterminated component or interface name", 0, 0);
  const auto* m =
      reinterpret_cast<const ManifestEntry*>(static_cast<const std::byte*>(memory) + l.manifest_offset);
  const std::uint64_t mirror_bytes = (std::uint64_t{l.mirror_words} - 1) * 8;
  for (std::uint64_t i = 0; i < l.manifest_count; ++i) {
    if (!terminated(m[i].name, sizeof m[i].name) || !terminated(m[i].arg_type, sizeof m[i].arg_type) ||
        !terminated(m[i].result_type, sizeof m[i].result_type))
      defect("unterminated name in manifest entry", i, 0);
    if (m[i].kind == static_cast<std::uint8_t>(saw::CommandKind::read) &&
        u128{m[i].mirror_offset} + m[i].arg_size > mirror_bytes)
      defect("read command's value outside the mirror", i, m[i].mirror_offset);
  }
}

// Maps the bytes as a named segment of a live server (the harness sets only the liveness words:
// state ready, a fresh heartbeat), resolves it as a client does and reads every read command.
void attach(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz-" + std::to_string(getpid());
  const std::string path = "/saw." + name;
  const int fd = shm_open(path.c_str(), O_CREAT | O_RDWR | O_TRUNC, 0600);
  if (fd < 0 || ftruncate(fd, static_cast<off_t>(size)) != 0) std::abort();
  void* p = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (p == MAP_FAILED) std::abort();
  std::memcpy(p, data, size);
  auto& h = *static_cast<SegmentHeader*>(p);
  h.state.store(static_cast<std::uint32_t>(saw::bridge::SegmentState::ready));
  h.heartbeat.store(saw::monotonic_now());
  std::unique_ptr<saw::Component> c;
  try {
    c = saw::bridge::ShmResolver().resolve(name);
  } catch (const saw::ConnectError&) {  // refused with a reason: fine
  }
  shm_unlink(path.c_str());
  if (c != nullptr)
    for (const auto& pi : c->provided_interfaces())
      for (const auto& cmd : pi->commands())
        if (cmd->signature.kind == saw::CommandKind::read) {
          // Exactly the value's size on the heap: a read past it is ASan's to see.
          auto* out = static_cast<std::byte*>(::operator new(cmd->signature.arg.size));
          (void)cmd->read(nullptr, out);
          ::operator delete(out);
        }
  // And the history as a gateway reads it: rows about the newest the header claims, whatever it says.
  if (auto* proxy = dynamic_cast<saw::bridge::Proxy*>(c.get())) {
    auto* block = static_cast<std::byte*>(::operator new(proxy->mirror_bytes() + 1));
    const std::uint64_t n = proxy->rows_written();
    for (std::uint64_t r : {n - 1, n, n + 1, std::uint64_t{0}, n - proxy->history_rows()})
      (void)proxy->read_row(r, block);
    ::operator delete(block);
  }
  c.reset();
  munmap(p, size);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // An exact-size, cache-line-aligned copy (as a mapping is): ASan sees any read past `size`.
  void* copy = ::operator new (size, std::align_val_t{saw::cache_line});
  if (size != 0) std::memcpy(copy, data, size);
  Layout layout;
  const std::string why = saw::bridge::validate(copy, size, &layout);
  if (why.empty()) check_accepted(copy, size, layout);
  ::operator delete (copy, std::align_val_t{saw::cache_line});
  if (why.empty()) attach(data, size);
  return 0;
}
