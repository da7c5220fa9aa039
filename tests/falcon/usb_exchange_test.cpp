// The USB exchange without USB: scripted FTDI transfers (split, doubled, late, status-only) behind
// the FtdiPort seam. Catches the exchange that took the oldest buffered report and kept the rest:
// once two reports were buffered it stayed one exchange behind for good and the backlog grew.
#include <gtest/gtest.h>

#include <deque>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "saw/drivers/falcon/report_stream.hpp"
#include "saw/drivers/falcon/usb_transport.hpp"

namespace saw::drivers::falcon {
namespace {

// A report written byte by byte (not packet.cpp): encoder 0 = `n`, the others 0, status 0.
std::string report(unsigned n) {
  std::string s = "<";
  for (unsigned k = 0; k < 4; ++k) s += static_cast<char>('A' + ((n >> (4 * k)) & 0xf));
  s += "AAAAAAAAAA>";  // encoders 1 and 2, status, byte 14
  return s;
}

std::int16_t encoder0(const Packet& p) {
  unsigned v = 0;
  for (unsigned k = 0; k < 4; ++k) v |= static_cast<unsigned>(p[1 + k] - 'A') << (4 * k);
  return static_cast<std::int16_t>(v);
}

// Each bulk read hands out the next scripted transfer (its data; the 2 status bytes are added),
// or the status bytes alone when the script is empty, as an idle FTDI does.
class ScriptedFtdi final : public FtdiPort {
 public:
  std::deque<std::string> transfers;
  int writes = 0, reads = 0;
  int control(std::uint8_t, std::uint16_t, unsigned) noexcept override { return 0; }
  int bulk_write(const std::uint8_t*, std::size_t n, std::size_t& done, unsigned) noexcept override {
    ++writes;
    done = n;
    return 0;
  }
  int bulk_read(std::uint8_t* data, std::size_t, std::size_t& got, unsigned) noexcept override {
    ++reads;
    data[0] = 0x31, data[1] = 0x60;  // FTDI modem and line status
    got = 2;
    if (transfers.empty()) return 0;
    const std::string t = transfers.front();
    transfers.pop_front();
    for (std::size_t i = 0; i < t.size(); ++i) data[2 + i] = static_cast<std::uint8_t>(t[i]);
    got += t.size();
    return 0;
  }
};

TEST(FalconReportStream, TheNewestCompleteFrameWinsAndAPartialOneWaits) {
  ReportStream s;
  Packet p{};
  const std::string two = report(1) + report(2) + report(3).substr(0, 5);
  s.push(std::span(reinterpret_cast<const std::uint8_t*>(two.data()), two.size()));
  ASSERT_TRUE(s.take_newest(p));
  EXPECT_EQ(encoder0(p), 2);
  EXPECT_EQ(s.skipped(), 1u);
  EXPECT_EQ(s.buffered(), 5u) << "the start of report 3 waits";
  EXPECT_FALSE(s.take_newest(p));
  const std::string rest = report(3).substr(5) + "xx";
  s.push(std::span(reinterpret_cast<const std::uint8_t*>(rest.data()), rest.size()));
  ASSERT_TRUE(s.take_newest(p));
  EXPECT_EQ(encoder0(p), 3);
  EXPECT_EQ(s.buffered(), 0u) << "bytes that frame nothing are dropped";
}

TEST(FalconReportStream, ResynchronisesAfterALostByteAndNeverOverflows) {
  ReportStream s;
  Packet p{};
  std::string bad = report(7);
  bad.erase(6, 1);  // a byte lost: '<' no longer frames 16 bytes
  const std::string bytes = bad + report(8);
  s.push(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
  ASSERT_TRUE(s.take_newest(p));
  EXPECT_EQ(encoder0(p), 8);
  std::string flood;
  for (unsigned i = 0; i < 40; ++i) flood += report(i);
  s.push(std::span(reinterpret_cast<const std::uint8_t*>(flood.data()), flood.size()));
  EXPECT_LE(s.buffered(), ReportStream::capacity);
  ASSERT_TRUE(s.take_newest(p));
  EXPECT_EQ(encoder0(p), 39);
}

// A firmware file for open() (its content is never sent: the firmware answers the first probe).
UsbConfig config_with_firmware() {
  const auto file = std::filesystem::temp_directory_path() / "saw_falcon_exchange_firmware.bin";
  std::ofstream(file, std::ios::binary) << "fw";
  UsbConfig c;
  c.firmware = file.string();
  return c;
}

struct Exchanger {
  Exchanger() : port(new ScriptedFtdi), transport(config_with_firmware(), std::unique_ptr<FtdiPort>(port)) {
    port->transfers.push_back(report(0));
    transport.open();
  }
  // One exchange: the encoder 0 of the report returned, -1 for none.
  int exchange() {
    Packet in{};
    const ExchangeResult r = transport.exchange(Packet{}, in);
    return r.status == ExchangeStatus::ok ? encoder0(in) : -1;
  }
  ScriptedFtdi* port;
  UsbTransport transport;
};

TEST(FalconUsbExchange, TheNewestReportIsUsedAndNoBacklogBuilds) {
  Exchanger x;
  EXPECT_TRUE(x.transport.firmware_was_running());
  auto& t = x.port->transfers;
  t = {report(1)};
  EXPECT_EQ(x.exchange(), 1) << "one report, one transfer";
  t = {report(2).substr(0, 9), report(2).substr(9)};
  EXPECT_EQ(x.exchange(), 2) << "split over two transfers";
  t = {report(3) + report(4)};
  EXPECT_EQ(x.exchange(), 4) << "doubled: the newer";
  EXPECT_EQ(x.transport.stream().buffered(), 0u);
  t = {"", report(5)};
  EXPECT_EQ(x.exchange(), 5) << "late: after a transfer of status bytes alone";
  t = {};
  EXPECT_EQ(x.exchange(), -1) << "status-only: no answer";
  t = {report(6), report(7) + report(8).substr(0, 4)};
  EXPECT_EQ(x.exchange(), 7) << "a backlog over two transfers: the newest complete";
  t = {report(8).substr(4)};
  EXPECT_EQ(x.exchange(), 8) << "the partial one completes next time";
  // A device always one report ahead of us (the old exchange stayed behind for good): every
  // exchange reads the two waiting and takes the newer; nothing is left over.
  for (unsigned n = 10; n < 40; n += 2) {
    t = {report(n) + report(n + 1)};
    EXPECT_EQ(x.exchange(), static_cast<int>(n + 1));
    EXPECT_EQ(x.transport.stream().buffered(), 0u);
  }
  EXPECT_LE(x.port->reads, 200);
}

TEST(FalconUsbExchange, ReadsAreBounded) {
  Exchanger x;
  auto& t = x.port->transfers;
  for (int i = 0; i < 50; ++i) t.push_back("xxxxxxxxxx");  // noise, forever
  const int before = x.port->reads;
  EXPECT_EQ(x.exchange(), -1);
  EXPECT_LE(x.port->reads - before, 4);
}

}  // namespace
}  // namespace saw::drivers::falcon
