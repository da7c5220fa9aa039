// An SDO server (CiA 301 7.2.4): serves an ObjectDictionary, expedited and segmented, frame in, frame out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "saw/can/frame.hpp"
#include "saw/canopen/dictionary.hpp"
#include "saw/canopen/sdo.hpp"
#include "saw/clock.hpp"

namespace saw::canopen {

struct SdoServerConfig {
  SdoChannel channel = SdoChannel::of_node(1);  // as the client sees it: requests in, responses out
  TimeNs timeout = 1'000'000'000;               // a segmented transfer left waiting this long is aborted
  std::size_t capacity = 1024;                  // the largest object it transfers
  bool expedited = true;                        // answer uploads of 1..4 bytes expedited
};

// The device end of an SDO channel, for the simulated drive. What an object accepts (exists,
// access, length, range) is the dictionary's answer; the server adds the protocol's own checks
// (command specifier, toggle bit, announced size against the bytes received, timeout) and turns
// every refusal into an abort frame. Block transfers are refused (command specifier).
// No allocation after construction.
class SdoServer {
 public:
  SdoServer(SdoServerConfig config, ObjectDictionary& dictionary);

  void on_frame(const can::Frame& frame, TimeNs now) noexcept;
  std::optional<can::Frame> poll(TimeNs now) noexcept;

  bool busy() const noexcept { return phase_ != Phase::idle; }
  // The abort this server last sent (none if it never did): for tests and diagnostics.
  SdoAbort last_abort() const noexcept { return last_abort_; }

 private:
  enum class Phase : std::uint8_t { idle, download, upload };

  void respond(const can::Frame& f) noexcept { pending_ = f; }
  void abort(ObjectAddress address, SdoAbort code) noexcept;
  void initiate_download(const can::Frame& f, TimeNs now) noexcept;
  void download_segment(const can::Frame& f, TimeNs now) noexcept;
  void initiate_upload(const can::Frame& f, TimeNs now) noexcept;
  void upload_segment(const can::Frame& f, TimeNs now) noexcept;

  SdoServerConfig config_;
  ObjectDictionary& dictionary_;
  std::vector<std::uint8_t> buffer_;
  Phase phase_ = Phase::idle;
  ObjectAddress address_;
  std::optional<std::size_t> indicated_;  // download: the size the client announced
  std::size_t size_ = 0;                  // upload: the value's size
  std::size_t done_ = 0;                  // bytes received (download) or sent (upload)
  bool toggle_ = false;
  TimeNs deadline_ = 0;
  SdoAbort last_abort_ = SdoAbort::none;
  std::optional<can::Frame> pending_;
};

}  // namespace saw::canopen
