// EDS/DCF parsing: a vendor-style file for a CiA 402 drive (tests/canopen/data/drive.eds), the
// PDO mappings and the dictionary made from it, and malformed files, each error located.
#include "saw/canopen/eds.hpp"

#include <gtest/gtest.h>

#include <string>

#include "fake_bus.hpp"
#include "saw/canopen/cia402.hpp"
#include "saw/canopen/sdo_client.hpp"
#include "saw/canopen/sdo_server.hpp"

namespace {

using namespace saw::canopen;
using saw::deploy::ConfigError;

const std::string drive_eds = std::string(SAW_CANOPEN_TEST_DATA) + "/drive.eds";

template <class T>
T number(const Eds& eds, ObjectAddress a, std::uint8_t node) {
  const auto v = eds.value(a, node);
  EXPECT_TRUE(v.has_value()) << to_string(a);
  T out{};
  EXPECT_EQ(to_value(v.value_or(std::uint64_t{0}), out), Codec::ok) << to_string(a);
  return out;
}

TEST(CanopenEds, ReadsAVendorStyleDriveFile) {
  const Eds eds = load_eds(drive_eds);
  EXPECT_EQ(eds.device.vendor_name, "Sawrt Motion");
  EXPECT_EQ(eds.device.vendor_number, 0x5A7u);
  EXPECT_EQ(eds.device.product_number, 0x00402001u);
  EXPECT_EQ(eds.device.revision_number, 0x00010003u);
  EXPECT_EQ(eds.device.baud_rates, (std::vector<unsigned>{125, 250, 500, 1000}));
  EXPECT_EQ(eds.device.rx_pdos, 2);
  EXPECT_EQ(eds.device.tx_pdos, 2);
  EXPECT_TRUE(eds.device.lss_supported);
  EXPECT_EQ(eds.objects.size(), 45u);
  EXPECT_FALSE(eds.node_id.has_value()) << "an EDS, not a DCF";

  const EdsEntry* cw = eds.find(cia402::object::controlword);
  ASSERT_NE(cw, nullptr);
  EXPECT_EQ(cw->name, "Controlword");
  EXPECT_EQ(cw->type, DataType::unsigned16);
  EXPECT_EQ(cw->access, Access::rww);
  EXPECT_TRUE(cw->pdo_mapping);
  for (const ObjectAddress a : {cia402::object::statusword, cia402::object::modes_of_operation,
                                cia402::object::modes_of_operation_display,
                                cia402::object::position_actual_value, cia402::object::velocity_actual_value,
                                cia402::object::target_torque, cia402::object::torque_actual_value,
                                cia402::object::target_position, cia402::object::target_velocity})
    EXPECT_NE(eds.find(a), nullptr) << to_string(a);
  EXPECT_EQ(eds.find(cia402::object::target_torque)->type, DataType::integer16);
  EXPECT_EQ(number<std::int8_t>(eds, cia402::object::modes_of_operation, 1), 8);
  EXPECT_EQ(number<std::uint32_t>(eds, cia402::object::supported_drive_modes, 1), 0x380u);
  EXPECT_EQ(eds.objects.at(0x1018).type, ObjectType::record);
  EXPECT_EQ(eds.objects.at(0x1018).sub_number, 5);
  EXPECT_EQ(number<std::uint32_t>(eds, {0x1018, 1}, 1), 0x5A7u);
}

TEST(CanopenEds, ResolvesNodeIdOctalRealAndLimits) {
  const Eds eds = load_eds(drive_eds);
  EXPECT_EQ(number<std::uint32_t>(eds, {0x1014, 0}, 5), 0x85u);
  EXPECT_EQ(number<std::uint32_t>(eds, {0x1200, 1}, 5), 0x605u);
  EXPECT_EQ(number<std::uint32_t>(eds, {0x1801, 1}, 9), 0x289u) << "0x280+$NODEID";
  EXPECT_TRUE(eds.find({0x1014, 0})->default_value->node_relative);
  EXPECT_EQ(number<std::int16_t>(eds, {0x2002, 0}, 1), 15) << "017 is octal";
  const EdsEntry* filter = eds.find({0x2002, 0});
  EXPECT_EQ(compare(*filter->low, Number{std::int64_t{-64}}), 0);
  EXPECT_EQ(compare(*filter->high, Number{std::int64_t{64}}), 0);
  EXPECT_DOUBLE_EQ(number<double>(eds, {0x2001, 0}, 1), 0.75);
  EXPECT_EQ(eds.find({0x2001, 0})->type, DataType::real32);
  const EdsEntry* name = eds.find({0x1008, 0});
  EXPECT_EQ(std::string(name->default_value->bytes.begin(), name->default_value->bytes.end()),
            "SD-402 test drive");
  EXPECT_EQ(name->access, Access::const_);
  // CompactSubObj: sub 0 holds the count, the names come from [1016Name].
  EXPECT_EQ(number<std::uint8_t>(eds, {0x1016, 0}, 1), 2);
  EXPECT_EQ(eds.find({0x1016, 1})->name, "Consumer heartbeat time master");
  EXPECT_EQ(eds.find({0x1016, 2})->type, DataType::unsigned32);
  EXPECT_EQ(eds.find({0x1016, 3}), nullptr);
}

TEST(CanopenEds, PdoMappingsFromTheDefaults) {
  const Eds eds = load_eds(drive_eds);
  const auto maps = eds_pdo_mappings(eds, 5);
  ASSERT_EQ(maps.size(), 4u);
  const PdoMapping& r1 = maps[0];
  EXPECT_EQ(r1.kind, PdoKind::rpdo);
  EXPECT_TRUE(r1.enabled);
  EXPECT_EQ(r1.cob_id, 0x205u);
  EXPECT_EQ(r1.transmission, 1);
  ASSERT_EQ(r1.count, 2);
  EXPECT_EQ(r1.entries[0].address, cia402::object::controlword);
  EXPECT_EQ(r1.entries[1].type, DataType::integer32);
  EXPECT_FALSE(maps[1].enabled) << "RPDO2 ships disabled (bit 31)";
  EXPECT_EQ(maps[1].count, 3);
  const PdoMapping& t1 = maps[2];
  EXPECT_EQ(t1.kind, PdoKind::tpdo);
  EXPECT_EQ(t1.cob_id, 0x185u);
  ASSERT_EQ(t1.count, 3);
  EXPECT_EQ(t1.entries[2].type, DataType::integer16) << "types from the mapped objects";
  EXPECT_EQ(t1.bytes(), 8u);
  const PdoMapping& t2 = maps[3];
  EXPECT_EQ(t2.transmission, 0xFF);
  EXPECT_EQ(t2.inhibit_time, 10);
  EXPECT_EQ(t2.event_timer, 100);
  EXPECT_EQ(t2.entries[2].type, DataType::integer8);
  PdoPacker p(t1);  // usable as is
  EXPECT_EQ(p.frame().len, 8);
}

TEST(CanopenEds, TheDictionaryItDescribesServesSdoAndTakesAPdoConfiguration) {
  const Eds eds = load_eds(drive_eds);
  LocalDictionary dictionary = make_dictionary(eds, 5);
  std::uint32_t emcy = 0;
  ASSERT_EQ(dictionary.get({0x1014, 0}, emcy), Codec::ok);
  EXPECT_EQ(emcy, 0x85u);

  fake::FakeNetwork network;
  fake::FakeBus& master = network.attach("master");
  fake::FakeBus& drive = network.attach("drive");
  SdoClient client(SdoClientConfig{SdoChannel::of_node(5)});
  SdoServer server(SdoServerConfig{SdoChannel::of_node(5)}, dictionary);
  const auto run = [&] {
    fake::exchange(0, fake::Endpoint<SdoClient>{client, master}, fake::Endpoint<SdoServer>{server, drive});
  };

  ASSERT_TRUE(client.upload({0x1008, 0}, 0));
  run();
  EXPECT_EQ(std::string(client.data().begin(), client.data().end()), "SD-402 test drive");
  ASSERT_TRUE(client.download_value({0x2000, 0}, DataType::unsigned32, 20000u, 0));
  run();
  EXPECT_EQ(client.result().abort, SdoAbort::value_too_high) << "HighLimit=10000";
  ASSERT_TRUE(client.download_value(cia402::object::modes_of_operation, DataType::integer8, 11, 0));
  run();
  EXPECT_EQ(client.result().abort, SdoAbort::value_too_high);
  ASSERT_TRUE(client.download_value({0x1018, 1}, DataType::unsigned32, 1u, 0));
  run();
  EXPECT_EQ(client.result().abort, SdoAbort::read_only);

  // A master's TPDO1 configuration, run through the SDO client before NMT start.
  PdoMapping t1;
  t1.kind = PdoKind::tpdo;
  t1.number = 1;
  t1.cob_id = 0x185;
  t1.map(cia402::object::statusword, DataType::unsigned16)
      .map(cia402::object::velocity_actual_value, DataType::integer32)
      .map(cia402::object::torque_actual_value, DataType::integer16);
  for (const SdoWrite& w : configuration_writes(t1)) {
    ASSERT_TRUE(client.download_value(w.address, w.type, w.value, 0));
    run();
    ASSERT_EQ(client.result().status, SdoStatus::done)
        << to_string(w.address) << ": " << to_string(client.result().abort);
  }
  std::uint32_t entry = 0;
  ASSERT_EQ(dictionary.get({0x1A00, 2}, entry), Codec::ok);
  EXPECT_EQ(entry, 0x606C0020u);
  std::uint32_t cob = 0;
  ASSERT_EQ(dictionary.get({0x1800, 1}, cob), Codec::ok);
  EXPECT_EQ(cob, 0x185u);
}

TEST(CanopenEds, DcfCommissioningAndParameterValues) {
  const std::string dcf = R"(
[DeviceInfo]
VendorName=x
[DeviceComissioning]
NodeID=0x07
NodeName=left arm joint 1
[MandatoryObjects]
SupportedObjects=3
1=0x1000
2=0x1001
3=0x1018
[1000]
ParameterName=Device type
DataType=0x0007
AccessType=ro
DefaultValue=0x00020192
[1001]
ParameterName=Error register
DataType=0x0005
AccessType=ro
DefaultValue=0
[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=1
[1018sub0]
ParameterName=Highest sub-index supported
DataType=0x0005
AccessType=ro
DefaultValue=0
[OptionalObjects]
SupportedObjects=1
1=0x1017
[1017]
ParameterName=Producer heartbeat time
DataType=0x0006
AccessType=rw
DefaultValue=0
ParameterValue=100
)";
  const Eds eds = parse_eds(dcf, "joint1.dcf");
  EXPECT_EQ(eds.node_id, 7);
  EXPECT_EQ(number<std::uint16_t>(eds, {0x1017, 0}, 7), 100) << "the DCF's value wins";
  EXPECT_EQ(eds.find({0x1017, 0})->default_value->text, "0");
}

// --- malformed files ------------------------------------------------------------------------

// A minimal valid EDS; `extra` is appended, `replace` swaps one line for another.
std::string minimal(const std::string& extra = "", const std::string& from = "", const std::string& to = "") {
  std::string text =
      "[DeviceInfo]\n"        // 1
      "VendorName=x\n"        // 2
      "[MandatoryObjects]\n"  // 3
      "SupportedObjects=3\n"  // 4
      "1=0x1000\n"            // 5
      "2=0x1001\n"            // 6
      "3=0x1018\n"            // 7
      "[1000]\n"              // 8
      "ParameterName=Device type\n"
      "DataType=0x0007\n"  // 10
      "AccessType=ro\n"
      "DefaultValue=0\n"  // 12
      "[1001]\n"          // 13
      "ParameterName=Error register\n"
      "DataType=0x0005\n"  // 15
      "AccessType=ro\n"
      "[1018]\n"  // 17
      "ParameterName=Identity\n"
      "ObjectType=0x9\n"
      "SubNumber=1\n"  // 20
      "[1018sub0]\n"   // 21
      "ParameterName=Highest sub-index supported\n"
      "DataType=0x0005\n"
      "AccessType=ro\n"
      "DefaultValue=0\n" +  // 25
      extra;
  if (!from.empty()) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  return text;
}

void expect_error(const std::string& text, int line, const std::string& key, const std::string& fragment) {
  try {
    (void)parse_eds(text, "vendor.eds");
    ADD_FAILURE() << "parsed; expected line " << line << " key " << key << ": " << fragment;
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "vendor.eds");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(CanopenEds, MinimalFileParses) {
  const Eds eds = parse_eds(minimal(), "vendor.eds");
  EXPECT_EQ(eds.objects.size(), 3u);
  EXPECT_EQ(eds.find({0x1001, 0})->default_value, std::nullopt);
}

TEST(CanopenEds, MalformedFilesNameFileLineAndKey) {
  expect_error("VendorName=x\n[DeviceInfo]\n", 1, "VendorName", "outside any section");
  expect_error(minimal("[2000\n"), 26, "[2000", "without ']'");
  expect_error(minimal("[1000]\n"), 26, "[1000]", "section given twice (first on line 8)");
  expect_error(minimal("", "AccessType=ro\nDefaultValue=0\n[1001]", "AccessType=ro\nAccessType=rw\n[1001]"),
               12, "1000.AccessType", "key given twice");
  expect_error(minimal("", "VendorName=x", "VendorName x"), 2, "[DeviceInfo]", "is not key=value");
  expect_error(minimal("", "[DeviceInfo]\nVendorName=x\n", ""), 1, "[DeviceInfo]", "missing");
  expect_error(minimal("", "ParameterName=Device type\n", ""), 8, "1000.ParameterName", "missing");
  expect_error(minimal("", "DataType=0x0007\n", ""), 8, "1000.DataType", "missing");
  expect_error(minimal("", "DataType=0x0007", "DataType=0x000C"), 10, "1000.DataType", "not supported");
  expect_error(
      minimal("", "DataType=0x0005\nAccessType=ro\n[1018]", "DataType=0x0005\nAccessType=rx\n[1018]"), 16,
      "1001.AccessType", "not an access type");
  expect_error(minimal("", "DataType=0x0007\nAccessType=ro\nDefaultValue=0",
                       "DataType=0x0005\nAccessType=ro\nDefaultValue=256"),
               12, "1000.DefaultValue", "value too high for UNSIGNED8");
  expect_error(minimal("", "DefaultValue=0\n[1001]", "DefaultValue=0x1G\n[1001]"), 12, "1000.DefaultValue",
               "not a whole number");
  expect_error(minimal("", "DefaultValue=0\n[1001]", "DefaultValue=09\n[1001]"), 12, "1000.DefaultValue",
               "not a whole number");  // 0 prefix: octal
  expect_error(minimal("", "SubNumber=1", "SubNumber=2"), 17, "1018.SubNumber",
               "says 2 sub-objects, the file has 1");
  expect_error(minimal("", "ObjectType=0x9", "ObjectType=0x4"), 19, "1018.ObjectType", "not an object type");
  expect_error(minimal("", "3=0x1018", "3=0x1019"), 7, "MandatoryObjects.3", "has no section");
  expect_error(minimal("", "SupportedObjects=3", "SupportedObjects=4"), 4,
               "MandatoryObjects.SupportedObjects", "entry 4 is missing");
  expect_error(minimal("", "3=0x1018", "3=0x1018\n7=0x1001"), 8, "MandatoryObjects.7", "not an entry 1..3");
  expect_error(minimal("[OptionalObjects]\nSupportedObjects=1\n1=0x1017\n"), 28, "OptionalObjects.1",
               "has no section");
  expect_error(minimal("[2000sub1]\nParameterName=x\nDataType=0x0005\nAccessType=ro\n"), 26, "[2000sub1]",
               "an object the file does not define");
  expect_error(minimal("[1000sub1]\nParameterName=x\nDataType=0x0005\nAccessType=ro\n"), 26, "[1000sub1]",
               "a sub-object of a VAR");
}

TEST(CanopenEds, ValuesAreCheckedAgainstLimitsAndTypes) {
  const std::string var = "[2000]\nParameterName=Gain\nDataType=0x0006\nAccessType=rw\n";  // lines 26..29
  expect_error(minimal(var + "LowLimit=10\nHighLimit=100\nDefaultValue=5\n"), 32, "2000.DefaultValue",
               "below LowLimit");
  expect_error(minimal(var + "LowLimit=10\nHighLimit=100\nDefaultValue=0x65\n"), 32, "2000.DefaultValue",
               "above HighLimit");
  expect_error(minimal(var + "LowLimit=100\nHighLimit=10\n"), 30, "2000.LowLimit", "above HighLimit");
  expect_error(minimal(var + "HighLimit=70000\n"), 30, "2000.HighLimit", "value too high for UNSIGNED16");
  expect_error(minimal(var + "PDOMapping=2\n"), 30, "2000.PDOMapping", "0..1");
  expect_error(minimal(var + "DefaultValue=-1\n"), 30, "2000.DefaultValue", "value too low");
  expect_error(
      minimal("[2001]\nParameterName=Gain\nDataType=0x0008\nAccessType=rw\nDefaultValue=$NODEID+1\n"), 30,
      "2001.DefaultValue", "$NODEID is not allowed");
  expect_error(minimal("[2001]\nParameterName=Gain\nDataType=0x0008\nAccessType=rw\nDefaultValue=nan\n"), 30,
               "2001.DefaultValue", "not a finite decimal number");
  expect_error(
      minimal("[2001]\nParameterName=Id\nDataType=0x0007\nAccessType=rw\nDefaultValue=5+$NODEID+1\n"), 30,
      "2001.DefaultValue", "one number only");
  expect_error(minimal("[2001]\nParameterName=Id\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID-1\n"),
               30, "2001.DefaultValue", "expected '+'");
  expect_error(minimal("[2001]\nParameterName=Blob\nDataType=0x000A\nAccessType=rw\nDefaultValue=0102F\n"),
               30, "2001.DefaultValue", "hex bytes");
  // A node-relative value that fits its type for small node-IDs but not for 127.
  const Eds eds = parse_eds(
      minimal("[2002]\nParameterName=Id\nDataType=0x0005\nAccessType=rw\nDefaultValue=$NODEID+0xA0\n"),
      "vendor.eds");
  EXPECT_EQ(number<std::uint8_t>(eds, {0x2002, 0}, 0x10), 0xB0);
  try {
    (void)eds.value({0x2002, 0}, 127);
    ADD_FAILURE() << "resolved beyond UNSIGNED8";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.line(), 26);
    EXPECT_NE(std::string(e.what()).find("node-ID 127 does not fit UNSIGNED8"), std::string::npos)
        << e.what();
  }
}

TEST(CanopenEds, MissingMandatoryObjectsAndBrokenMappings) {
  const std::string no_identity = minimal("", "3=0x1018", "3=0x1001").substr(0);
  std::string text = no_identity;
  text.erase(text.find("[1018]"));
  text.replace(text.find("SupportedObjects=3"), 18, "SupportedObjects=2");
  text.replace(text.find("3=0x1001\n"), 9, "");
  expect_error(text, 3, "[MandatoryObjects]", "0x1018 is mandatory");

  const std::string pdo =
      "[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n"                                      // 26
      "[1800sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"                   // 30
      "[1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x180\n"  // 35
      "[1A00]\nParameterName=map\nObjectType=0x9\nSubNumber=2\n"                                        // 40
      "[1A00sub0]\nParameterName=n\nDataType=0x0005\nAccessType=rw\nDefaultValue=1\n"                   // 44
      "[1A00sub1]\nParameterName=e1\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x60410010\n";        // 49
  const Eds eds = parse_eds(minimal(pdo), "vendor.eds");
  try {
    (void)eds_pdo_mappings(eds, 3);
    ADD_FAILURE() << "mapped an object the file does not have";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.line(), 49) << e.what();
    EXPECT_EQ(e.key(), "0x1A00:01");
    EXPECT_NE(std::string(e.what()).find("maps 0x6041:00, which the file does not define"),
              std::string::npos);
  }
}

TEST(CanopenEds, ExtendedPdoIdentifiersAreRefused) {
  const std::string pdo =
      "[1400]\nParameterName=RPDO1\nObjectType=0x9\nSubNumber=2\n"                                    // 26
      "[1400sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"                 // 30
      "[1400sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x20000200\n";  // 35
  const Eds eds = parse_eds(minimal(pdo), "vendor.eds");
  try {
    (void)eds_pdo_mappings(eds, 3);
    ADD_FAILURE() << "took a 29-bit identifier";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.line(), 35) << e.what();
    EXPECT_EQ(e.key(), "0x1400:01");
    EXPECT_NE(std::string(e.what()).find("not an 11-bit identifier"), std::string::npos) << e.what();
  }
}

TEST(CanopenEds, AnUnreadableFileIsNamed) {
  try {
    (void)load_eds("/nonexistent/drive.eds");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/drive.eds");
    EXPECT_NE(std::string(e.what()).find("cannot read"), std::string::npos);
  }
}

}  // namespace
