// SDO client and server: each against hand-made frames (every abort path, every check of a
// received frame) and against each other over an in-memory bus (expedited and segmented).
#include <gtest/gtest.h>

#include <numeric>
#include <vector>

#include "fake_bus.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sdo_server.hpp"

namespace {

using namespace saw::canopen;
using fake::Endpoint;
using fake::FakeNetwork;
using saw::TimeNs;
using saw::can::Frame;

constexpr std::uint8_t node = 5;
constexpr TimeNs ms = 1'000'000;

constexpr ObjectAddress device_type{0x1000, 0};
constexpr ObjectAddress device_name{0x1008, 0};
constexpr ObjectAddress blob{0x2000, 0};
constexpr ObjectAddress command_only{0x2001, 0};
constexpr ObjectAddress flag{0x2002, 0};
constexpr ObjectAddress controlword{0x6040, 0};
constexpr ObjectAddress mode{0x6060, 0};
constexpr ObjectAddress target_position{0x607A, 0};

LocalDictionary make_dictionary() {
  LocalDictionary d;
  d.add_value(device_type, "Device type", DataType::unsigned32, Access::ro, 0x00020192u);
  Entry name{"Manufacturer device name", DataType::visible_string, Access::const_, {}, {}, {}, 0, false};
  const std::string text = "sawrt simulated drive";
  name.value.assign(text.begin(), text.end());
  d.add(device_name, name);
  d.add(blob, Entry{"Blob", DataType::domain, Access::rw, {}, {}, {}, 200, false});
  d.add_value(command_only, "Command", DataType::unsigned32, Access::wo, 0u);
  d.add_value(flag, "Flag", DataType::boolean, Access::rw, false);
  d.add_value(controlword, "Controlword", DataType::unsigned16, Access::rww, 0u);
  d.add_value(mode, "Modes of operation", DataType::integer8, Access::rw, 0);
  d.add_value(target_position, "Target position", DataType::integer32, Access::rww, 0,
              Number{std::int64_t{-1000000}}, Number{std::int64_t{1000000}});
  // The drive supports CSP, CSV and CST only.
  d.on_write([](ObjectAddress a, std::span<const std::uint8_t> bytes) {
    if (a == mode && (static_cast<std::int8_t>(bytes[0]) < 8 || static_cast<std::int8_t>(bytes[0]) > 10))
      return SdoAbort::invalid_value;
    return SdoAbort::none;
  });
  return d;
}

Frame frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  std::vector<std::uint8_t> v(bytes);
  return saw::can::classic(id, v);
}

std::uint32_t abort_code(const Frame& f) {
  return static_cast<std::uint32_t>(f.data[4] | f.data[5] << 8 | f.data[6] << 16 | f.data[7] << 24);
}

// A client and a server on one in-memory bus.
struct Rig {
  FakeNetwork network;
  saw::can::Bus& unused = network.attach("observer");  // sees all traffic, never polled
  fake::FakeBus& master = network.attach("master");
  fake::FakeBus& drive = network.attach("drive");
  LocalDictionary dictionary = make_dictionary();
  SdoClient client{SdoClientConfig{SdoChannel::of_node(node), 100 * ms, 1024}};
  SdoServer server;
  TimeNs now = 0;

  explicit Rig(bool expedited = true)
      : server(SdoServerConfig{SdoChannel::of_node(node), 100 * ms, 1024, expedited}, dictionary) {}

  int run() {
    return fake::exchange(now, Endpoint<SdoClient>{client, master}, Endpoint<SdoServer>{server, drive});
  }
};

