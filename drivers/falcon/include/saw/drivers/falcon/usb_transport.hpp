// UsbTransport: a Falcon on USB through libusb-1.0 (its FTDI chip, firmware upload, packets).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "saw/drivers/falcon/ftdi_port.hpp"
#include "saw/drivers/falcon/report_stream.hpp"
#include "saw/drivers/falcon/transport.hpp"

namespace saw::drivers::falcon {

inline constexpr std::uint16_t falcon_vendor_id = 0x0403;   // FTDI
inline constexpr std::uint16_t falcon_product_id = 0xcb48;  // Novint Falcon

struct UsbConfig {
  std::string firmware;         // the firmware file (not shipped: the lab's copy of Novint's)
  int bus = -1;                 // USB bus number to search; -1: every bus
  int index = 0;                // which Falcon when several match (0: the first found)
  int exchange_timeout_ms = 1;  // bound of each bulk transfer in the cycle (libusb's unit: ms)
  int handshake_tries = 100;    // the loader's hello, sent until answered (libnifalcon: 100)
  int load_attempts = 5;        // firmware uploads before giving up (libnifalcon's CLI: 10)
  std::string udev_rule = "70-novint-falcon.rules";  // named in the permission error
};

// open(): libusb_init, the Falcon by VID:PID (and bus/index), claim interface 0; then, as
// libnifalcon does, a probe at the packet protocol's settings (1.456 Mbaud, 1 ms latency timer):
// a firmware already running (a restart without a power cycle) answers it and is kept. Else the
// loader: FTDI setup at 9600 baud, the DTR handshake (its hello resent up to handshake_tries
// times), 140000 baud, the upload with every byte's echo checked, the probe again; all of it up
// to load_attempts times. exchange(): a bulk write of 16 bytes, then bulk reads (each starting
// with the FTDI's 2 status bytes) until the FTDI has nothing more: the newest complete report is
// returned and the older ones dropped (ReportStream), within a bounded number of reads.
class UsbTransport final : public FalconTransport {
 public:
  explicit UsbTransport(UsbConfig config);
  // Over a given port instead of libusb (tests: a scripted FTDI, a simulated Falcon).
  UsbTransport(UsbConfig config, std::unique_ptr<FtdiPort> port);
  ~UsbTransport() override;
  UsbTransport(const UsbTransport&) = delete;
  UsbTransport& operator=(const UsbTransport&) = delete;

  void open() override;
  ExchangeResult exchange(const Packet& out, Packet& in) noexcept override;
  void close() noexcept override;
  std::string describe() const override;

  // Set by open(): the firmware was running already (not uploaded), and the uploads it took.
  bool firmware_was_running() const noexcept { return was_running_; }
  int load_attempts_made() const noexcept { return attempts_; }
  const ReportStream& stream() const noexcept { return stream_; }

 private:
  struct Usb;
  void start(FtdiPort& port, const std::string& where, const std::vector<std::uint8_t>& firmware);
  bool firmware_answers(FtdiPort& port);
  UsbConfig config_;
  std::unique_ptr<FtdiPort> given_;  // the test seam, when given
  std::unique_ptr<Usb> usb_;
  FtdiPort* port_ = nullptr;  // open: usb_'s libusb port or given_
  ReportStream stream_;
  std::array<std::uint8_t, 64> transfer_{};
  bool was_running_ = false;
  int attempts_ = 0;
};

}  // namespace saw::drivers::falcon
