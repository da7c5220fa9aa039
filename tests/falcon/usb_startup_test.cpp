// Start-up over the FtdiPort seam against a simulated Falcon (FTDI, loader and firmware as bytes)
// written from libnifalcon's description of the loader and packets (tests/falcon/reference/
// README.md), not from usb_transport.cpp or packet.cpp.
#include <gtest/gtest.h>

#include <array>
#include <deque>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "saw/drivers/falcon/usb_transport.hpp"

namespace saw::drivers::falcon {
namespace {

// The Falcon stays powered across open() and close(): a firmware once running keeps running and
// answers 16-byte packets at the packet baud rate (divisor 2), and its loader no longer answers
// the hello (what the real one does then is unknown; libnifalcon probes first and so do we).
class SimFalconFtdi final : public FtdiPort {
 public:
  explicit SimFalconFtdi(std::size_t firmware_size) : firmware_size_(firmware_size) {}
  int hellos_missed = 0;       // the loader misses this many hellos after each DTR toggle
  int uploads_to_corrupt = 0;  // the next uploads' echoes carry a wrong byte
  int hellos = 0, uploads = 0, packets = 0;
  bool running = false;
  void power_cycle() { running = false, stage_ = Stage::idle, out_.clear(); }

  int control(std::uint8_t request, std::uint16_t value, unsigned) noexcept override {
    if (request == 3) baud_ = value;
    if (request == 0 && value == 1) out_.clear();                                         // purge rx
    if (request == 1 && value == 0x0101 && !running) stage_ = Stage::hello, missed_ = 0;  // DTR high
    return 0;
  }
  int bulk_write(const std::uint8_t* d, std::size_t n, std::size_t& done, unsigned) noexcept override {
    done = n;
    const std::vector<std::uint8_t> bytes(d, d + n);
    if (running) {
      if (baud_ == 2 && n == 16 && d[0] == '<' && d[15] == '>') answer_packet();
      return 0;
    }
    if (stage_ == Stage::hello && baud_ == 0x4138 && bytes == std::vector<std::uint8_t>{0x0a, 0x43, 0x0d}) {
      ++hellos;
      if (missed_++ < hellos_missed) return 0;
      for (const int b : {0x0a, 0x44, 0x2c, 0x0d}) out_.push_back(static_cast<std::uint8_t>(b));
      stage_ = Stage::probe;
    } else if (stage_ == Stage::probe && baud_ == 0x15 && n == 1 && d[0] == 0x41) {
      out_.push_back(0x41);
      stage_ = Stage::upload, loaded_ = 0, ++uploads;
      corrupt_ = uploads_to_corrupt > 0 ? (--uploads_to_corrupt, true) : false;
    } else if (stage_ == Stage::upload && baud_ == 0x15) {
      for (std::size_t i = 0; i < n; ++i)
        out_.push_back(corrupt_ && loaded_ + i == 1 ? std::uint8_t{0xff} : d[i]);
      loaded_ += n;
      if (loaded_ >= firmware_size_ && !corrupt_) running = true, stage_ = Stage::idle;
    }
    return 0;
  }
  int bulk_read(std::uint8_t* d, std::size_t capacity, std::size_t& got, unsigned) noexcept override {
    d[0] = 0x31, d[1] = 0x60;
    got = 2;
    while (got < capacity && !out_.empty()) d[got++] = out_.front(), out_.pop_front();
    return 0;
  }