TEST(CanopenSdoAbort, NamesTheStandardCodes) {
  EXPECT_EQ(sdo_abort_name(0x06020000), "object does not exist in the object dictionary");
  EXPECT_EQ(sdo_abort_name(0x05030000), "toggle bit not alternated");
  EXPECT_EQ(sdo_abort_name(0x05040000), "SDO protocol timed out");
  EXPECT_EQ(sdo_abort_name(0x06090011), "sub-index does not exist");
  EXPECT_EQ(sdo_abort_name(0x08000022),
            "data cannot be transferred or stored to the application because of the present device state");
  EXPECT_EQ(sdo_abort_name(0x12345678), "not a standard SDO abort code");
  const std::uint32_t all[] = {
      0x05030000, 0x05040000, 0x05040001, 0x05040002, 0x05040003, 0x05040004, 0x05040005, 0x06010000,
      0x06010001, 0x06010002, 0x06020000, 0x06040041, 0x06040042, 0x06040043, 0x06040047, 0x06060000,
      0x06070010, 0x06070012, 0x06070013, 0x06090011, 0x06090030, 0x06090031, 0x06090032, 0x06090036,
      0x060A0023, 0x08000000, 0x08000020, 0x08000021, 0x08000022, 0x08000023, 0x08000024};
  for (std::uint32_t c : all) EXPECT_NE(sdo_abort_name(c), "not a standard SDO abort code") << std::hex << c;
}

TEST(CanopenSdo, ExpeditedDownloadAndUpload) {
  Rig r;
  ASSERT_TRUE(r.client.download_value(controlword, DataType::unsigned16, 0x000F, r.now));
  r.run();
  ASSERT_EQ(r.client.result().status, SdoStatus::done);
  std::uint16_t cw = 0;
  ASSERT_EQ(r.dictionary.get(controlword, cw), Codec::ok);
  EXPECT_EQ(cw, 0x000F);
  // The request: expedited, size indicated, n = 2 unused bytes.
  ASSERT_GE(r.master.sent.size(), 1u);
  EXPECT_EQ(r.master.sent[0].id, 0x600u + node);
  EXPECT_EQ(r.master.sent[0].data[0], 0x2B);

  ASSERT_TRUE(r.client.upload(device_type, r.now));
  r.run();
  ASSERT_EQ(r.client.result().status, SdoStatus::done);
  std::uint32_t type = 0;
  ASSERT_EQ(r.client.value(DataType::unsigned32, type), Codec::ok);
  EXPECT_EQ(type, 0x00020192u);
  EXPECT_EQ(r.drive.sent.back().id, 0x580u + node);
  EXPECT_EQ(r.drive.sent.back().data[0], 0x43);
}

TEST(CanopenSdo, SegmentedTransfersOfOddLengths) {
  for (const std::size_t length : {0, 1, 7, 8, 13, 100}) {
    SCOPED_TRACE(length);
    Rig r(false);  // segments for uploads of 1..4 bytes too
    std::vector<std::uint8_t> data(length);
    std::iota(data.begin(), data.end(), std::uint8_t{1});
    ASSERT_TRUE(r.client.download(blob, data, r.now, SdoMode::segmented));
    r.run();
    ASSERT_EQ(r.client.result().status, SdoStatus::done) << to_string(r.client.result().abort);
    EXPECT_EQ(r.client.result().size, length);
    EXPECT_EQ(r.dictionary.find(blob)->value, data);
    // Initiate plus one segment per 7 bytes (an empty value still takes one, the last).
    const std::size_t segments = length == 0 ? 1 : (length + 6) / 7;
    EXPECT_EQ(r.master.sent.size(), 1 + segments);
    EXPECT_EQ(r.master.sent.back().data[0] & 0x01, 1) << "the last segment has c set";

    ASSERT_TRUE(r.client.upload(blob, r.now));
    r.run();
    ASSERT_EQ(r.client.result().status, SdoStatus::done) << to_string(r.client.result().abort);
    EXPECT_EQ(std::vector<std::uint8_t>(r.client.data().begin(), r.client.data().end()), data);
    EXPECT_FALSE(r.server.busy());
  }
}

