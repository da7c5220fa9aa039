// The bridge's shared-memory layout between real processes: rings, mirror, slots, bad segments.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstring>

#include "saw/bridge/layout.hpp"
#include "saw/bridge/shm_segment.hpp"

namespace {

using namespace saw::bridge;

std::string unique_name(const char* what) {
  return "/saw.test." + std::string(what) + "." + std::to_string(getpid());
}

LayoutParams make(const char* component, std::size_t mirror, std::uint32_t slots, std::uint32_t capacity,
                  std::size_t payload) {
  LayoutParams p;
  p.component = component;
  p.interface = "p";
  p.interface_hash = 42;
  p.mirror_bytes = mirror;
  p.slot_count = slots;
  p.ring_capacity = capacity;
  p.command_payload = p.event_payload = payload;
  return p;
}

bool owner_alive(const void* mapping, std::size_t size) {
  if (!validate(mapping, size).empty()) return false;
  return process_alive(static_cast<const SegmentHeader*>(mapping)->owner_pid.load());
}

struct Fixture {
  explicit Fixture(const char* what, LayoutParams p = make("server", 64, 4, 64, 40))
      : params(std::move(p)),
        layout(Layout::of(params)),
        seg(ShmSegment::create(unique_name(what), layout.total_size, owner_alive)) {
    initialize(seg.data(), params, layout, getpid());
  }
  LayoutParams params;
  Layout layout;
  ShmSegment seg;
};

// Runs f in a child process; returns its exit code.
template <class F>
int in_child(F f) {
  const pid_t pid = fork();
  if (pid == 0) _exit(f());
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 100;
}

TEST(BridgeLayout, ACommandRingCarriesEveryRecordBetweenProcessesInOrder) {
  Fixture f("ring");
  constexpr std::uint64_t n = 200'000;
  const pid_t child = fork();
  if (child == 0) {  // the client process: attaches by name, claims a slot, produces
    ShmSegment s = ShmSegment::attach(f.seg.name());
    if (!validate(s.data(), s.size()).empty()) _exit(2);
    const int index = claim_slot(s.data(), getpid());
    if (index != 0) _exit(3);
    auto ring = command_ring(s.data(), 0);
    for (std::uint64_t k = 0; k < n;) {
      std::byte* slot = ring.try_reserve();
      if (slot == nullptr) continue;
      const std::uint64_t words[4] = {k, ~k, k * 3, k ^ 0x5555};
      std::memcpy(slot, words, sizeof words);
      ring.commit();
      ++k;
    }
    _exit(0);
  }
  // The server side: waits for the claim, then consumes.
  int status = 0;
  bool exited = false;
  while (slot(f.seg.data(), 0).owner_pid.load() != child)
    if (waitpid(child, &status, WNOHANG) == child)
      FAIL() << "the client died before claiming, status " << status;
  auto ring = command_ring(f.seg.data(), 0);
  std::uint64_t torn = 0;
  for (std::uint64_t k = 0; k < n;) {
    const std::byte* s = ring.front();
    if (s == nullptr) {
      // A client that died early must fail the test, not hang it.
      if (exited) FAIL() << "the client exited after " << k << " records";
      exited = waitpid(child, &status, WNOHANG) == child;
      continue;
    }
    std::uint64_t w[4];
    std::memcpy(w, s, sizeof w);
    if (w[0] != k || w[1] != ~k || w[2] != k * 3 || w[3] != (k ^ 0x5555)) ++torn;
    ring.pop();
    ++k;
  }
  if (!exited) waitpid(child, &status, 0);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(torn, 0u);
}

TEST(BridgeLayout, TheMirrorIsNeverTornAcrossProcesses) {
  Fixture f("mirror");
  const pid_t child = fork();
  if (child == 0) {
    ShmSegment s = ShmSegment::attach(f.seg.name());
    std::array<std::uint64_t, 8> v{};
    for (std::uint64_t k = 1; k <= 300'000; ++k) {
      v.fill(k);
      mirror_write(s.data(), v.data(), sizeof v);
    }
    _exit(0);
  }
  std::uint64_t torn = 0, reads = 0, last = 0;
  for (bool exited = false;;) {
    if (exited && last != 300'000) FAIL() << "the writer exited at " << last;
    exited = waitpid(child, nullptr, WNOHANG) == child;
    std::array<std::uint64_t, 8> v{};
    if (mirror_read(f.seg.data(), v.data(), sizeof v)) {
      ++reads;
      for (auto x : v) torn += x != v[0];
      if (v[0] < last) ++torn;
      last = v[0];
      if (v[0] == 300'000) break;
    }
  }
  waitpid(child, nullptr, 0);  // (a no-op if already reaped)
  EXPECT_EQ(torn, 0u);
  EXPECT_GT(reads, 0u);
}

TEST(BridgeLayout, SlotsAreClaimedOnceAndReclaimedFromDeadProcesses) {
  Fixture f("slots", make("server", 8, 2, 8, 16));
  EXPECT_EQ(in_child([&] { return claim_slot(f.seg.data(), getpid()); }),
            0);  // the child dies holding slot 0
  EXPECT_EQ(claim_slot(f.seg.data(), getpid()), 1);
  EXPECT_EQ(claim_slot(f.seg.data(), getpid()), -1) << "all taken";
  const auto generation = slot(f.seg.data(), 0).generation.load();
  EXPECT_EQ(reclaim_dead_slots(f.seg.data()), 1u);
  EXPECT_EQ(claim_slot(f.seg.data(), getpid()), 0);
  EXPECT_EQ(slot(f.seg.data(), 0).generation.load(), generation + 1);
  release_slot(f.seg.data(), 1, getpid());
  EXPECT_EQ(slot(f.seg.data(), 1).owner_pid.load(), 0);
}

TEST(BridgeLayout, BadSegmentsAreRefusedWithAClearReason) {
  Fixture f("bad");
  EXPECT_EQ(validate(f.seg.data(), f.seg.size()), "");
  auto& h = header(f.seg.data());
  EXPECT_NE(validate(f.seg.data(), sizeof(SegmentHeader) - 1).find("truncated"), std::string::npos);
  EXPECT_NE(validate(f.seg.data(), f.seg.size() - 64).find("truncated"), std::string::npos);
  h.layout_version = 7;
  const auto v = validate(f.seg.data(), f.seg.size());
  EXPECT_NE(v.find("layout version 7"), std::string::npos) << v;
  EXPECT_NE(v.find("version " + std::to_string(layout_version)), std::string::npos) << v;
  h.layout_version = layout_version;
  h.slot_stride += 64;
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("inconsistent"), std::string::npos);
  h.magic = 0x1234;
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("not a sawrt bridge segment"), std::string::npos);

  // A foreign file under a bridge name, and an empty one: refused, no crash.
  const auto foreign = unique_name("foreign");
  int fd = shm_open(foreign.c_str(), O_RDWR | O_CREAT, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(write(fd, "hello, not a segment at all, just some text of some length........", 64), 64);
  close(fd);
  ShmSegment s = ShmSegment::attach(foreign);
  EXPECT_NE(validate(s.data(), s.size()).find("truncated"), std::string::npos);
  shm_unlink(foreign.c_str());
  const auto empty = unique_name("empty");
  fd = shm_open(empty.c_str(), O_RDWR | O_CREAT, 0600);
  close(fd);
  EXPECT_THROW(ShmSegment::attach(empty), BridgeError);
  shm_unlink(empty.c_str());
  EXPECT_THROW(ShmSegment::attach(unique_name("absent")), BridgeError);
}

TEST(BridgeLayout, ASegmentLeftByADeadOwnerIsTakenOverALiveOneIsNot) {
  const auto name = unique_name("owner");
  const LayoutParams p = make("server", 8, 1, 8, 16);
  const Layout l = Layout::of(p);
  // A child creates the segment and dies without unlinking it.
  ASSERT_EQ(in_child([&] {
              ShmSegment s = ShmSegment::create(name, l.total_size, owner_alive);
              initialize(s.data(), p, l, getpid());
              std::_Exit(0);  // no destructor: the name stays behind
              return 0;
            }),
            0);
  {
    ShmSegment taken = ShmSegment::create(name, l.total_size, owner_alive);
    initialize(taken.data(), p, l, getpid());
    EXPECT_THROW(ShmSegment::create(name, l.total_size, owner_alive), BridgeError)
        << "its owner (this process) lives";
  }
  EXPECT_THROW(ShmSegment::attach(name), BridgeError) << "the owner unlinks the name when it goes";
}

}  // namespace
