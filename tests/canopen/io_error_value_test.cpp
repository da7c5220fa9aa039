// canopen_io writes each channel's CiA 401 error behaviour from its safe value (the node's own
// safe state when the controller dies), and says so when a channel's output has none.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "saw/canopen/canopen_io.hpp"
#include "saw/canopen/eds.hpp"
#include "saw/log.hpp"
#include "shared_rig.hpp"

namespace saw::canopen::test {
namespace {

bool has(const std::vector<SdoWrite>& writes, ObjectAddress a, std::uint32_t value) {
  return std::any_of(writes.begin(), writes.end(),
                     [&](const SdoWrite& w) { return w.address == a && w.value == value; });
}

bool logged(const std::string& text) {
  bool found = false;
  saw::LogRecord r;
  while (saw::log_ring().pop(r)) found = found || saw::format_log_record(r).find(text) != std::string::npos;
  return found;
}

std::unique_ptr<CanopenIo> make(const CanopenIoConfig& c) {
  return std::make_unique<CanopenIo>("gripper", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
}

TEST(CanopenIoErrorValue, AnAnalogOutputsErrorModeAndValueAreItsSafeValueInCounts) {
  SharedRig rig;
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.node.writes.push_back({{0x2000, 1}, DataType::unsigned8, 7});  // the deployment's own, after
  auto io = make(c);
  const auto& w = io->node().config().writes;
  ASSERT_GE(w.size(), 3u);
  EXPECT_EQ(w[0].address, (ObjectAddress{0x6443, 1}));
  EXPECT_EQ(w[0].value, 1u);
  EXPECT_EQ(w[1].address, (ObjectAddress{0x6444, 1}));
  EXPECT_EQ(w[1].type, DataType::integer32);
  EXPECT_EQ(w[1].value, 2000u) << "0.02 m at 1e-5 m per count";
  EXPECT_EQ(w.back().address, (ObjectAddress{0x2000, 1}));
  // Every start-up write of the node (and its re-configuration after a reboot) carries them.
  const NodeSetup s = setup_of(io->node().config());
  EXPECT_TRUE(std::any_of(s.writes.begin(), s.writes.end(), [](const StartupWrite& x) {
    return x.write.address == ObjectAddress{0x6444, 1} && !x.optional;
  }));
}

TEST(CanopenIoErrorValue, ADigitalOutputGetsAMaskOfEveryBitAndItsSafeByte) {
  SharedRig rig;
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.channels[0].output = PdoEntry::of({0x6200, 2}, DataType::unsigned8);
  c.channels[0].scale = 1;
  c.channels[0].min = 0;
  c.channels[0].max = 255;
  c.channels[0].safe = 0x81;
  c.node.pdos[0] = make_pdo(PdoKind::rpdo, 1, 10, std::span(&*c.channels[0].output, 1));
  auto io = make(c);
  const auto& w = io->node().config().writes;
  EXPECT_TRUE(has(w, {0x6206, 2}, 0xFF));
  EXPECT_TRUE(has(w, {0x6207, 2}, 0x81));
  EXPECT_FALSE(has(w, {0x6443, 2}, 1));
}

TEST(CanopenIoErrorValue, AnOutputWithNoStandardErrorValueIsSaidOnceAndNothingIsWritten) {
  SharedRig rig;
  logged("");  // empty the ring
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.channels[0].output = PdoEntry::of({0x2100, 1}, DataType::integer16);
  c.node.pdos[0] = make_pdo(PdoKind::rpdo, 1, 10, std::span(&*c.channels[0].output, 1));
  auto io = make(c);
  EXPECT_TRUE(io->node().config().writes.empty());
  EXPECT_TRUE(logged("channel 'jaw': its output is no CiA 401 output object"));
}

TEST(CanopenIoErrorValue, ASafeValueTheErrorValueCannotHoldIsRefusedNamingTheChannel) {
  SharedRig rig;
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.channels[0].output = PdoEntry::of({0x6200, 1}, DataType::unsigned8);
  c.channels[0].scale = 1;
  c.channels[0].max = 1000;
  c.channels[0].safe = 300;
  c.node.pdos[0] = make_pdo(PdoKind::rpdo, 1, 10, std::span(&*c.channels[0].output, 1));
  try {
    make(c);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("channel 'jaw'"), std::string::npos) << e.what();
  }
}

// A node's EDS (a Turck BL20's manual types its 0x6443 and 0x6444 as UNSIGNED16) with the error
// objects of analog output 1 as `mode` and `value` ("" leaves the object out).
Eds eds_with(const std::string& mode, const std::string& value) {
  std::string text =
      "[DeviceInfo]\nVendorNumber=0x48\nProductNumber=1\n"
      "[MandatoryObjects]\nSupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n"
      "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\n"
      "DefaultValue=0x191\n"
      "[1001]\nParameterName=Error register\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\n"
      "[1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=2\n"
      "[1018sub0]\nParameterName=n\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"
      "[1018sub1]\nParameterName=Vendor-ID\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\n"
      "DefaultValue=0x48\n";
  const auto array = [&](const std::string& index, const std::string& type) {
    text += "[" + index + "]\nParameterName=x\nObjectType=0x8\nSubNumber=2\n[" + index +
            "sub0]\nParameterName=n\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n[" +
            index + "sub1]\nParameterName=x1\nObjectType=0x7\nDataType=" + type +
            "\nAccessType=rw\nDefaultValue=0\n";
  };
  if (!mode.empty()) array("6443", mode);
  if (!value.empty()) array("6444", value);
  return parse_eds(text, "bl20.eds");
}

const SdoWrite* find(const std::vector<SdoWrite>& writes, ObjectAddress a) {
  const auto it =
      std::find_if(writes.begin(), writes.end(), [&](const SdoWrite& w) { return w.address == a; });
  return it == writes.end() ? nullptr : &*it;
}

TEST(CanopenIoErrorValue, WithAnEdsEachErrorObjectTakesItsType) {
  SharedRig rig;
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.eds = eds_with("0x0006", "0x0006");  // UNSIGNED16 both
  auto io = make(c);
  const auto& w = io->node().config().writes;
  const SdoWrite* mode = find(w, {0x6443, 1});
  const SdoWrite* value = find(w, {0x6444, 1});
  ASSERT_TRUE(mode && value);
  EXPECT_EQ(mode->type, DataType::unsigned16);
  EXPECT_EQ(value->type, DataType::unsigned16);
  EXPECT_EQ(size_of(value->type), 2u) << "a 2-byte download";
  EXPECT_EQ(mode->value, 1u);
  EXPECT_EQ(value->value, 2000u);
}

TEST(CanopenIoErrorValue, AnObjectTheEdsDoesNotListIsNotWrittenAndSaidNamingTheChannel) {
  SharedRig rig;
  logged("");  // empty the ring
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.eds = eds_with("", "0x0003");  // no 0x6443; 0x6444 INTEGER16
  auto io = make(c);
  const auto& w = io->node().config().writes;
  EXPECT_EQ(find(w, {0x6443, 1}), nullptr);
  ASSERT_NE(find(w, {0x6444, 1}), nullptr);
  EXPECT_EQ(find(w, {0x6444, 1})->type, DataType::integer16);
  EXPECT_TRUE(logged("channel 'jaw': the EDS lists no 0x6443:1, not written"));
}

TEST(CanopenIoErrorValue, AChannelThatOptsOutWritesNothing) {
  SharedRig rig;
  logged("");
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.channels[0].error_value = false;
  auto io = make(c);
  EXPECT_TRUE(io->node().config().writes.empty());
  EXPECT_FALSE(logged("channel 'jaw'"));
}

TEST(CanopenIoErrorValue, ANegativeSafeValueForAnUnsigned16ErrorValueIsRefusedNamingTheChannel) {
  SharedRig rig;
  CanopenIoConfig c = gripper_config(rig.name, 10);
  c.eds = eds_with("0x0006", "0x0006");
  c.channels[0].min = -0.08;
  c.channels[0].safe = -0.01;
  try {
    make(c);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("channel 'jaw'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("UNSIGNED16"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace saw::canopen::test
