// The virtual bus in one process: vcan's broadcast semantics, FD, overruns, filters, the
// dead-producer rule, and what it does with a segment a bad peer wrote or never finished.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <random>
#include <thread>

#include "can_test_support.hpp"

namespace {

using namespace saw::can;
using saw::can::testing::config;
using saw::can::testing::drain;
using saw::can::testing::numbered;
using saw::can::testing::RawSegment;
using saw::can::testing::same_frame;
using saw::can::testing::ScopedBusName;
using saw::can::testing::sequence_of;

// Writes a segment by hand, as a foreign or broken creator would, for the attach checks.
void write_segment(const std::string& name, std::size_t size, std::uint64_t magic, std::uint32_t version,
                   std::uint64_t capacity, std::uint64_t total) {
  const std::string shm = virtual_bus_shm_name(name);
  const int fd = ::shm_open(shm.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(size)), 0);
  void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  ::close(fd);
  ASSERT_NE(p, MAP_FAILED);
  auto* h = static_cast<detail::VirtualBusHeader*>(p);
  h->version.store(version);
  h->slot_size.store(sizeof(detail::VirtualBusSlot));
  h->capacity.store(capacity);
  h->total_size.store(total);
  h->magic.store(magic);
  ::munmap(p, size);
}

std::string open_error(const std::string& name, VirtualBusOptions options = {}) {
  try {
    VirtualBus bus(config("virtual:" + name), name, options);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(VirtualBus, TwoAttachmentsSeeEachOthersFramesButNotTheirOwn) {
  ScopedBusName bus;
  const auto a = open_bus(config(bus.uri()));
  const auto b = open_bus(config(bus.uri()));
  EXPECT_EQ(a->name(), bus.uri());
  const std::uint8_t payload[] = {0x11, 0x22, 0x33};
  const Frame from_a = classic(0x123, payload);
  Frame from_b = numbered(0x7FF, 42);
  from_b.id = 0x1ABCDEF0 | CAN_EFF_FLAG;
  Frame rtr;
  rtr.id = 0x321 | CAN_RTR_FLAG;
  rtr.len = 2;
  const Frame to_b[] = {from_a, rtr};
  const saw::TimeNs before = saw::monotonic_now();
  ASSERT_EQ(a->send(to_b), 2u);
  ASSERT_EQ(b->send(std::span<const Frame>(&from_b, 1)), 1u);

  const auto at_b = drain(*b);
  ASSERT_EQ(at_b.size(), 2u);
  EXPECT_TRUE(same_frame(at_b[0].frame, from_a));
  EXPECT_TRUE(same_frame(at_b[1].frame, rtr));
  EXPECT_GE(at_b[0].time, before);
  EXPECT_LE(at_b[0].time, saw::monotonic_now());
  const auto at_a = drain(*a);
  ASSERT_EQ(at_a.size(), 1u);
  EXPECT_TRUE(same_frame(at_a[0].frame, from_b));
  EXPECT_TRUE(at_a[0].frame.extended());

  EXPECT_EQ(a->counters().sent, 2u);
  EXPECT_EQ(a->counters().received, 1u);
  EXPECT_EQ(b->counters().received, 2u);
  EXPECT_EQ(b->counters().overruns + b->counters().malformed + b->counters().send_refused, 0u);
  EXPECT_EQ(a->state(), BusState::error_active);
}

TEST(VirtualBus, AThirdAttachmentSeesBothAndOnlyWhatWasSentAfterItAttached) {
  ScopedBusName bus;
  const auto a = open_bus(config(bus.uri()));
  const auto b = open_bus(config(bus.uri()));
  const Frame early = numbered(1, 0);
  ASSERT_EQ(a->send(std::span<const Frame>(&early, 1)), 1u);
  const auto c = open_bus(config(bus.uri()));
  const Frame late_a = numbered(1, 1), late_b = numbered(2, 0);
  ASSERT_EQ(a->send(std::span<const Frame>(&late_a, 1)), 1u);
  ASSERT_EQ(b->send(std::span<const Frame>(&late_b, 1)), 1u);
  const auto at_c = drain(*c);
  ASSERT_EQ(at_c.size(), 2u);
  EXPECT_TRUE(same_frame(at_c[0].frame, late_a));
  EXPECT_TRUE(same_frame(at_c[1].frame, late_b));
  EXPECT_EQ(drain(*b).size(), 2u);  // early and late_a
}

TEST(VirtualBus, FdFramesReachFdReadersOnlyAndClassicAttachmentsCannotSendThem) {
  ScopedBusName bus;
  const auto fd_a = open_bus(config(bus.uri(), true));
  const auto fd_b = open_bus(config(bus.uri(), true));
  const auto classic_c = open_bus(config(bus.uri(), false));
  Frame fd;
  fd.id = 0x12345 | CAN_EFF_FLAG;
  fd.flags = CANFD_FDF | CANFD_BRS;
  fd.len = 64;
  for (int i = 0; i < 64; ++i) fd.data[i] = static_cast<std::uint8_t>(i * 3);
  const Frame small = numbered(5, 9);
  const Frame both[] = {fd, small};
  ASSERT_EQ(fd_a->send(both), 2u);
  const auto at_b = drain(*fd_b);
  ASSERT_EQ(at_b.size(), 2u);
  EXPECT_TRUE(at_b[0].frame.fd());
  EXPECT_EQ(at_b[0].frame.flags, CANFD_FDF | CANFD_BRS);
  EXPECT_TRUE(same_frame(at_b[0].frame, fd));
  const auto at_c = drain(*classic_c);  // as a CAN_RAW socket without CAN_RAW_FD_FRAMES
  ASSERT_EQ(at_c.size(), 1u);
  EXPECT_TRUE(same_frame(at_c[0].frame, small));
  EXPECT_EQ(classic_c->send(std::span<const Frame>(&fd, 1)), 0u);
  EXPECT_EQ(classic_c->counters().send_refused, 1u);
}

TEST(VirtualBus, SendRefusesMalformedFramesAndStopsThere) {
  ScopedBusName bus;
  const auto a = open_bus(config(bus.uri()));
  const auto b = open_bus(config(bus.uri()));
  Frame too_long = numbered(1, 1);
  too_long.len = 9;
  Frame bad_id = numbered(1, 2);
  bad_id.id = 0x800;  // 12 bits without CAN_EFF_FLAG
  const Frame frames[] = {numbered(1, 0), too_long, numbered(1, 3)};
  EXPECT_EQ(a->send(frames), 1u);
  EXPECT_EQ(a->send(std::span<const Frame>(&bad_id, 1)), 0u);
  EXPECT_EQ(a->counters().sent, 1u);
  EXPECT_EQ(a->counters().send_refused, 3u);
  EXPECT_EQ(drain(*b).size(), 1u);
}

TEST(VirtualBus, AReaderThatFallsMoreThanARingBehindSkipsAheadAndCountsTheLoss) {
  ScopedBusName bus;
  const auto writer = open_bus(config(bus.uri(), false, 16));
  const auto reader = open_bus(config(bus.uri(), false, 16));
  constexpr std::uint32_t sent = 100;
  for (std::uint32_t i = 0; i < sent; ++i) {
    const Frame f = numbered(1, i);
    ASSERT_EQ(writer->send(std::span<const Frame>(&f, 1)), 1u);
  }
  const auto got = drain(*reader, 4);
  const auto c = reader->counters();
  EXPECT_GT(c.overruns, 0u);
  EXPECT_EQ(c.received + c.overruns, sent) << "every frame is either read or counted as lost";
  ASSERT_FALSE(got.empty());
  EXPECT_LE(got.size(), 16u);
  for (std::size_t i = 0; i < got.size(); ++i)  // the newest ones, in order
    EXPECT_EQ(sequence_of(got[i].frame), sent - got.size() + i);
  // Back in step: the next frame arrives normally.
  const Frame next = numbered(1, sent);
  ASSERT_EQ(writer->send(std::span<const Frame>(&next, 1)), 1u);
  const auto after = drain(*reader);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(sequence_of(after[0].frame), sent);
}

TEST(VirtualBus, FiltersWorkAsCanRawFilters) {
  ScopedBusName bus;
  const auto writer = open_bus(config(bus.uri()));
  BusConfig filtered = config(bus.uri());
  filtered.filters = {{0x100, 0x700}, {0x1234 | CAN_EFF_FLAG, CAN_EFF_MASK | CAN_EFF_FLAG}};
  const auto reader = open_bus(filtered);
  Frame ext = numbered(0, 0);
  ext.id = 0x1234 | CAN_EFF_FLAG;
  Frame std_1234 = numbered(0x234, 0);  // same low bits, standard: no match for the EFF filter
  const Frame frames[] = {numbered(0x100, 1), numbered(0x1FF, 2), numbered(0x200, 3), ext, std_1234};
  ASSERT_EQ(writer->send(frames), 5u);
  const auto got = drain(*reader);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].frame.id, 0x100u);
  EXPECT_EQ(got[1].frame.id, 0x1FFu);
  EXPECT_EQ(got[2].frame.id, 0x1234u | CAN_EFF_FLAG);
}

