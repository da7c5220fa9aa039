#include "saw/canopen/sdo_server.hpp"

#include <algorithm>

#include "saw/canopen/cob.hpp"
#include "sdo_protocol.hpp"

namespace saw::canopen {

SdoServer::SdoServer(SdoServerConfig config, ObjectDictionary& dictionary)
    : config_(config), dictionary_(dictionary), buffer_(std::max<std::size_t>(config.capacity, 8)) {}

void SdoServer::abort(ObjectAddress address, SdoAbort code) noexcept {
  phase_ = Phase::idle;
  last_abort_ = code;
  respond(sdo_abort_frame(config_.channel.response, address, code));
}

void SdoServer::on_frame(const can::Frame& f, TimeNs now) noexcept {
  if (f.can_id() != config_.channel.request || !canopen_data_frame(f)) return;
  if (f.len != sdo::frame_length) {
    // The multiplexer as far as the frame carries it, the rest 0: bytes past len are whatever the
    // sender's buffer or virtual-bus slot held, not something to echo.
    can::Frame carried;
    std::copy_n(f.data, std::min<std::size_t>(f.len, 4), carried.data);
    return abort(sdo::multiplexer(carried), SdoAbort::command_specifier);
  }
  switch (sdo::specifier(f)) {
    case sdo::ccs::initiate_download:
      return initiate_download(f, now);
    case sdo::ccs::download_segment:
      return download_segment(f, now);
    case sdo::ccs::initiate_upload:
      return initiate_upload(f, now);
    case sdo::ccs::upload_segment:
      return upload_segment(f, now);
    case sdo::abort_cs:
      // The client ended the transfer; an abort is never answered.
      if (busy() && sdo::multiplexer(f) == address_) phase_ = Phase::idle;
      return;
    default:  // block upload, block download (not supported), and the unassigned 7
      return abort(sdo::multiplexer(f), SdoAbort::command_specifier);
  }
}

// A new initiate replaces a transfer in progress: the client gave up on it (its timeout).
void SdoServer::initiate_download(const can::Frame& f, TimeNs now) noexcept {
  phase_ = Phase::idle;
  address_ = sdo::multiplexer(f);
  const std::uint8_t command = f.data[0];
  const bool e = (command & sdo::bit_e) != 0, s = (command & sdo::bit_s) != 0;
  if (e) {
    const std::size_t n = s ? 4u - ((command >> 2) & 0x3u) : 4u;
    if (const SdoAbort a = dictionary_.write(address_, {f.data + 4, n}, s); a != SdoAbort::none)
      return abort(address_, a);
    return respond(sdo::frame(config_.channel.response, sdo::scs::initiate_download << 5, address_));
  }
  indicated_.reset();
  if (s) {
    const std::uint32_t size = sdo::u32(f.data + 4);
    if (size > buffer_.size()) return abort(address_, SdoAbort::out_of_memory);
    indicated_ = size;
  }
  if (const SdoAbort a = dictionary_.check_download(address_, indicated_); a != SdoAbort::none)
    return abort(address_, a);
  phase_ = Phase::download;
  toggle_ = false;
  done_ = 0;
  deadline_ = now + config_.timeout;
  respond(sdo::frame(config_.channel.response, sdo::scs::initiate_download << 5, address_));
}

void SdoServer::download_segment(const can::Frame& f, TimeNs now) noexcept {
  if (phase_ != Phase::download) return abort(address_, SdoAbort::command_specifier);
  deadline_ = now + config_.timeout;
  const std::uint8_t command = f.data[0];
  if (((command & sdo::bit_t) != 0) != toggle_) return abort(address_, SdoAbort::toggle_bit);
  const std::size_t chunk = sdo::segment_data - ((command >> 1) & 0x7u);
  if (done_ + chunk > buffer_.size()) return abort(address_, SdoAbort::out_of_memory);
  if (indicated_ && done_ + chunk > *indicated_) return abort(address_, SdoAbort::length_too_high);
  std::copy_n(f.data + 1, chunk, buffer_.begin() + static_cast<std::ptrdiff_t>(done_));
  done_ += chunk;
  const auto response =
      static_cast<std::uint8_t>(sdo::scs::download_segment << 5 | (toggle_ ? sdo::bit_t : 0));
  if ((command & sdo::bit_c) != 0) {
    if (indicated_ && done_ < *indicated_) return abort(address_, SdoAbort::length_too_low);
    if (const SdoAbort a = dictionary_.write(address_, {buffer_.data(), done_}, true); a != SdoAbort::none)
      return abort(address_, a);
    phase_ = Phase::idle;
    return respond(sdo::frame(config_.channel.response, response));
  }
  toggle_ = !toggle_;
  respond(sdo::frame(config_.channel.response, response));
}

void SdoServer::initiate_upload(const can::Frame& f, TimeNs now) noexcept {
  phase_ = Phase::idle;
  address_ = sdo::multiplexer(f);
  std::size_t size = 0;
  if (const SdoAbort a = dictionary_.read(address_, buffer_, size); a != SdoAbort::none)
    return abort(address_, a);
  if (config_.expedited && size >= 1 && size <= 4) {
    const auto n = static_cast<std::uint8_t>(4 - size);
    can::Frame r = sdo::frame(
        config_.channel.response,
        static_cast<std::uint8_t>(sdo::scs::initiate_upload << 5 | n << 2 | sdo::bit_e | sdo::bit_s),
        address_);
    std::copy_n(buffer_.begin(), size, r.data + 4);
    return respond(r);
  }
  can::Frame r = sdo::frame(config_.channel.response,
                            static_cast<std::uint8_t>(sdo::scs::initiate_upload << 5 | sdo::bit_s), address_);
  sdo::put_u32(r.data + 4, static_cast<std::uint32_t>(size));
  phase_ = Phase::upload;
  size_ = size;
  done_ = 0;
  toggle_ = false;
  deadline_ = now + config_.timeout;
  respond(r);
}

void SdoServer::upload_segment(const can::Frame& f, TimeNs now) noexcept {
  if (phase_ != Phase::upload) return abort(address_, SdoAbort::command_specifier);
  deadline_ = now + config_.timeout;
  if (((f.data[0] & sdo::bit_t) != 0) != toggle_) return abort(address_, SdoAbort::toggle_bit);
  const std::size_t chunk = std::min<std::size_t>(sdo::segment_data, size_ - done_);
  const bool last = done_ + chunk == size_;
  const auto n = static_cast<std::uint8_t>(sdo::segment_data - chunk);
  can::Frame r =
      sdo::frame(config_.channel.response,
                 static_cast<std::uint8_t>(sdo::scs::upload_segment << 5 | (toggle_ ? sdo::bit_t : 0) |
                                           n << 1 | (last ? sdo::bit_c : 0)));
  std::copy_n(buffer_.begin() + static_cast<std::ptrdiff_t>(done_), chunk, r.data + 1);
  done_ += chunk;
  toggle_ = !toggle_;
  if (last) phase_ = Phase::idle;
  respond(r);
}

std::optional<can::Frame> SdoServer::poll(TimeNs now) noexcept {
  if (busy() && !pending_ && now >= deadline_) abort(address_, SdoAbort::timeout);
  std::optional<can::Frame> out = pending_;
  pending_.reset();
  return out;
}

}  // namespace saw::canopen
