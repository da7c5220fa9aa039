// UsbTransport: a Falcon on USB through libusb-1.0 (its FTDI chip, firmware upload, packets).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "saw/drivers/falcon/transport.hpp"

namespace saw::drivers::falcon {

inline constexpr std::uint16_t falcon_vendor_id = 0x0403;   // FTDI
inline constexpr std::uint16_t falcon_product_id = 0xcb48;  // Novint Falcon

struct UsbConfig {
  std::string firmware;         // the firmware file (not shipped: the lab's copy of Novint's)
  int bus = -1;                 // USB bus number to search; -1: every bus
  int index = 0;                // which Falcon when several match (0: the first found)
  int exchange_timeout_ms = 1;  // bound of each bulk transfer in the cycle (libusb's unit: ms)
  std::string udev_rule = "70-novint-falcon.rules";  // named in the permission error
};

// open(): libusb_init, the Falcon by VID:PID (and bus/index), claim interface 0, FTDI setup by
// control transfers, firmware upload at 9600/140000 baud with its checks, then 1.456 Mbaud and
// a 1 ms latency timer for the packet protocol. exchange(): a bulk write of 16 bytes and bulk
// reads (each FTDI read starts with 2 modem status bytes) until 16 bytes or the bound.
class UsbTransport final : public FalconTransport {
 public:
  explicit UsbTransport(UsbConfig config);
  ~UsbTransport() override;
  UsbTransport(const UsbTransport&) = delete;
  UsbTransport& operator=(const UsbTransport&) = delete;

  void open() override;
  ExchangeResult exchange(const Packet& out, Packet& in) noexcept override;
  void close() noexcept override;
  std::string describe() const override;

 private:
  struct Usb;
  UsbConfig config_;
  std::unique_ptr<Usb> usb_;
};

}  // namespace saw::drivers::falcon