TEST(VirtualBus, TheBusOutlivesItsAttachmentsUntilRemoved) {
  ScopedBusName bus;
  {
    const auto a = open_bus(config(bus.uri()));
    EXPECT_TRUE(dynamic_cast<VirtualBus&>(*a).created());
  }
  EXPECT_EQ(::access(("/dev/shm" + virtual_bus_shm_name(bus.name())).c_str(), F_OK), 0);
  {
    // Attaching to an existing bus takes its ring size, whatever this opener asked for.
    const auto b = open_bus(config(bus.uri(), false, 64));
    EXPECT_FALSE(dynamic_cast<VirtualBus&>(*b).created());
    EXPECT_EQ(dynamic_cast<VirtualBus&>(*b).capacity(), 4096u);
  }
  EXPECT_TRUE(remove_virtual_bus(bus.name()));
  EXPECT_FALSE(remove_virtual_bus(bus.name()));
}

TEST(VirtualBus, AttachmentsInOneProcessShareOneMappingUntilTheBusIsRecreated) {
  ScopedBusName bus;
  VirtualBus a(config(bus.uri()), bus.name());
  VirtualBus b(config(bus.uri()), bus.name());
  EXPECT_EQ(a.mapping_address(), b.mapping_address());
  EXPECT_NE(a.attachment_id(), b.attachment_id());
  ASSERT_TRUE(remove_virtual_bus(bus.name()));
  VirtualBus c(config(bus.uri()), bus.name());  // a new segment: its own mapping
  EXPECT_TRUE(c.created());
  EXPECT_NE(c.mapping_address(), a.mapping_address());
}