TEST(CanopenSdo, AutomaticModeUsesSegmentsOnlyWhenItMust) {
  Rig r;
  const std::string text(40, 'x');
  std::vector<std::uint8_t> bytes(text.begin(), text.end());
  ASSERT_TRUE(r.client.download(blob, bytes, r.now));
  r.run();
  ASSERT_EQ(r.client.result().status, SdoStatus::done);
  EXPECT_EQ(r.master.sent[0].data[0], 0x21);  // initiate, segmented, size indicated
  ASSERT_TRUE(r.client.upload(device_name, r.now));
  r.run();
  ASSERT_EQ(r.client.result().status, SdoStatus::done);
  EXPECT_EQ(std::string(r.client.data().begin(), r.client.data().end()), "sawrt simulated drive");
  // An empty download has no expedited form: automatic falls back to a segment.
  ASSERT_TRUE(r.client.download(blob, {}, r.now));
  r.run();
  ASSERT_EQ(r.client.result().status, SdoStatus::done);
  EXPECT_TRUE(r.dictionary.find(blob)->value.empty());
}

TEST(CanopenSdo, ServerAbortsWhatTheDictionaryRefuses) {
  struct Case {
    const char* what;
    bool upload;
    ObjectAddress address;
    std::vector<std::uint8_t> data;
    SdoMode mode;
    SdoAbort expected;
  };
  const std::vector<Case> cases = {
      {"unknown object", true, {0x3000, 0}, {}, SdoMode::automatic, SdoAbort::no_object},
      {"unknown object (download)", false, {0x3000, 0}, {1}, SdoMode::automatic, SdoAbort::no_object},
      {"unknown sub-index", true, {0x6040, 1}, {}, SdoMode::automatic, SdoAbort::no_subindex},
      {"read-only", false, device_type, {1, 2, 3, 4}, SdoMode::automatic, SdoAbort::read_only},
      {"constant (segmented)", false, device_name, {'a', 'b'}, SdoMode::segmented, SdoAbort::read_only},
      {"write-only", true, command_only, {}, SdoMode::automatic, SdoAbort::write_only},
      {"too long", false, controlword, {1, 2, 3, 4}, SdoMode::automatic, SdoAbort::length_too_high},
      {"too short", false, controlword, {1}, SdoMode::automatic, SdoAbort::length_too_low},
      {"too long (segmented)", false, controlword, {1, 2, 3}, SdoMode::segmented, SdoAbort::length_too_high},
      {"above the high limit",
       false,
       target_position,
       {0x80, 0x84, 0x1E, 0x00},
       SdoMode::automatic,
       SdoAbort::value_too_high},
      {"below the low limit",
       false,
       target_position,
       {0x80, 0x7B, 0xE1, 0xFF},
       SdoMode::automatic,
       SdoAbort::value_too_low},
      {"not a boolean", false, flag, {2}, SdoMode::automatic, SdoAbort::invalid_value},
      {"refused by the device", false, mode, {1}, SdoMode::automatic, SdoAbort::invalid_value},
      {"longer than the domain", false, blob, std::vector<std::uint8_t>(201), SdoMode::automatic,
       SdoAbort::length_too_high},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    Rig r;
    ASSERT_TRUE(c.upload ? r.client.upload(c.address, r.now)
                         : r.client.download(c.address, c.data, r.now, c.mode));
    r.run();
    EXPECT_EQ(r.client.result().status, SdoStatus::failed);
    EXPECT_EQ(r.client.result().abort, c.expected) << to_string(r.client.result().abort);
    EXPECT_TRUE(r.client.result().remote);
    EXPECT_NE(r.master.sent.back().data[0], 0x80) << "the client does not answer an abort";
    EXPECT_EQ(abort_code(r.drive.sent.back()), static_cast<std::uint32_t>(c.expected));
    EXPECT_EQ(r.drive.sent.back().data[0], 0x80);
  }
  // A write the device accepts after one it refused.
  Rig r;
  ASSERT_TRUE(r.client.download_value(mode, DataType::integer8, 8, r.now));
  r.run();
  EXPECT_EQ(r.client.result().status, SdoStatus::done);
}

// --- the client against hand-made server frames ------------------------------------------

