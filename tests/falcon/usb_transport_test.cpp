// The libusb backend on a machine without a Falcon: its errors, before and after libusb_init.
#include "saw/drivers/falcon/usb_transport.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace saw::drivers::falcon {
namespace {

std::string open_error(UsbConfig c) {
  UsbTransport t(std::move(c));
  try {
    t.open();
  } catch (const TransportError& e) {
    return e.what();
  }
  return {};
}

TEST(FalconUsb, NoFirmwareFileIsSaidFirst) {
  EXPECT_NE(open_error({}).find("no firmware file given"), std::string::npos);
  UsbConfig c;
  c.firmware = "/nonexistent/falcon_firmware.bin";
  const std::string e = open_error(c);
  EXPECT_NE(e.find("'/nonexistent/falcon_firmware.bin' cannot be read"), std::string::npos) << e;
}

// This machine has no Falcon (and maybe no usbfs at all): opening says which, with the buses
// searched. Either way it is an error, never a hang or a crash.
TEST(FalconUsb, OpeningWithoutAFalconSaysNoneFoundAndWhere) {
  const auto firmware = std::filesystem::temp_directory_path() / "saw_falcon_test_firmware.bin";
  std::ofstream(firmware, std::ios::binary) << "not a real firmware";
  UsbConfig c;
  c.firmware = firmware.string();
  const std::string e = open_error(c);
  std::printf("open: %s\n", e.c_str());
  const bool none_found = e.find("no Falcon found on the USB buses searched (") != std::string::npos;
  const bool no_usb = e.find("libusb_init failed") != std::string::npos;
  EXPECT_TRUE(none_found || no_usb) << e;
  c.bus = 250;  // no such bus
  const std::string e2 = open_error(c);
  if (none_found) {
    EXPECT_NE(e2.find("bus 250: not present"), std::string::npos) << e2;
  }
  std::filesystem::remove(firmware);
}

TEST(FalconUsb, ExchangeBeforeOpenIsDisconnected) {
  UsbTransport t({});
  Packet in{};
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::disconnected);
  EXPECT_EQ(t.describe(), "Falcon on USB (not open)");
}

}  // namespace
}  // namespace saw::drivers::falcon
