#include "saw/drivers/falcon/usb_transport.hpp"

#include <libusb.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

namespace saw::drivers::falcon {
namespace {

// FTDI vendor requests (host → device, vendor type, wIndex = interface 0).
constexpr std::uint8_t ftdi_out = 0x40;
constexpr std::uint8_t sio_reset = 0, sio_modem_ctrl = 1, sio_flow_ctrl = 2, sio_baud = 3, sio_data = 4,
                       sio_latency = 9, sio_bitmode = 0x0b;
constexpr std::uint16_t reset_sio = 0, purge_rx = 1, purge_tx = 2;
constexpr std::uint16_t dtr_low = 0x0100, dtr_high = 0x0101, rts_low = 0x0200;
constexpr std::uint16_t baud_9600 = 0x4138, baud_140000 = 0x15, baud_1456000 = 0x02;  // divisors
constexpr std::uint16_t data_8n1 = 8;
constexpr unsigned char ep_out = 0x02, ep_in = 0x81;
constexpr std::size_t ftdi_status_bytes = 2;  // every bulk-in transfer starts with the modem status
constexpr unsigned setup_timeout_ms = 1000;
constexpr std::size_t firmware_chunk = 128;

std::string usb_error(int e) { return std::string(libusb_error_name(e)) + " (" + std::to_string(e) + ")"; }

}  // namespace

struct UsbTransport::Usb {
  libusb_context* context = nullptr;
  libusb_device_handle* handle = nullptr;
  bool claimed = false;
  int bus = -1, address = -1;
  // The cycle's receive staging: bytes after the status bytes, kept across exchanges.
  std::array<std::uint8_t, 128> rx{};
  std::size_t rx_count = 0;
  std::array<std::uint8_t, 64> transfer{};

  ~Usb() {
    if (claimed) libusb_release_interface(handle, 0);
    if (handle) libusb_close(handle);
    if (context) libusb_exit(context);
  }

  void control(std::uint8_t request, std::uint16_t value, const char* what) const {
    const int r = libusb_control_transfer(handle, ftdi_out, request, value, 0, nullptr, 0, setup_timeout_ms);
    if (r < 0) throw TransportError(std::string("Falcon: FTDI ") + what + " failed: " + usb_error(r));
  }

  void write(const std::uint8_t* data, std::size_t n, const char* what) const {
    int done = 0;
    const int r = libusb_bulk_transfer(handle, ep_out, const_cast<unsigned char*>(data), static_cast<int>(n),
                                       &done, setup_timeout_ms);
    if (r < 0 || done != static_cast<int>(n))
      throw TransportError(std::string("Falcon: writing ") + what + " failed: " + usb_error(r));
  }