struct ClientRig {
  SdoClient client{SdoClientConfig{SdoChannel::of_node(node), 100 * ms, 64}};
  static constexpr std::uint32_t response = 0x580 + node;
  Frame sent() {
    auto f = client.poll(0);
    EXPECT_TRUE(f.has_value());
    return f.value_or(Frame{});
  }
};

TEST(CanopenSdoClient, TimesOutAndTellsTheServer) {
  ClientRig r;
  ASSERT_TRUE(r.client.upload(controlword, 0));
  EXPECT_EQ(r.sent().data[0], 0x40);
  EXPECT_FALSE(r.client.poll(99 * ms).has_value());
  EXPECT_TRUE(r.client.busy());
  const auto f = r.client.poll(100 * ms);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->id, 0x600u + node);
  EXPECT_EQ(f->data[0], 0x80);
  EXPECT_EQ(abort_code(*f), 0x05040000u);
  EXPECT_EQ(f->data[1], 0x40);
  EXPECT_EQ(f->data[2], 0x60);
  EXPECT_EQ(r.client.result().status, SdoStatus::failed);
  EXPECT_EQ(r.client.result().abort, SdoAbort::timeout);
  EXPECT_FALSE(r.client.result().remote);
  EXPECT_FALSE(r.client.poll(200 * ms).has_value());
}

TEST(CanopenSdoClient, ToggleErrorInAnUploadSegmentAborts) {
  ClientRig r;
  ASSERT_TRUE(r.client.upload(blob, 0));
  r.sent();
  r.client.on_frame(frame(r.response, {0x41, 0x00, 0x20, 0x00, 20, 0, 0, 0}), 1);
  EXPECT_EQ(r.sent().data[0], 0x60);  // first segment request, toggle 0
  r.client.on_frame(frame(r.response, {0x00, 1, 2, 3, 4, 5, 6, 7}), 2);
  EXPECT_EQ(r.sent().data[0], 0x70);                                          // second request, toggle 1
  r.client.on_frame(frame(r.response, {0x00, 8, 9, 10, 11, 12, 13, 14}), 3);  // toggle not alternated
  const Frame a = r.sent();
  EXPECT_EQ(a.data[0], 0x80);
  EXPECT_EQ(abort_code(a), 0x05030000u);
  EXPECT_EQ(r.client.result().abort, SdoAbort::toggle_bit);
}

TEST(CanopenSdoClient, ToggleErrorInADownloadSegmentResponseAborts) {
  ClientRig r;
  const std::vector<std::uint8_t> data(10, 0xAA);
  ASSERT_TRUE(r.client.download(blob, data, 0));
  r.sent();
  r.client.on_frame(frame(r.response, {0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}), 1);
  EXPECT_EQ(r.sent().data[0], 0x00);                                     // segment, toggle 0, 7 bytes
  r.client.on_frame(frame(r.response, {0x30, 0, 0, 0, 0, 0, 0, 0}), 2);  // answers with toggle 1
  EXPECT_EQ(abort_code(r.sent()), 0x05030000u);
  EXPECT_EQ(r.client.result().abort, SdoAbort::toggle_bit);
}

