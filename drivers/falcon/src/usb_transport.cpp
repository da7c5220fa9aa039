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

static_assert(port_timeout == LIBUSB_ERROR_TIMEOUT && port_no_device == LIBUSB_ERROR_NO_DEVICE);

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
// Reads per exchange: a 64-byte transfer holds 62 data bytes (almost 4 reports), so 4 reads
// drain any backlog the FTDI can hold between two cycles, and bound the exchange's time.
constexpr int max_reads = 4;
// The probe for a running firmware (libnifalcon's isFirmwareLoaded: rounds of write and read).
constexpr int probe_rounds = 10;

std::string usb_error(int e) { return std::string(libusb_error_name(e)) + " (" + std::to_string(e) + ")"; }

// libusb behind the port (the claimed interface 0 of an open device).
class LibusbPort final : public FtdiPort {
 public:
  explicit LibusbPort(libusb_device_handle* h) : handle_(h) {}
  int control(std::uint8_t request, std::uint16_t value, unsigned timeout_ms) noexcept override {
    return libusb_control_transfer(handle_, ftdi_out, request, value, 0, nullptr, 0, timeout_ms);
  }
  int bulk_write(const std::uint8_t* data, std::size_t n, std::size_t& done,
                 unsigned timeout_ms) noexcept override {
    int d = 0;
    const int r = libusb_bulk_transfer(handle_, ep_out, const_cast<unsigned char*>(data), static_cast<int>(n),
                                       &d, timeout_ms);
    done = d > 0 ? static_cast<std::size_t>(d) : 0;
    return r;
  }
  int bulk_read(std::uint8_t* data, std::size_t capacity, std::size_t& got,
                unsigned timeout_ms) noexcept override {
    int g = 0;
    const int r = libusb_bulk_transfer(handle_, ep_in, data, static_cast<int>(capacity), &g, timeout_ms);
    got = g > 0 ? static_cast<std::size_t>(g) : 0;
    return r;
  }

 private:
  libusb_device_handle* handle_;
};

// open()'s steps over the port: each throws TransportError saying what failed.
void control(FtdiPort& port, std::uint8_t request, std::uint16_t value, const char* what) {
  if (const int r = port.control(request, value, setup_timeout_ms); r < 0)
    throw TransportError(std::string("Falcon: FTDI ") + what + " failed: " + usb_error(r));
}

void write(FtdiPort& port, const std::uint8_t* data, std::size_t n, const char* what) {
  std::size_t done = 0;
  const int r = port.bulk_write(data, n, done, setup_timeout_ms);
  if (r < 0 || done != n)
    throw TransportError(std::string("Falcon: writing ") + what + " failed: " + usb_error(r));
}

// Up to `n` data bytes (status bytes off) within `timeout`.
std::vector<std::uint8_t> read(FtdiPort& port, std::size_t n, std::chrono::milliseconds timeout) {
  std::vector<std::uint8_t> data;
  std::array<std::uint8_t, 64> transfer{};
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (data.size() < n && std::chrono::steady_clock::now() < deadline) {
    std::size_t got = 0;
    const int r = port.bulk_read(transfer.data(), transfer.size(), got, 10);
    if (r < 0 && r != port_timeout) throw TransportError("Falcon: reading failed: " + usb_error(r));
    if (got > ftdi_status_bytes)
      data.insert(data.end(), transfer.begin() + ftdi_status_bytes, transfer.begin() + got);
  }
  return data;
}

// The packet protocol's settings: 1.456 Mbaud, 1 ms latency timer (one report per cycle, not per
// 16 ms), both directions purged.
void normal_mode(FtdiPort& port) {
  control(port, sio_latency, 1, "latency timer");
  control(port, sio_baud, baud_1456000, "baud rate");
  control(port, sio_reset, purge_rx, "purge rx");
  control(port, sio_reset, purge_tx, "purge tx");
}

// The loader: 9600 baud 8N1, the DTR handshake (the hello resent until answered, as libnifalcon
// does: the loader may miss the first ones), 140000 baud, the probe, the upload with every byte's
// echo checked.
void load(FtdiPort& port, const UsbConfig& config, const std::vector<std::uint8_t>& firmware) {
  control(port, sio_reset, reset_sio, "reset");
  control(port, sio_bitmode, 0x0000, "bit mode reset");
  control(port, sio_reset, purge_rx, "purge rx");
  control(port, sio_reset, purge_tx, "purge tx");
  control(port, sio_latency, 16, "latency timer");
  control(port, sio_baud, baud_9600, "baud rate");
  control(port, sio_data, data_8n1, "data format");
  control(port, sio_flow_ctrl, 0, "flow control");
  control(port, sio_modem_ctrl, rts_low, "RTS");
  control(port, sio_modem_ctrl, dtr_low, "DTR");
  control(port, sio_modem_ctrl, dtr_high, "DTR");
  const std::array<std::uint8_t, 3> hello{0x0a, 0x43, 0x0d};
  const std::array<std::uint8_t, 4> expected{0x0a, 0x44, 0x2c, 0x0d};
  bool answered = false;
  std::size_t last = 0;
  for (int tries = 0; tries < config.handshake_tries && !answered; ++tries) {
    write(port, hello.data(), hello.size(), "the loader handshake");
    const auto answer = read(port, expected.size(), std::chrono::milliseconds(50));
    last = answer.size();
    answered = answer.size() >= expected.size() &&
               std::equal(expected.begin(), expected.end(), answer.end() - expected.size());
  }
  if (!answered)
    throw TransportError("the firmware loader did not answer its handshake (" +
                         std::to_string(config.handshake_tries) + " tries, last " + std::to_string(last) +
                         " bytes)");
  control(port, sio_modem_ctrl, dtr_low, "DTR");
  control(port, sio_baud, baud_140000, "baud rate");
  const std::uint8_t probe = 0x41;
  write(port, &probe, 1, "the loader probe");
  const auto echo = read(port, 1, std::chrono::milliseconds(1000));
  if (echo.empty() || echo.back() != probe)
    throw TransportError("the firmware loader did not echo its probe");
  for (std::size_t at = 0; at < firmware.size(); at += firmware_chunk) {
    const std::size_t len = std::min(firmware_chunk, firmware.size() - at);
    write(port, firmware.data() + at, len, "the firmware");
    const auto back = read(port, len, std::chrono::milliseconds(1000));
    if (back.size() < len || !std::equal(back.begin(), back.begin() + static_cast<std::ptrdiff_t>(len),
                                         firmware.begin() + static_cast<std::ptrdiff_t>(at)))
      throw TransportError("firmware upload failed at byte " + std::to_string(at) + " of " + config.firmware +
                           " (echo " + std::to_string(back.size()) + "/" + std::to_string(len) + " bytes)");
  }
}

}  // namespace

