// An SDO client (CiA 301 7.2.4): expedited and segmented upload and download, frame in, frame out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "saw/can/frame.hpp"
#include "saw/canopen/od.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

struct SdoClientConfig {
  SdoChannel channel = SdoChannel::of_node(1);
  // Longest wait for each response. CiA 301 leaves it to the application; drives answer in
  // milliseconds, slower ones (storing parameters, 0x1010) take up to a second.
  TimeNs timeout = 500'000'000;
  std::size_t capacity = 1024;  // the largest transfer, either way (at least 8)
};

enum class SdoStatus : std::uint8_t { idle, busy, done, failed };

// Where a transfer stands; Ruckig's shape: a value the caller inspects after each step.
struct SdoResult {
  SdoStatus status = SdoStatus::idle;
  SdoAbort abort = SdoAbort::none;  // why it failed
  bool remote = false;              // the server aborted; else this client did (and told the server)
  std::size_t size = 0;             // bytes moved so far
};

// Segmented: even 1..4 bytes go in segments (testing, or a server that refuses expedited).
enum class SdoMode : std::uint8_t { automatic, segmented };

// One transfer at a time. Feed every received frame to on_frame() (others' frames are
// ignored) and send what poll() returns; poll() also runs the timeout. No allocation after
// construction, no lock, no exception: usable in an RT cycle. Every response is checked
// (identifier, length, command specifier, multiplexer, toggle bit, sizes) before it is used;
// a response to another object (a late answer to an abandoned transfer) is ignored.
class SdoClient {
 public:
  explicit SdoClient(SdoClientConfig config = {});

  // Starts reading `address`; false if a transfer is in progress.
  bool upload(ObjectAddress address, TimeNs now) noexcept;
  // Starts writing `data` (copied); false if busy or larger than the capacity.
  bool download(ObjectAddress address, std::span<const std::uint8_t> data, TimeNs now,
                SdoMode mode = SdoMode::automatic) noexcept;
  // Encodes `value` as `type` and downloads it; false if busy or the value does not fit the type.
  template <class T>
  bool download_value(ObjectAddress address, DataType type, T value, TimeNs now) noexcept {
    std::uint8_t bytes[8];
    const std::span<std::uint8_t> span(bytes, size_of(type));
    return encode_value(type, value, span) == Codec::ok && download(address, span, now);
  }
  // Abandons the transfer in progress, telling the server why.
  void abort(SdoAbort code) noexcept;

  void on_frame(const can::Frame& frame, TimeNs now) noexcept;
  std::optional<can::Frame> poll(TimeNs now) noexcept;

  const SdoResult& result() const noexcept { return result_; }
  bool busy() const noexcept { return result_.status == SdoStatus::busy; }
  ObjectAddress address() const noexcept { return address_; }
  // The uploaded bytes once result().status is done.
  std::span<const std::uint8_t> data() const noexcept { return {buffer_.data(), result_.size}; }
  // The uploaded value decoded as `type`.
  template <class T>
  Codec value(DataType type, T& out) const noexcept {
    return decode_value(type, data(), out);
  }

 private:
  enum class Phase : std::uint8_t {
    idle,
    download_initiate,
    download_segment,
    upload_initiate,
    upload_segment
  };

  void start(ObjectAddress address, Phase phase, TimeNs now) noexcept;
  void send(const can::Frame& f, TimeNs now) noexcept;
  void send_download_segment(TimeNs now) noexcept;
  void succeed() noexcept;
  void fail(SdoAbort code, bool remote) noexcept;
  void on_download(const can::Frame& f, std::uint8_t cs, TimeNs now) noexcept;
  void on_upload(const can::Frame& f, std::uint8_t cs, TimeNs now) noexcept;

  SdoClientConfig config_;
  std::vector<std::uint8_t> buffer_;
  Phase phase_ = Phase::idle;
  SdoResult result_;
  ObjectAddress address_;
  std::size_t total_ = 0;                 // download: bytes to send
  std::optional<std::size_t> indicated_;  // upload: the size the server announced
  bool toggle_ = false;
  bool last_sent_ = false;  // download: the segment in flight is the last
  bool expedited_ = false;  // download: sent expedited
  TimeNs deadline_ = 0;
  std::optional<can::Frame> pending_;
};

}  // namespace saw::canopen