TEST(CanopenSdoClient, ChecksEveryResponseBeforeUsingIt) {
  {  // wrong length
    ClientRig r;
    ASSERT_TRUE(r.client.upload(controlword, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x4B, 0x40, 0x60, 0x00, 0x0F, 0x00, 0x00}), 1);
    EXPECT_EQ(abort_code(r.sent()), 0x05040001u);
    EXPECT_EQ(r.client.result().abort, SdoAbort::command_specifier);
  }
  {  // a download response to an upload
    ClientRig r;
    ASSERT_TRUE(r.client.upload(controlword, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x60, 0x40, 0x60, 0x00, 0, 0, 0, 0}), 1);
    EXPECT_EQ(r.client.result().abort, SdoAbort::command_specifier);
  }
  {  // a response for another object is stale: ignored; the right one completes
    ClientRig r;
    ASSERT_TRUE(r.client.upload(controlword, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x4B, 0x41, 0x60, 0x00, 0x37, 0x02, 0, 0}), 1);
    EXPECT_TRUE(r.client.busy());
    r.client.on_frame(frame(r.response, {0x80, 0x41, 0x60, 0x00, 0, 0, 2, 6}), 1);  // abort for 0x6041
    EXPECT_TRUE(r.client.busy());
    r.client.on_frame(frame(r.response, {0x4B, 0x40, 0x60, 0x00, 0x0F, 0x00, 0, 0}), 2);
    std::uint16_t cw = 0;
    ASSERT_EQ(r.client.result().status, SdoStatus::done);
    ASSERT_EQ(r.client.value(DataType::unsigned16, cw), Codec::ok);
    EXPECT_EQ(cw, 0x000F);
  }
  {  // frames that are not this server's response: other identifiers, remote, extended, FD
    ClientRig r;
    ASSERT_TRUE(r.client.upload(controlword, 0));
    r.sent();
    r.client.on_frame(frame(0x580 + node + 1, {0x4B, 0x40, 0x60, 0x00, 1, 0, 0, 0}), 1);
    Frame rtr = frame(r.response, {0x4B, 0x40, 0x60, 0x00, 1, 0, 0, 0});
    rtr.id |= CAN_RTR_FLAG;
    r.client.on_frame(rtr, 1);
    Frame ext = frame(r.response, {0x4B, 0x40, 0x60, 0x00, 1, 0, 0, 0});
    ext.id |= CAN_EFF_FLAG;
    r.client.on_frame(ext, 1);
    Frame fd = frame(r.response, {0x4B, 0x40, 0x60, 0x00, 1, 0, 0, 0});
    fd.flags = CANFD_FDF;
    r.client.on_frame(fd, 1);
    EXPECT_TRUE(r.client.busy());
    EXPECT_FALSE(r.client.poll(1).has_value());
  }
  {  // an announced size beyond the client's capacity
    ClientRig r;
    ASSERT_TRUE(r.client.upload(blob, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x41, 0x00, 0x20, 0x00, 65, 0, 0, 0}), 1);
    EXPECT_EQ(abort_code(r.sent()), 0x05040005u);
  }
  {  // more segment data than announced
    ClientRig r;
    ASSERT_TRUE(r.client.upload(blob, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x41, 0x00, 0x20, 0x00, 5, 0, 0, 0}), 1);
    r.sent();
    r.client.on_frame(frame(r.response, {0x01, 1, 2, 3, 4, 5, 6, 7}), 2);
    EXPECT_EQ(abort_code(r.sent()), 0x06070010u);
  }
  {  // a last segment that leaves the value shorter than announced
    ClientRig r;
    ASSERT_TRUE(r.client.upload(blob, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x41, 0x00, 0x20, 0x00, 9, 0, 0, 0}), 1);
    r.sent();
    r.client.on_frame(frame(r.response, {0x05, 1, 2, 3, 4, 5, 6, 7}), 2);  // n = 2, c: 5 bytes, last
    EXPECT_EQ(abort_code(r.sent()), 0x06070010u);
  }
  {  // an unknown command specifier in a segment response
    ClientRig r;
    ASSERT_TRUE(r.client.upload(blob, 0));
    r.sent();
    r.client.on_frame(frame(r.response, {0x41, 0x00, 0x20, 0x00, 9, 0, 0, 0}), 1);
    r.sent();
    r.client.on_frame(frame(r.response, {0xE0, 0, 0, 0, 0, 0, 0, 0}), 2);
    EXPECT_EQ(abort_code(r.sent()), 0x05040001u);
  }
}