TEST(VirtualBus, OpenBusNamesTheBusAndTheReasonInItsErrors) {
  const auto message = [](const std::string& uri, std::size_t ring = 4096) -> std::string {
    try {
      (void)open_bus(config(uri, false, ring));
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message("vcan0").find("'vcan0'"), std::string::npos);
  EXPECT_NE(message("vcan0").find("socketcan:<ifname> or virtual:<name>"), std::string::npos);
  EXPECT_NE(message("virtual:").find("1 to 64 characters"), std::string::npos);
  EXPECT_NE(message("virtual:a/b").find("'virtual:a/b'"), std::string::npos);
  EXPECT_NE(message("virtual:ring1000", 1000).find("not a power of two"), std::string::npos);
}

TEST(VirtualBus, AttachRefusesASegmentThatFailsItsChecksWithTheReason) {
  const auto size = detail::virtual_bus_size(8);
  const std::uint64_t magic = detail::virtual_bus_magic;
  const std::uint32_t version = detail::virtual_bus_version;
  struct Case {
    const char* what;
    std::size_t size;
    std::uint64_t magic;
    std::uint32_t version;
    std::uint64_t capacity, total;
  };
  const Case cases[] = {
      {"not a sawrt virtual CAN bus (magic 0x1234)", size, 0x1234, version, 8, size},
      {"layout version 99", size, magic, 99, 8, size},
      {"capacity 6 is not a power of two", size, magic, version, 6, size},
      {"capacity 0 is not a power of two", size, magic, version, 0, size},
      {"capacity 4611686018427387904 is not a power of two from 2 to 1048576", size, magic, version,
       1ULL << 62, size},
      {"does not match 16 slots", size, magic, version, 16, detail::virtual_bus_size(16)},
      {"does not match 8 slots", size, magic, version, 8, size + 128},
  };
  for (const auto& c : cases) {
    ScopedBusName bus("bad");
    write_segment(bus.name(), c.size, c.magic, c.version, c.capacity, c.total);
    const std::string e = open_error(bus.name());
    EXPECT_NE(e.find(c.what), std::string::npos) << e;
    EXPECT_NE(e.find("virtual:" + bus.name()), std::string::npos) << e;
    EXPECT_NE(e.find("remove it"), std::string::npos) << e;
  }
}

TEST(VirtualBus, AttachWaitsForTheCreatorThenGivesUpOnOneThatNeverPublished) {
  ScopedBusName bus;
  const auto size = detail::virtual_bus_size(8);
  write_segment(bus.name(), size, 0, detail::virtual_bus_version, 8, size);
  VirtualBusOptions quick;
  quick.attach_timeout = 30'000'000;
  const std::string e = open_error(bus.name(), quick);
  EXPECT_NE(e.find("not published"), std::string::npos) << e;
  // A creator that publishes while we wait is found.
  std::thread creator([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    RawSegment raw(bus.name());
    raw.header().magic.store(detail::virtual_bus_magic, std::memory_order_release);
  });
  EXPECT_NO_THROW(VirtualBus(config(bus.uri()), bus.name()));
  creator.join();
}

TEST(VirtualBus, ABadPeersSlotsAreCountedAsMalformedAndNeverReturned) {
  ScopedBusName bus;
  const auto reader = open_bus(config(bus.uri(), false, 16));
  RawSegment raw(bus.name());
  std::mt19937_64 rng(7);
  // Slots that claim to hold tickets 0..3, with garbage for payload: the check word fails.
  for (std::uint64_t t = 0; t < 4; ++t) {
    auto& s = raw.slot(t);
    for (auto& w : s.frame) w.store(rng());
    s.check.store(rng());
    s.sequence.store(2 * t + 2);
  }
  // Ticket 4: a consistent check word over a frame that is not well formed (length 77).
  Frame bad = numbered(1, 0);
  bad.len = 77;
  const auto words = detail::frame_to_words(bad);
  auto& s4 = raw.slot(4);
  for (std::size_t i = 0; i < words.size(); ++i) s4.frame[i].store(words[i]);
  s4.time.store(0);
  s4.writer.store(999);
  s4.check.store(detail::slot_check(4, 0, 999, words));
  s4.sequence.store(2 * 4 + 2);
  // Ticket 5: a well-formed frame whose check word does not match it (a torn mix of two
  // producers looks like this: each word plausible, the whole not what anyone wrote).
  const auto good = detail::frame_to_words(numbered(1, 5));
  auto& s5 = raw.slot(5);
  for (std::size_t i = 0; i < good.size(); ++i) s5.frame[i].store(good[i]);
  s5.time.store(0);
  s5.writer.store(999);
  s5.check.store(detail::slot_check(5, 0, 999, good) ^ 1);
  s5.sequence.store(2 * 5 + 2);
  raw.header().write_ticket.store(6);
  EXPECT_TRUE(drain(*reader).empty());
  EXPECT_EQ(reader->counters().malformed, 6u);
  // Honest traffic after it still flows.
  const auto writer = open_bus(config(bus.uri()));
  const Frame f = numbered(3, 3);
  ASSERT_EQ(writer->send(std::span<const Frame>(&f, 1)), 1u);
  const auto got = drain(*reader);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_TRUE(same_frame(got[0].frame, f));
}

TEST(VirtualBus, RandomWritesAllOverTheSegmentNeverCrashAReaderOrAWriter) {
  ScopedBusName bus;
  const auto reader = open_bus(config(bus.uri(), true, 64));
  const auto writer = open_bus(config(bus.uri(), true, 64));
  RawSegment raw(bus.name());
  std::mt19937_64 rng(11);
  std::vector<Received> out(32);
  std::uint64_t returned = 0;
  for (int round = 0; round < 2000; ++round) {
    // A burst of random bytes anywhere past the magic (the fields a running peer could hit).
    for (int k = 0; k < 16; ++k) {
      const std::size_t at = 8 + rng() % (raw.size() - 16);
      const std::uint64_t v = rng();
      std::memcpy(raw.bytes() + at, &v, 8);
    }
    const Frame f = numbered(static_cast<std::uint32_t>(round), static_cast<std::uint32_t>(round));
    (void)writer->send(std::span<const Frame>(&f, 1));
    const std::size_t n = reader->receive(out);
    ASSERT_LE(n, out.size());
    for (std::size_t i = 0; i < n; ++i) EXPECT_TRUE(well_formed(out[i].frame));
    returned += n;
  }
  EXPECT_GT(reader->counters().malformed, 0u);
  EXPECT_EQ(reader->counters().received, returned);
}

TEST(VirtualBus, AProducerThatDiedMidWriteStallsReadersOnlyForTheGracePeriod) {
  ScopedBusName bus;
  VirtualBusOptions options;
  options.incomplete_grace = 20'000'000;
  VirtualBus reader(config(bus.uri()), bus.name(), options);
  const auto writer = open_bus(config(bus.uri()));
  RawSegment raw(bus.name());
  // The dead producer: took ticket 0, marked its slot "being written", never finished.
  ASSERT_EQ(raw.header().write_ticket.fetch_add(1), 0u);
  raw.slot(0).sequence.store(1);
  const Frame frames[] = {numbered(1, 0), numbered(1, 1), numbered(1, 2)};
  ASSERT_EQ(writer->send(frames), 3u);
  std::vector<Received> out(8);
  EXPECT_EQ(reader.receive(out), 0u) << "the frames behind the incomplete slot wait";
  const auto start = saw::monotonic_now();
  std::size_t n = 0;
  while (n == 0 && saw::monotonic_now() - start < 2'000'000'000) n = reader.receive(out);
  EXPECT_GE(saw::monotonic_now() - start, 15'000'000);
  ASSERT_EQ(n, 3u);
  for (std::uint32_t i = 0; i < 3; ++i) EXPECT_EQ(sequence_of(out[i].frame), i);
  EXPECT_EQ(reader.abandoned(), 1u);
  EXPECT_EQ(reader.counters().overruns, 1u);
}

TEST(VirtualBus, AnIncompleteSlotAFullRingBehindIsSkippedAtOnce) {
  ScopedBusName bus;
  VirtualBusOptions patient;
  patient.incomplete_grace = 3'600'000'000'000;  // an hour: only the ring rule can apply
  VirtualBus reader(config(bus.uri(), false, 8), bus.name(), patient);
  const auto writer = open_bus(config(bus.uri()));
  RawSegment raw(bus.name());
  ASSERT_EQ(raw.header().write_ticket.fetch_add(1), 0u);
  raw.slot(0).sequence.store(1);  // dead at ticket 0
  for (std::uint32_t i = 0; i < 10; ++i) {
    const Frame f = numbered(1, i);
    ASSERT_EQ(writer->send(std::span<const Frame>(&f, 1)), 1u);
  }
  // Ticket 8 took the dead producer's slot over (a producer a full ring late never holds it).
  EXPECT_EQ(raw.slot(0).sequence.load(), 2u * 8 + 2);
  const auto got = drain(reader);
  const auto c = reader.counters();
  EXPECT_EQ(c.received + c.overruns, 11u);
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(sequence_of(got.back().frame), 9u);
  for (std::size_t i = 1; i < got.size(); ++i)
    EXPECT_EQ(sequence_of(got[i].frame), sequence_of(got[i - 1].frame) + 1);
}

TEST(VirtualBus, AProducerLappedBeforeItFinishesLosesItsFrameNotTheRing) {
  ScopedBusName bus;
  VirtualBus slow(config(bus.uri(), false, 4), bus.name());
  const auto reader = open_bus(config(bus.uri()));
  RawSegment raw(bus.name());
  // Slot 1 already holds ticket 5: a producer holding ticket 1 comes a full ring too late.
  raw.header().write_ticket.store(1);
  raw.slot(1).sequence.store(2 * 5 + 2);
  const Frame late = numbered(2, 0);
  EXPECT_EQ(slow.send(std::span<const Frame>(&late, 1)), 1u);  // accepted: the ring took it
  EXPECT_EQ(slow.lapped_sends(), 1u);
  EXPECT_EQ(raw.slot(1).sequence.load(), 2u * 5 + 2) << "the newer slot was not overwritten";
}

}  // namespace