 private:
  enum class Stage { idle, hello, probe, upload };
  // A report: encoders 100, 200, 300 (4 nibbles each, least significant first), status 0.
  void answer_packet() {
    ++packets;
    out_.push_back('<');
    for (const unsigned v : {100u, 200u, 300u})
      for (unsigned k = 0; k < 4; ++k)
        out_.push_back(static_cast<std::uint8_t>(0x41 + ((v >> (4 * k)) & 0xf)));
    out_.push_back(0x41);
    out_.push_back(0x41);
    out_.push_back('>');
  }
  std::size_t firmware_size_;
  std::uint16_t baud_ = 0;
  Stage stage_ = Stage::idle;
  int missed_ = 0;
  std::size_t loaded_ = 0;
  bool corrupt_ = false;
  std::deque<std::uint8_t> out_;
};

struct Bench {
  static constexpr std::size_t size = 300;  // bytes of "firmware": 3 chunks
  Bench() : sim(new SimFalconFtdi(size)), usb(config(), std::unique_ptr<FtdiPort>(sim)) {}
  static UsbConfig config() {
    const auto file = std::filesystem::temp_directory_path() / "saw_falcon_startup_firmware.bin";
    std::ofstream(file, std::ios::binary) << std::string(size, 'f');
    UsbConfig c;
    c.firmware = file.string();
    c.load_attempts = 3;
    return c;
  }
  std::string open_error() {
    try {
      usb.open();
    } catch (const TransportError& e) {
      return e.what();
    }
    return {};
  }
  SimFalconFtdi* sim;
  UsbTransport usb;
};

// The loader may miss hellos: resent until answered. Catches the hello sent once.
TEST(FalconUsbStartup, TheHandshakeIsRetried) {
  Bench b;
  b.sim->hellos_missed = 4;
  ASSERT_EQ(b.open_error(), "");
  EXPECT_EQ(b.sim->hellos, 5);
  EXPECT_EQ(b.sim->uploads, 1);
  EXPECT_FALSE(b.usb.firmware_was_running());
  Packet in{};
  const ExchangeResult r = b.usb.exchange(encode_command({}), in);
  ASSERT_EQ(r.status, ExchangeStatus::ok);
  DeviceReport report{};
  ASSERT_EQ(decode_report(in, report), FrameError::none);
  EXPECT_EQ(report.encoder, (std::array<std::int16_t, 3>{100, 200, 300}));
}

// Reopened without a power cycle: the running firmware answers the probe and is kept, no loader.
// Catches the upload done every time (whose handshake a running firmware does not answer).
TEST(FalconUsbStartup, ARestartWithoutAPowerCycleKeepsTheRunningFirmware) {
  Bench b;
  ASSERT_EQ(b.open_error(), "");
  b.usb.close();
  const int hellos = b.sim->hellos;
  ASSERT_EQ(b.open_error(), "");
  EXPECT_TRUE(b.usb.firmware_was_running());
  EXPECT_EQ(b.sim->uploads, 1);
  EXPECT_EQ(b.sim->hellos, hellos);
  Packet in{};
  EXPECT_EQ(b.usb.exchange(encode_command({}), in).status, ExchangeStatus::ok);
  b.usb.close();
  b.sim->power_cycle();  // and after a power cycle it loads again
  ASSERT_EQ(b.open_error(), "");
  EXPECT_FALSE(b.usb.firmware_was_running());
  EXPECT_EQ(b.sim->uploads, 2);
}

// A failed upload (a wrong echo) is tried again from the handshake. Catches the single attempt.
TEST(FalconUsbStartup, AFailedUploadIsRetried) {
  Bench b;
  b.sim->uploads_to_corrupt = 2;
  ASSERT_EQ(b.open_error(), "");
  EXPECT_EQ(b.usb.load_attempts_made(), 3);
  EXPECT_EQ(b.sim->uploads, 3);
}

TEST(FalconUsbStartup, GivingUpSaysWhyAndHowOften) {
  Bench b;
  b.sim->uploads_to_corrupt = 5;
  const std::string e = b.open_error();
  EXPECT_NE(e.find("firmware upload failed at byte 0"), std::string::npos) << e;
  EXPECT_NE(e.find("3 load attempts"), std::string::npos) << e;
  EXPECT_NE(e.find("power-cycle"), std::string::npos) << e;
  Packet in{};
  EXPECT_EQ(b.usb.exchange(encode_command({}), in).status, ExchangeStatus::disconnected);
}

}  // namespace
}  // namespace saw::drivers::falcon