TEST(CanopenSdoClient, ReceivesAnAbortWithoutAnsweringIt) {
  ClientRig r;
  const std::vector<std::uint8_t> data(20, 1);
  ASSERT_TRUE(r.client.download(blob, data, 0));
  r.sent();
  r.client.on_frame(frame(r.response, {0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0}), 1);
  r.sent();
  r.client.on_frame(frame(r.response, {0x80, 0x00, 0x20, 0x00, 0x22, 0x00, 0x00, 0x08}), 2);
  EXPECT_EQ(r.client.result().status, SdoStatus::failed);
  EXPECT_EQ(r.client.result().abort, SdoAbort::device_state);
  EXPECT_TRUE(r.client.result().remote);
  EXPECT_FALSE(r.client.poll(3).has_value());
  EXPECT_FALSE(r.client.poll(500 * ms).has_value()) << "no timeout after the transfer ended";
}

TEST(CanopenSdoClient, LocalAbortIsSent) {
  ClientRig r;
  ASSERT_TRUE(r.client.upload(blob, 0));
  r.sent();
  EXPECT_FALSE(r.client.upload(blob, 0)) << "one transfer at a time";
  r.client.abort(SdoAbort::general);
  const Frame a = r.sent();
  EXPECT_EQ(abort_code(a), 0x08000000u);
  EXPECT_EQ(r.client.result().status, SdoStatus::failed);
  EXPECT_FALSE(r.client.result().remote);
  EXPECT_TRUE(r.client.upload(blob, 0)) << "a failed transfer leaves the client free";
  EXPECT_FALSE(r.client.download(blob, std::vector<std::uint8_t>(65), 0)) << "beyond capacity";
}

// --- the server against hand-made client frames ------------------------------------------

struct ServerRig {
  LocalDictionary dictionary = make_dictionary();
  SdoServer server{SdoServerConfig{SdoChannel::of_node(node), 100 * ms, 64, true}, dictionary};
  static constexpr std::uint32_t request = 0x600 + node;
  Frame answer(TimeNs now = 0) {
    auto f = server.poll(now);
    EXPECT_TRUE(f.has_value());
    return f.value_or(Frame{});
  }
};