  // Reads `n` data bytes (status bytes stripped) within `timeout`; returns what arrived.
  std::vector<std::uint8_t> read(std::size_t n, std::chrono::milliseconds timeout) {
    std::vector<std::uint8_t> data;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (data.size() < n && std::chrono::steady_clock::now() < deadline) {
      int got = 0;
      const int r =
          libusb_bulk_transfer(handle, ep_in, transfer.data(), static_cast<int>(transfer.size()), &got, 10);
      if (r < 0 && r != LIBUSB_ERROR_TIMEOUT) throw TransportError("Falcon: reading failed: " + usb_error(r));
      if (got > static_cast<int>(ftdi_status_bytes))
        data.insert(data.end(), transfer.begin() + ftdi_status_bytes, transfer.begin() + got);
    }
    return data;
  }
};

const char* to_string(ExchangeStatus s) noexcept {
  switch (s) {
    case ExchangeStatus::ok:
      return "ok";
    case ExchangeStatus::no_answer:
      return "no answer";
    case ExchangeStatus::usb_error:
      return "USB error";
    case ExchangeStatus::disconnected:
      return "disconnected";
  }
  return "?";
}

UsbTransport::UsbTransport(UsbConfig config) : config_(std::move(config)) {}
UsbTransport::~UsbTransport() = default;

std::string UsbTransport::describe() const {
  if (!usb_ || usb_->bus < 0) return "Falcon on USB (not open)";
  return "Falcon on USB bus " + std::to_string(usb_->bus) + " address " + std::to_string(usb_->address);
}

void UsbTransport::open() {
  close();
  // The firmware first: without it an open device is useless, and this needs no USB.
  if (config_.firmware.empty())
    throw TransportError("Falcon: no firmware file given (params: firmware: PATH to the Novint firmware)");
  std::ifstream file(config_.firmware, std::ios::binary);
  if (!file)
    throw TransportError("Falcon: firmware file '" + config_.firmware +
                         "' cannot be read (the firmware is not shipped: see docs/devices.md)");
  const std::vector<std::uint8_t> firmware{std::istreambuf_iterator<char>(file), {}};
  if (firmware.empty()) throw TransportError("Falcon: firmware file '" + config_.firmware + "' is empty");

  auto usb = std::make_unique<Usb>();
  if (const int r = libusb_init(&usb->context); r < 0)
    throw TransportError("Falcon: libusb_init failed: " + usb_error(r) +
                         " (no USB subsystem here: is /dev/bus/usb present in this machine or container?)");

  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(usb->context, &list);
  if (n < 0) throw TransportError("Falcon: cannot list USB devices: " + usb_error(static_cast<int>(n)));
  std::vector<int> buses;
  libusb_device* found = nullptr;
  int seen = 0;
  for (ssize_t i = 0; i < n; ++i) {
    const int bus = libusb_get_bus_number(list[i]);
    if (config_.bus >= 0 && bus != config_.bus) continue;
    if (std::find(buses.begin(), buses.end(), bus) == buses.end()) buses.push_back(bus);
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    if (d.idVendor != falcon_vendor_id || d.idProduct != falcon_product_id) continue;
    if (seen++ == config_.index) {
      found = libusb_ref_device(list[i]);
      break;
    }
  }
  libusb_free_device_list(list, 1);
  if (!found) {
    std::string searched;
    for (const int b : buses) searched += (searched.empty() ? "" : ", ") + std::to_string(b);
    if (searched.empty())
      searched =
          config_.bus >= 0 ? "bus " + std::to_string(config_.bus) + ": not present" : "no USB bus visible";
    else
      searched = "bus " + searched;
    throw TransportError("Falcon: no Falcon found on the USB buses searched (" + searched + "; looking for " +
                         "0403:cb48" + (config_.index > 0 ? ", index " + std::to_string(config_.index) : "") +
                         (seen > 0 ? ", " + std::to_string(seen) + " found" : "") + ")");
  }
  usb->bus = libusb_get_bus_number(found);
  usb->address = libusb_get_device_address(found);
  const int r = libusb_open(found, &usb->handle);
  libusb_unref_device(found);
  const std::string where = "bus " + std::to_string(usb->bus) + " address " + std::to_string(usb->address);
  if (r == LIBUSB_ERROR_ACCESS)
    throw TransportError("Falcon: permission denied opening the Falcon on " + where + ": the udev rule " +
                         config_.udev_rule +
                         " must be installed (the sawrt .deb puts it in /usr/lib/udev/rules.d; " +
                         "from a source tree, sudo cp config/udev/" + config_.udev_rule +
                         " /etc/udev/rules.d/ && sudo udevadm control --reload), the Falcon " +
                         "replugged after it, and this user in the plugdev group (docs/devices.md)");
  if (r < 0) throw TransportError("Falcon: cannot open the Falcon on " + where + ": " + usb_error(r));
  // The kernel's ftdi_sio may have bound it as a serial port: take it back.
  if (libusb_kernel_driver_active(usb->handle, 0) == 1) libusb_detach_kernel_driver(usb->handle, 0);
  if (const int c = libusb_claim_interface(usb->handle, 0); c < 0)
    throw TransportError("Falcon: cannot claim the Falcon on " + where + ": " + usb_error(c) +
                         (c == LIBUSB_ERROR_BUSY ? " (another program has it)" : ""));
  usb->claimed = true;

  // Firmware loader mode: 9600 baud 8N1, no flow control, then the DTR/RTS handshake.
  usb->control(sio_reset, reset_sio, "reset");
  usb->control(sio_bitmode, 0x0000, "bit mode reset");
  usb->control(sio_reset, purge_rx, "purge rx");
  usb->control(sio_reset, purge_tx, "purge tx");
  usb->control(sio_latency, 16, "latency timer");
  usb->control(sio_baud, baud_9600, "baud rate");
  usb->control(sio_data, data_8n1, "data format");
  usb->control(sio_flow_ctrl, 0, "flow control");
  usb->control(sio_modem_ctrl, rts_low, "RTS");
  usb->control(sio_modem_ctrl, dtr_low, "DTR");
  usb->control(sio_modem_ctrl, dtr_high, "DTR");
  const std::array<std::uint8_t, 3> hello{0x0a, 0x43, 0x0d};
  usb->write(hello.data(), hello.size(), "the loader handshake");
  const auto answer = usb->read(4, std::chrono::milliseconds(1000));
  const std::array<std::uint8_t, 4> expected{0x0a, 0x44, 0x2c, 0x0d};
  if (answer.size() < expected.size() ||
      !std::equal(expected.begin(), expected.end(), answer.end() - expected.size()))
    throw TransportError("Falcon on " + where + ": the firmware loader did not answer its handshake (" +
                         std::to_string(answer.size()) +
                         " bytes): power-cycle the Falcon (its power supply!)");
  usb->control(sio_modem_ctrl, dtr_low, "DTR");
  usb->control(sio_baud, baud_140000, "baud rate");
  const std::uint8_t probe = 0x41;
  usb->write(&probe, 1, "the loader probe");
  const auto echo = usb->read(1, std::chrono::milliseconds(1000));
  if (echo.empty() || echo.back() != probe)
    throw TransportError("Falcon on " + where + ": the firmware loader did not echo its probe");
  // The loader echoes every byte: a chunk that does not come back whole is a failed upload.
  for (std::size_t at = 0; at < firmware.size(); at += firmware_chunk) {
    const std::size_t len = std::min(firmware_chunk, firmware.size() - at);
    usb->write(firmware.data() + at, len, "the firmware");
    const auto back = usb->read(len, std::chrono::milliseconds(1000));
    if (back.size() < len || !std::equal(back.begin(), back.begin() + static_cast<std::ptrdiff_t>(len),
                                         firmware.begin() + static_cast<std::ptrdiff_t>(at)))
      throw TransportError("Falcon on " + where + ": firmware upload failed at byte " + std::to_string(at) +
                           " of " + config_.firmware + " (echo " + std::to_string(back.size()) + "/" +
                           std::to_string(len) + " bytes)");
  }
  // The packet protocol: 1.456 Mbaud, 1 ms latency timer (one report per cycle, not per 16 ms).
  usb->control(sio_latency, 1, "latency timer");
  usb->control(sio_baud, baud_1456000, "baud rate");
  usb->control(sio_reset, purge_rx, "purge rx");
  usb->control(sio_reset, purge_tx, "purge tx");
  usb_ = std::move(usb);
  // The firmware must answer a null command (zero force, LEDs off) within 100 ms.
  Packet in{};
  DeviceReport report{};
  for (int tries = 0; tries < 100; ++tries) {
    const ExchangeResult x = exchange(encode_command(MotorCommand{}), in);
    if (x.status == ExchangeStatus::ok && decode_report(in, report) == FrameError::none) return;
  }
  usb_.reset();
  throw TransportError("Falcon on " + where + ": the firmware in " + config_.firmware +
                       " does not answer packets after upload (a firmware for another protocol?)");
}

ExchangeResult UsbTransport::exchange(const Packet& out, Packet& in) noexcept {
  if (!usb_) return {ExchangeStatus::disconnected, 0, 0};
  Usb& u = *usb_;
  auto fail = [](int r) {
    return ExchangeResult{
        r == LIBUSB_ERROR_NO_DEVICE ? ExchangeStatus::disconnected : ExchangeStatus::usb_error, 0, r};
  };
  int done = 0;
  const auto timeout = static_cast<unsigned>(config_.exchange_timeout_ms);
  if (const int r = libusb_bulk_transfer(u.handle, ep_out, const_cast<unsigned char*>(out.data()),
                                         static_cast<int>(out.size()), &done, timeout);
      r < 0)
    return fail(r);
  // At most two reads: the FTDI's latency timer is 1 ms, so a report is one or two transfers.
  for (int reads = 0; reads < 2 && u.rx_count < packet_size; ++reads) {
    int got = 0;
    const int r = libusb_bulk_transfer(u.handle, ep_in, u.transfer.data(),
                                       static_cast<int>(u.transfer.size()), &got, timeout);
    if (r < 0 && r != LIBUSB_ERROR_TIMEOUT) return fail(r);
    for (int k = static_cast<int>(ftdi_status_bytes); k < got && u.rx_count < u.rx.size(); ++k)
      u.rx[u.rx_count++] = u.transfer[static_cast<std::size_t>(k)];
  }
  // Resynchronise on a start byte, so one lost byte costs one report, not all later ones.
  std::size_t start = 0;
  while (start < u.rx_count && u.rx[start] != packet_start) ++start;
  if (u.rx_count - start < packet_size) {
    std::memmove(u.rx.data(), u.rx.data() + start, u.rx_count - start);
    u.rx_count -= start;
    return {ExchangeStatus::no_answer, 0, 0};
  }
  std::memcpy(in.data(), u.rx.data() + start, packet_size);
  const std::size_t used = start + packet_size;
  std::memmove(u.rx.data(), u.rx.data() + used, u.rx_count - used);
  u.rx_count -= used;
  return {ExchangeStatus::ok, packet_size, 0};
}

void UsbTransport::close() noexcept { usb_.reset(); }

}  // namespace saw::drivers::falcon
