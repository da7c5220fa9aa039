// FtdiPort: what UsbTransport needs of the Falcon's FTDI chip (vendor requests and the two bulk
// endpoints), the seam between the Falcon protocol and libusb. UsbTransport puts libusb behind
// it; tests put a scripted FTDI or a simulated Falcon (loader and firmware) behind it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace saw::drivers::falcon {

// The results are libusb's: 0 or a negative libusb_error; these two matter to the protocol (the
// values are libusb's, checked where libusb is included).
inline constexpr int port_timeout = -7;    // LIBUSB_ERROR_TIMEOUT: nothing (more) within the bound
inline constexpr int port_no_device = -4;  // LIBUSB_ERROR_NO_DEVICE: unplugged

class FtdiPort {
 public:
  virtual ~FtdiPort() = default;
  // An FTDI vendor request (host → device, interface 0): reset/purge, modem control, baud rate...
  virtual int control(std::uint8_t request, std::uint16_t value, unsigned timeout_ms) noexcept = 0;
  // Bulk out of `n` bytes; `done` says how many went.
  virtual int bulk_write(const std::uint8_t* data, std::size_t n, std::size_t& done,
                         unsigned timeout_ms) noexcept = 0;
  // One bulk-in transfer of at most `capacity` bytes: the FTDI's 2 modem-status bytes, then data.
  virtual int bulk_read(std::uint8_t* data, std::size_t capacity, std::size_t& got,
                        unsigned timeout_ms) noexcept = 0;
};

}  // namespace saw::drivers::falcon