TEST(CanopenSdoServer, AbortsProtocolErrors) {
  {  // toggle bit not alternated
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x21, 0x00, 0x20, 0x00, 14, 0, 0, 0}), 0);
    EXPECT_EQ(r.answer().data[0], 0x60);
    r.server.on_frame(frame(r.request, {0x00, 1, 2, 3, 4, 5, 6, 7}), 1);
    EXPECT_EQ(r.answer().data[0], 0x20);
    r.server.on_frame(frame(r.request, {0x01, 1, 2, 3, 4, 5, 6, 7}), 2);
    const Frame a = r.answer();
    EXPECT_EQ(a.data[0], 0x80);
    EXPECT_EQ(abort_code(a), 0x05030000u);
    EXPECT_EQ(a.data[1], 0x00);
    EXPECT_EQ(a.data[2], 0x20);
    EXPECT_FALSE(r.server.busy());
  }
  {  // a segment with no transfer
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x00, 1, 2, 3, 4, 5, 6, 7}), 0);
    EXPECT_EQ(abort_code(r.answer()), 0x05040001u);
  }
  {  // block download: not supported
    ServerRig r;
    r.server.on_frame(frame(r.request, {0xC6, 0x00, 0x20, 0x00, 10, 0, 0, 0}), 0);
    EXPECT_EQ(abort_code(r.answer()), 0x05040001u);
  }
  {  // a request shorter than 8 bytes
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x40, 0x40, 0x60, 0x00}), 0);
    const Frame a = r.answer();
    EXPECT_EQ(abort_code(a), 0x05040001u);
    EXPECT_EQ(a.data[1], 0x40);
    EXPECT_EQ(a.data[2], 0x60);
  }
  {  // more bytes than announced
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x21, 0x00, 0x20, 0x00, 5, 0, 0, 0}), 0);
    r.answer();
    r.server.on_frame(frame(r.request, {0x01, 1, 2, 3, 4, 5, 6, 7}), 1);
    EXPECT_EQ(abort_code(r.answer()), 0x06070012u);
  }
  {  // fewer bytes than announced
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x21, 0x00, 0x20, 0x00, 9, 0, 0, 0}), 0);
    r.answer();
    r.server.on_frame(frame(r.request, {0x03, 1, 2, 3, 4, 5, 6, 7}), 1);  // n = 1, last: 6 bytes
    EXPECT_EQ(abort_code(r.answer()), 0x06070013u);
    EXPECT_TRUE(r.dictionary.find(blob)->value.empty()) << "nothing stored";
  }
  {  // an announced size beyond the server's buffer
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x21, 0x00, 0x20, 0x00, 65, 0, 0, 0}), 0);
    EXPECT_EQ(abort_code(r.answer()), 0x05040005u);
  }
  {  // the client went quiet mid-transfer
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x21, 0x00, 0x20, 0x00, 20, 0, 0, 0}), 0);
    r.answer();
    r.server.on_frame(frame(r.request, {0x00, 1, 2, 3, 4, 5, 6, 7}), 50 * ms);
    r.answer(50 * ms);
    EXPECT_FALSE(r.server.poll(149 * ms).has_value());
    const Frame a = r.answer(150 * ms);
    EXPECT_EQ(abort_code(a), 0x05040000u);
    EXPECT_FALSE(r.server.busy());
    EXPECT_EQ(r.server.last_abort(), SdoAbort::timeout);
  }
  {  // the client aborts: no answer, the transfer is over
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}), 0);
    EXPECT_EQ(r.answer().data[0], 0x41);  // the name is segmented
    EXPECT_TRUE(r.server.busy());
    r.server.on_frame(frame(r.request, {0x80, 0x08, 0x10, 0x00, 0, 0, 0, 0x08}), 1);
    EXPECT_FALSE(r.server.busy());
    EXPECT_FALSE(r.server.poll(1).has_value());
    EXPECT_FALSE(r.server.poll(500 * ms).has_value());
  }
  {  // toggle error on an upload segment request
    ServerRig r;
    r.server.on_frame(frame(r.request, {0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0}), 0);
    r.answer();
    r.server.on_frame(frame(r.request, {0x70, 0, 0, 0, 0, 0, 0, 0}), 1);
    EXPECT_EQ(abort_code(r.answer()), 0x05030000u);
  }
}

TEST(CanopenSdoServer, ExpeditedDownloadWithoutSizeTakesTheObjectsSize) {
  ServerRig r;
  r.server.on_frame(frame(r.request, {0x22, 0x40, 0x60, 0x00, 0x06, 0x00, 0xEE, 0xEE}), 0);  // e, no s
  EXPECT_EQ(r.answer().data[0], 0x60);
  std::uint16_t cw = 0;
  ASSERT_EQ(r.dictionary.get(controlword, cw), Codec::ok);
  EXPECT_EQ(cw, 6);
}

TEST(CanopenDictionary, RefusesBadEntriesAtSetUp) {
  LocalDictionary d;
  d.add_value(controlword, "Controlword", DataType::unsigned16, Access::rw, 0u);
  EXPECT_THROW(d.add_value(controlword, "again", DataType::unsigned16, Access::rw, 0u),
               std::invalid_argument);
  EXPECT_THROW(d.add_value(mode, "Mode", DataType::integer8, Access::rw, 300), std::invalid_argument);
  EXPECT_THROW(d.add_value(target_position, "Target", DataType::integer32, Access::rw, 5,
                           Number{std::int64_t{10}}, Number{std::int64_t{20}}),
               std::invalid_argument);
  EXPECT_EQ(d.set(controlword, 70000), Codec::too_high);
  EXPECT_EQ(d.set(controlword, 6), Codec::ok);
  EXPECT_TRUE(d.has_index(0x6040));
  EXPECT_FALSE(d.has_index(0x6041));
  EXPECT_EQ(access_from_string("RWW"), Access::rww);
  EXPECT_EQ(access_from_string("Const"), Access::const_);
  EXPECT_EQ(access_from_string("rx"), std::nullopt);
}

}  // namespace