struct UsbTransport::Usb {
  libusb_context* context = nullptr;
  libusb_device_handle* handle = nullptr;
  bool claimed = false;
  int bus = -1, address = -1;
  std::unique_ptr<LibusbPort> port;

  ~Usb() {
    port.reset();
    if (claimed) libusb_release_interface(handle, 0);
    if (handle) libusb_close(handle);
    if (context) libusb_exit(context);
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
UsbTransport::UsbTransport(UsbConfig config, std::unique_ptr<FtdiPort> port)
    : config_(std::move(config)), given_(std::move(port)) {}
UsbTransport::~UsbTransport() = default;

std::string UsbTransport::describe() const {
  if (given_) return "Falcon on a given FTDI port";
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

  if (given_) {
    start(*given_, "the given port", firmware);
    port_ = given_.get();
    return;
  }
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
  usb->port = std::make_unique<LibusbPort>(usb->handle);
  start(*usb->port, where, firmware);
  usb_ = std::move(usb);
  port_ = usb_->port.get();
}

// A firmware that answers a null packet with a framed report is running (libnifalcon's
// isFirmwareLoaded: rounds of a write and reads). Not the cycle: it may wait.
bool UsbTransport::firmware_answers(FtdiPort& port) {
  port_ = &port;
  stream_.clear();
  Packet in{};
  DeviceReport report{};
  for (int round = 0; round < probe_rounds; ++round) {
    for (int tries = 0; tries < 10; ++tries) {
      const ExchangeResult x = exchange(encode_command(MotorCommand{}), in);
      if (x.status == ExchangeStatus::ok && decode_report(in, report) == FrameError::none) return true;
      if (x.status != ExchangeStatus::ok && x.status != ExchangeStatus::no_answer) break;
    }
  }
  port_ = nullptr;
  return false;
}

// A running firmware is kept (a restart without a power cycle: libnifalcon probes first too);
// otherwise the loader, up to load_attempts times, each followed by the probe.
void UsbTransport::start(FtdiPort& port, const std::string& where,
                         const std::vector<std::uint8_t>& firmware) {
  was_running_ = false;
  attempts_ = 0;
  normal_mode(port);
  if (firmware_answers(port)) {
    was_running_ = true;
    port_ = nullptr;
    return;
  }
  std::string why;
  while (attempts_ < config_.load_attempts) {
    ++attempts_;
    try {
      load(port, config_, firmware);
      normal_mode(port);
      if (firmware_answers(port)) {
        port_ = nullptr;
        return;
      }
      why = "the firmware in " + config_.firmware +
            " does not answer packets after upload (a firmware for another protocol?)";
    } catch (const TransportError& e) {
      why = e.what();
    }
  }
  port_ = nullptr;
  throw TransportError("Falcon on " + where + ": " + why + "; " + std::to_string(attempts_) +
                       " load attempts: power-cycle the Falcon (its power supply!)");
}

ExchangeResult UsbTransport::exchange(const Packet& out, Packet& in) noexcept {
  if (port_ == nullptr) return {ExchangeStatus::disconnected, 0, 0};
  FtdiPort& port = *port_;
  auto fail = [](int r) {
    return ExchangeResult{r == port_no_device ? ExchangeStatus::disconnected : ExchangeStatus::usb_error, 0,
                          r};
  };
  std::size_t done = 0;
  const auto timeout = static_cast<unsigned>(config_.exchange_timeout_ms);
  if (const int r = port.bulk_write(out.data(), out.size(), done, timeout); r < 0) return fail(r);
  // Read until the FTDI has nothing more (a transfer of status bytes alone) once a report came,
  // or the bound: the newest report wins and no backlog is left for the next cycle.
  bool got = false;
  for (int reads = 0; reads < max_reads; ++reads) {
    std::size_t n = 0;
    const int r = port.bulk_read(transfer_.data(), transfer_.size(), n, timeout);
    if (r < 0 && r != port_timeout) return fail(r);
    const std::size_t data = n > ftdi_status_bytes ? n - ftdi_status_bytes : 0;
    if (data > 0) stream_.push(std::span<const std::uint8_t>(transfer_.data() + ftdi_status_bytes, data));
    got = stream_.take_newest(in) || got;
    if (data == 0 && (got || r == port_timeout)) break;
  }
  if (!got) return {ExchangeStatus::no_answer, 0, 0};
  return {ExchangeStatus::ok, packet_size, 0};
}

void UsbTransport::close() noexcept {
  port_ = nullptr;
  usb_.reset();
  stream_.clear();
}

}  // namespace saw::drivers::falcon
