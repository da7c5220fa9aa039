// The bridge's shared-memory layout between real processes: rings, mirror, slots, bad segments.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <ctime>

#include "saw/bridge/exporter.hpp"
#include "saw/bridge/layout.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/clock.hpp"
#include "saw/detail/spsc_ring.hpp"
#include "saw/task.hpp"
#include "saw/testing/child_process.hpp"

namespace {

using saw::testing::in_child;

using namespace saw::bridge;
using saw::monotonic_now;

std::string unique_name(const char* what) {
  return "/saw.test." + std::string(what) + "." + std::to_string(getpid());
}

LayoutParams make(std::size_t mirror, std::uint32_t slots, std::uint32_t capacity, std::size_t payload) {
  LayoutParams p;
  p.mirror_bytes = mirror;
  p.slot_count = slots;
  p.ring_capacity = capacity;
  p.command_payload = p.event_payload = payload;
  return p;
}

Layout layout_of(const LayoutParams& p) {
  Layout l;
  EXPECT_EQ(Layout::compute(p, l), "");
  return l;
}

struct Fixture {
  explicit Fixture(const char* what, LayoutParams p = make(64, 4, 64, 40))
      : layout(layout_of(p)),
        seg(ShmSegment::create(unique_name(what), layout.total_size, segment_owner_alive)) {
    view = SegmentView(seg.data(), layout);
    initialize(view, "server", "p", 42, getpid());
    view.header().heartbeat.store(monotonic_now());
  }
  Layout layout;
  ShmSegment seg;
  SegmentView view;
};

TEST(BridgeLayout, ACommandRingCarriesEveryRecordBetweenProcessesInOrder) {
  Fixture f("ring");
  constexpr std::uint64_t n = 200'000;
  const pid_t child = fork();
  if (child == 0) {  // the client process: attaches by name, claims a slot, produces
    Layout l;
    std::string why;
    ShmSegment s = attach_validated(f.seg.name(), l, why);
    if (!why.empty()) _exit(2);
    const SegmentView v(s.data(), l);
    if (claim_slot(v, 77, getpid(), monotonic_now()) != 0) _exit(3);
    auto ring = command_ring(v, 0);
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
  int status = 0;
  bool exited = false;
  while (f.view.client_slot(0).owner.load() != 77)
    if (waitpid(child, &status, WNOHANG) == child)
      FAIL() << "the client died before claiming, status " << status;
  auto ring = command_ring(f.view, 0);  // the server's view: consumer
  std::uint64_t torn = 0;
  for (std::uint64_t k = 0; k < n;) {
    const std::byte* s = ring.front();
    if (s == nullptr) {
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
  EXPECT_EQ(ring.corrupt_count(), 0u);
}

// A client that falls behind reads every row it missed while fewer than the history's depth
// were written since; an older one is said overwritten, never read as another row's values.
TEST(BridgeLayout, TheMirrorKeepsTheLastRowsAndSaysWhichAreGone) {
  LayoutParams p = make(16, 1, 2, 16);
  p.mirror_rows = 4;
  Fixture f("history", p);
  std::uint64_t rows = 0;
  std::array<std::uint64_t, 2> v{};
  EXPECT_TRUE(mirror_read(f.view, v.data(), sizeof v)) << "before the first row: zeros";
  EXPECT_EQ(v[0], 0u);
  EXPECT_EQ(mirror_read_row(f.view, 0, v.data(), sizeof v), RowRead::not_written);
  for (std::uint64_t k = 0; k < 10; ++k) {
    const std::array<std::uint64_t, 2> w{k, 100 + k};
    mirror_write(f.view, rows, w.data(), sizeof w);
  }
  EXPECT_EQ(rows, 10u);
  EXPECT_EQ(f.view.header().rows_written.load(), 10u);
  for (std::uint64_t k = 6; k < 10; ++k) {
    ASSERT_EQ(mirror_read_row(f.view, k, v.data(), sizeof v), RowRead::ok) << k;
    EXPECT_EQ(v[0], k);
    EXPECT_EQ(v[1], 100 + k);
  }
  for (std::uint64_t k = 0; k < 6; ++k)
    EXPECT_EQ(mirror_read_row(f.view, k, v.data(), sizeof v), RowRead::overwritten) << k;
  EXPECT_EQ(mirror_read_row(f.view, 10, v.data(), sizeof v), RowRead::not_written);
  ASSERT_TRUE(mirror_read(f.view, v.data(), sizeof v));
  EXPECT_EQ(v[0], 9u) << "the newest row";
  LayoutParams none = p;
  none.mirror_rows = 0;
  Layout l;
  EXPECT_NE(Layout::compute(none, l).find("rows is outside 1..4096"), std::string::npos);
}

TEST(BridgeLayout, TheMirrorIsNeverTornAcrossProcesses) {
  Fixture f("mirror");
  const pid_t child = fork();
  if (child == 0) {
    std::array<std::uint64_t, 8> v{};
    std::uint64_t seq = 0;
    for (std::uint64_t k = 1; k <= 300'000; ++k) {
      v.fill(k);
      mirror_write(f.view, seq, v.data(), sizeof v);
    }
    _exit(0);
  }
  std::uint64_t torn = 0, reads = 0, last = 0;
  for (bool exited = false;;) {
    if (exited && last != 300'000) FAIL() << "the writer exited at " << last;
    exited = waitpid(child, nullptr, WNOHANG) == child;
    std::array<std::uint64_t, 8> v{};
    if (mirror_read(f.view, v.data(), sizeof v)) {
      ++reads;
      for (auto x : v) torn += x != v[0];
      if (v[0] < last) ++torn;
      last = v[0];
      if (v[0] == 300'000) break;
    }
  }
  waitpid(child, nullptr, 0);
  EXPECT_EQ(torn, 0u);
  EXPECT_GT(reads, 0u);
}

TEST(BridgeLayout, SlotsAreClaimedOnceAndFreedWhenTheirHeartbeatStops) {
  Fixture f("slots", make(8, 2, 8, 16));
  const auto now = monotonic_now();
  EXPECT_EQ(claim_slot(f.view, 11, 1, now - 2'000'000'000), 0);  // a client that stopped beating 2 s ago
  EXPECT_EQ(claim_slot(f.view, 12, 2, now), 1);
  EXPECT_EQ(claim_slot(f.view, 13, 3, now), -1) << "all taken";
  f.view.client_slot(0).update_waiting.store(1);  // it died asleep
  EXPECT_EQ(reclaim_stale_slots(f.view, now, 500'000'000), 1u);
  EXPECT_EQ(f.view.client_slot(0).update_waiting.load(), 0u) << "a dead client's sleeper flag is cleared";
  EXPECT_EQ(claim_slot(f.view, 14, 4, now), 0);
  release_slot(f.view, 1, 99);  // not its token: nothing happens
  EXPECT_EQ(f.view.client_slot(1).owner.load(), 12u);
  release_slot(f.view, 1, 12);
  EXPECT_EQ(f.view.client_slot(1).owner.load(), 0u);
}

TEST(BridgeLayout, BadSegmentsAreRefusedWithAClearReason) {
  Fixture f("bad");
  EXPECT_EQ(validate(f.seg.data(), f.seg.size()), "");
  auto& h = f.view.header();
  EXPECT_NE(validate(f.seg.data(), sizeof(SegmentHeader) - 1).find("truncated"), std::string::npos);
  EXPECT_NE(validate(f.seg.data(), f.seg.size() - 64).find("truncated"), std::string::npos);
  h.layout_version = 7;
  const auto v = validate(f.seg.data(), f.seg.size());
  EXPECT_NE(v.find("layout version 7"), std::string::npos) << v;
  EXPECT_NE(v.find("version " + std::to_string(layout_version)), std::string::npos) << v;
  h.layout_version = layout_version;
  h.slot_count += 1;
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("inconsistent"), std::string::npos);
  h.slot_count -= 1;
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

// Layout arithmetic that wrapped in 32 bits: a header whose slot sizes add up past 2^32 made a
// 1,664-byte segment validate with rings 4-6 GB away. Every count is bounded and every sum checked.
TEST(BridgeLayout, ValidationRefusesHugeOrWrappingCountsAndOddRingCapacities) {
  Fixture f("wrap");
  auto& h = f.view.header();
  const auto expect_refused = [&](const char* what, const char* needle) {
    const auto why = validate(f.seg.data(), f.seg.size());
    EXPECT_NE(why.find(needle), std::string::npos) << what << ": " << why;
  };
  struct {
    std::uint32_t command_slot_size, event_slot_size, ring_capacity, manifest_count, mirror_words;
  } const saved{h.command_slot_size, h.event_slot_size, h.ring_capacity, h.manifest_count, h.mirror_words};
  h.command_slot_size = 0xFFFFFFF0U;
  h.event_slot_size = 0x20U;
  expect_refused("slot sizes summing past 2^32", "out of bounds");
  h.command_slot_size = saved.command_slot_size;
  h.event_slot_size = saved.event_slot_size;
  h.ring_capacity = 3;
  expect_refused("a capacity of 3 (SpscRing would throw in the monitor thread)", "power of two");
  h.ring_capacity = 1U << 31;
  expect_refused("a huge capacity", "power of two");
  h.ring_capacity = saved.ring_capacity;
  h.manifest_count = 0xFFFFFFFFU;
  expect_refused("a huge manifest", "out of bounds");
  h.manifest_count = saved.manifest_count;
  h.mirror_words = 0;
  expect_refused("no mirror sequence word", "0 words");
  h.mirror_words = saved.mirror_words;
  h.command_slot_size = 24;
  expect_refused("a slot size not a multiple of 16", "multiple of 16");
  h.command_slot_size = saved.command_slot_size;
  std::memset(h.component, 'x', sizeof h.component);
  expect_refused("an unterminated name", "not terminated");
  std::strcpy(h.component, "server");
  EXPECT_EQ(validate(f.seg.data(), f.seg.size()), "");
}

TEST(BridgeLayout, ManifestEntriesMustLieInsideTheSegmentTheyDescribe) {
  LayoutParams p = make(64, 2, 8, 40);
  p.manifest_count = 2;
  Fixture f("manifest", p);
  ManifestEntry* m = f.view.manifest();
  std::strcpy(m[0].name, "measured");
  m[0].kind = static_cast<std::uint8_t>(saw::CommandKind::read);
  m[0].arg_size = 24;
  m[0].mirror_offset = 8;
  std::strcpy(m[1].name, "servo");
  m[1].kind = static_cast<std::uint8_t>(saw::CommandKind::write);
  m[1].arg_size = 40;
  EXPECT_EQ(validate(f.seg.data(), f.seg.size()), "");
  m[0].mirror_offset = 1U << 30;
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("state mirror"), std::string::npos);
  m[0].mirror_offset = 0xFFFFFFF0U;  // offset + size wraps in 32 bits
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("state mirror"), std::string::npos);
  m[0].mirror_offset = 8;
  m[1].arg_size = 4096;
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("command slot"), std::string::npos);
  m[1].arg_size = 40;
  m[1].kind = 99;
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("kind 99"), std::string::npos);
  m[1].kind = static_cast<std::uint8_t>(saw::CommandKind::write);
  m[1].has_limits = 1;
  m[1].limit_min = 1;
  m[1].limit_max = std::nan("");
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("interval"), std::string::npos);
  m[1].has_limits = 0;
  std::strcpy(m[1].name, "measured");  // two commands of one name: the proxy could not rebuild them
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("named twice"), std::string::npos);
  std::strcpy(m[1].name, "servo");
  std::memset(m[1].arg_type, 'y', sizeof m[1].arg_type);
  EXPECT_NE(validate(f.seg.data(), f.seg.size()).find("not terminated"), std::string::npos);
}

// A client sees the server's region read-only: a stray write faults in the client, not the server.
TEST(BridgeLayout, ClientsMapTheServersRegionReadOnlyAndTheirOwnReadWrite) {
  Fixture f("readonly");
  ASSERT_EQ(f.layout.client_offset % page_size, 0u);
  const auto write_at = [&](std::uint64_t offset) {
    return in_child([&] {
      Layout l;
      std::string why;
      ShmSegment s = attach_validated(f.seg.name(), l, why);
      if (!why.empty()) return 2;
      static_cast<volatile std::byte*>(s.data())[offset] = std::byte{1};
      return 0;
    });
  };
  EXPECT_NE(write_at(offsetof(SegmentHeader, heartbeat)), 0) << "the header is read-only (SIGSEGV)";
  EXPECT_NE(write_at(f.layout.mirror_offset), 0) << "the state mirror is read-only";
  EXPECT_NE(write_at(f.layout.server_slots_offset), 0) << "the server's half of a slot is read-only";
  EXPECT_EQ(write_at(f.layout.client_slots_offset + offsetof(ClientSlot, commands_head)), 0)
      << "the client's half is its own";
}

// A peer that rewinds or races the index this side owns cannot make it replay or skip: each
// side keeps its own index privately and checks the other's.
TEST(BridgeLayout, RingIndicesFromAPeerAreCheckedNotTrusted) {
  Fixture f("indices", make(8, 1, 8, 16));
  auto consumer = command_ring(f.view, 0);  // the server's view
  auto producer = command_ring(f.view, 0);  // a client's
  for (int k = 0; k < 3; ++k) {
    ASSERT_NE(producer.try_reserve(), nullptr);
    producer.commit();
  }
  for (int k = 0; k < 3; ++k) {
    ASSERT_NE(consumer.front(), nullptr);
    consumer.pop();
  }
  ClientSlot& c = f.view.client_slot(0);
  ServerSlot& s = f.view.server_slot(0);
  s.commands_tail.store(0);  // someone rewrites the server's published index: no replay
  EXPECT_EQ(consumer.front(), nullptr);
  c.commands_head.store(3 + 1'000'000);  // a head a million records ahead: dropped, not run
  EXPECT_EQ(consumer.front(), nullptr);
  EXPECT_EQ(consumer.corrupt_count(), 1u);
  c.commands_head.store(1);  // a head behind the tail: dropped too, and the consumer follows it
  EXPECT_EQ(consumer.front(), nullptr);
  EXPECT_EQ(consumer.corrupt_count(), 2u);
  ASSERT_NE(producer.try_reserve(), nullptr) << "a live producer goes on from its own index";
  // A consumer index that no consumer could have published: the producer sees a full ring.
  s.commands_tail.store(1'000'000'000);
  c.commands_head.store(8);
  auto late = command_ring(f.view, 0);
  EXPECT_EQ(late.try_reserve(), nullptr);
  EXPECT_EQ(late.corrupt_count(), 1u);
}

TEST(BridgeLayout, ASegmentLeftByADeadOwnerIsTakenOverALiveOneIsNot) {
  const auto name = unique_name("owner");
  const Layout l = layout_of(make(8, 1, 8, 16));
  ASSERT_EQ(in_child([&] {
              ShmSegment s = ShmSegment::create(name, l.total_size, segment_owner_alive);
              initialize(SegmentView(s.data(), l), "server", "p", 1, getpid());
              std::_Exit(0);  // no destructor: the name stays behind, its heartbeat 0
              return 0;
            }),
            0);
  {
    ShmSegment taken = ShmSegment::create(name, l.total_size, segment_owner_alive);
    const SegmentView v(taken.data(), l);
    initialize(v, "server", "p", 1, getpid());
    EXPECT_THROW(ShmSegment::create(name, l.total_size, segment_owner_alive), BridgeError)
        << "its owner (this process) lives";
    // A client scribbles the layout version: the live owner's segment is still not replaced.
    v.header().layout_version = 9;
    EXPECT_THROW(ShmSegment::create(name, l.total_size, segment_owner_alive), BridgeError);
    v.header().layout_version = layout_version;
  }
  EXPECT_THROW(ShmSegment::attach(name), BridgeError) << "the owner unlinks the name when it goes";
}

// Pids wrap: a segment left by a killed owner whose pid a later process now holds is taken over;
// one whose owner's pid belongs to a process older than the segment is not.
TEST(BridgeLayout, ASegmentWhoseOwnersPidWasReusedIsTakenOver) {
  const auto name = unique_name("reused");
  const Layout l = layout_of(make(8, 1, 8, 16));
  ASSERT_EQ(in_child([&] {
              ShmSegment s = ShmSegment::create(name, l.total_size, segment_owner_alive);
              initialize(SegmentView(s.data(), l), "server", "p", 1, getpid());
              std::_Exit(0);  // the name stays behind, its owner's pid now free
              return 0;
            }),
            0);
  // Names `pid` as the owner and dates the segment ten seconds back, as if made before the
  // processes below began (a store's first write to a tmpfs page dates it now).
  const auto leave_owner = [&](int pid) {
    static_cast<SegmentHeader*>(ShmSegment::attach(name).data())->owner_pid.store(pid);
    const int fd = ::shm_open(name.c_str(), O_RDWR, 0);
    ASSERT_GE(fd, 0);
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    const timespec times[2] = {{now.tv_sec - 10, 0}, {now.tv_sec - 10, 0}};
    EXPECT_EQ(::futimens(fd, times), 0);
    ::close(fd);
  };
  leave_owner(1);  // init: alive, and older than the segment
  EXPECT_TRUE(segment_owner_alive(ShmSegment::attach(name)));
  EXPECT_THROW(ShmSegment::create(name, l.total_size, segment_owner_alive), BridgeError);
  saw::testing::ChildProcess later({"/bin/sleep", "30"});  // alive, and younger than the segment
  ASSERT_GT(later.pid(), 0);
  leave_owner(later.pid());
  EXPECT_FALSE(segment_owner_alive(ShmSegment::attach(name))) << "pid " << later.pid() << " began after it";
  EXPECT_TRUE(ShmSegment::create(name, l.total_size, segment_owner_alive).owner());
  EXPECT_THROW(ShmSegment::attach(name), BridgeError);
}

// A manifest's type name field holds 95 characters and a NUL. A longer name is refused at
// export: truncated, it could match another type's name in a client, or none.
struct LongestName {
  static constexpr std::string_view type_name =
      "probe::NNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNN";
  static constexpr std::uint32_t layout_version = 1;
  double x = 0;
};
struct TooLongName {
  static constexpr std::string_view type_name =
      "probe::NNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNNX";
  static constexpr std::uint32_t layout_version = 1;
  double x = 0;
};
static_assert(LongestName::type_name.size() + 1 == sizeof ManifestEntry::arg_type);

template <class T>
class Carrier : public saw::Task {
 public:
  explicit Carrier(std::string name)
      : Task(std::move(name), saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    provide("arm").template add_command_write<T>("set", [](const T&) {});
  }
};

TEST(BridgeLayout, ATypeNameLongerThanItsManifestFieldIsRefusedAtExportNotTruncated) {
  Carrier<TooLongName> over("over" + std::to_string(getpid()));
  try {
    Exporter exporter(over, "arm");
    ADD_FAILURE() << "exported a type name that does not fit the manifest";
  } catch (const BridgeError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(std::string(TooLongName::type_name)), std::string::npos) << "names it whole: " << msg;
    EXPECT_NE(msg.find("96 characters"), std::string::npos) << msg;
    EXPECT_NE(msg.find("95"), std::string::npos) << "says the bound: " << msg;
  }
  EXPECT_THROW(ShmSegment::attach("/saw." + over.name()), BridgeError) << "refused before the segment exists";

  Carrier<LongestName> fits("fits" + std::to_string(getpid()));
  Exporter exporter(fits, "arm");
  Layout l;
  std::string why;
  const ShmSegment s = attach_validated(exporter.segment_name(), l, why);
  ASSERT_EQ(why, "");
  EXPECT_EQ(std::string_view(SegmentView(s.data(), l).manifest()[0].arg_type), LongestName::type_name)
      << "crosses whole";
}

TEST(BridgeLayout, ACommandOrComponentNameLongerThanItsFieldIsRefusedAtExport) {
  class Named : public saw::Task {
   public:
    Named(std::string name, std::string command)
        : Task(std::move(name), saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
      provide("arm").add_command_write<double>(std::move(command), [](const double&) {});
    }
  };
  Named long_command("cmd" + std::to_string(getpid()), std::string(48, 'c'));
  EXPECT_THROW(Exporter(long_command, "arm"), BridgeError);
  Named long_component(std::string(64, 'k'), "set");
  EXPECT_THROW(Exporter(long_component, "arm"), BridgeError);
}

}  // namespace
