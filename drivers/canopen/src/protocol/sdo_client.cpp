#include "saw/canopen/sdo_client.hpp"

#include <algorithm>
#include <cstring>

#include "saw/canopen/cob.hpp"
#include "sdo_protocol.hpp"

namespace saw::canopen {

SdoClient::SdoClient(SdoClientConfig config)
    : config_(config), buffer_(std::max<std::size_t>(config.capacity, 8)) {}

void SdoClient::start(ObjectAddress address, Phase phase, TimeNs now) noexcept {
  address_ = address;
  phase_ = phase;
  result_ = {SdoStatus::busy, SdoAbort::none, false, 0};
  toggle_ = false;
  last_sent_ = false;
  expedited_ = false;
  indicated_.reset();
  deadline_ = now + config_.timeout;
}

void SdoClient::send(const can::Frame& f, TimeNs now) noexcept {
  pending_ = f;
  deadline_ = now + config_.timeout;
}

bool SdoClient::upload(ObjectAddress address, TimeNs now) noexcept {
  if (busy()) return false;
  start(address, Phase::upload_initiate, now);
  send(sdo::frame(config_.channel.request, sdo::ccs::initiate_upload << 5, address), now);
  return true;
}

bool SdoClient::download(ObjectAddress address, std::span<const std::uint8_t> data, TimeNs now,
                         SdoMode mode) noexcept {
  if (busy() || data.size() > buffer_.size()) return false;
  start(address, Phase::download_initiate, now);
  std::copy(data.begin(), data.end(), buffer_.begin());
  total_ = data.size();
  // Expedited carries 1..4 bytes; an empty value has no expedited form (n is two bits).
  expedited_ = mode == SdoMode::automatic && total_ >= 1 && total_ <= 4;
  if (expedited_) {
    const auto n = static_cast<std::uint8_t>(4 - total_);
    can::Frame f = sdo::frame(
        config_.channel.request,
        static_cast<std::uint8_t>(sdo::ccs::initiate_download << 5 | n << 2 | sdo::bit_e | sdo::bit_s),
        address);
    std::copy_n(buffer_.begin(), total_, f.data + 4);
    send(f, now);
  } else {
    can::Frame f =
        sdo::frame(config_.channel.request,
                   static_cast<std::uint8_t>(sdo::ccs::initiate_download << 5 | sdo::bit_s), address);
    sdo::put_u32(f.data + 4, static_cast<std::uint32_t>(total_));
    send(f, now);
  }
  return true;
}

void SdoClient::send_download_segment(TimeNs now) noexcept {
  const std::size_t chunk = std::min<std::size_t>(sdo::segment_data, total_ - result_.size);
  last_sent_ = result_.size + chunk == total_;
  const auto n = static_cast<std::uint8_t>(sdo::segment_data - chunk);
  const auto command = static_cast<std::uint8_t>(
      sdo::ccs::download_segment << 5 | (toggle_ ? sdo::bit_t : 0) | n << 1 | (last_sent_ ? sdo::bit_c : 0));
  can::Frame f = sdo::frame(config_.channel.request, command);
  std::copy_n(buffer_.begin() + static_cast<std::ptrdiff_t>(result_.size), chunk, f.data + 1);
  send(f, now);
  result_.size += chunk;  // counted when sent; confirmed by the response's toggle
}

void SdoClient::abort(SdoAbort code) noexcept {
  if (busy()) fail(code, false);
}

void SdoClient::succeed() noexcept {
  phase_ = Phase::idle;
  result_.status = SdoStatus::done;
}

void SdoClient::fail(SdoAbort code, bool remote) noexcept {
  phase_ = Phase::idle;
  result_.status = SdoStatus::failed;
  result_.abort = code;
  result_.remote = remote;
  // Only a client-side abort is sent: answering the server's abort would start a ping-pong.
  pending_ = remote ? std::nullopt : std::optional(sdo_abort_frame(config_.channel.request, address_, code));
}

void SdoClient::on_frame(const can::Frame& f, TimeNs now) noexcept {
  if (!busy() || f.can_id() != config_.channel.response || !canopen_data_frame(f)) return;
  if (f.len != sdo::frame_length) return fail(SdoAbort::command_specifier, false);
  const std::uint8_t cs = sdo::specifier(f);
  if (cs == sdo::abort_cs) {
    // The abort names the transfer it ends; one naming another object is a stale answer.
    if (sdo::multiplexer(f) != address_) return;
    return fail(static_cast<SdoAbort>(sdo::u32(f.data + 4)), true);
  }
  switch (phase_) {
    case Phase::download_initiate:
    case Phase::download_segment:
      return on_download(f, cs, now);
    case Phase::upload_initiate:
    case Phase::upload_segment:
      return on_upload(f, cs, now);
    case Phase::idle:
      return;
  }
}

void SdoClient::on_download(const can::Frame& f, std::uint8_t cs, TimeNs now) noexcept {
  if (phase_ == Phase::download_initiate) {
    if (cs != sdo::scs::initiate_download) return fail(SdoAbort::command_specifier, false);
    if (sdo::multiplexer(f) != address_) return;  // stale: a late answer to another transfer
    if (expedited_) {
      result_.size = total_;
      return succeed();
    }
    phase_ = Phase::download_segment;
    return send_download_segment(now);
  }
  if (cs != sdo::scs::download_segment) return fail(SdoAbort::command_specifier, false);
  if (((f.data[0] & sdo::bit_t) != 0) != toggle_) return fail(SdoAbort::toggle_bit, false);
  if (last_sent_) return succeed();
  toggle_ = !toggle_;
  send_download_segment(now);
}

void SdoClient::on_upload(const can::Frame& f, std::uint8_t cs, TimeNs now) noexcept {
  const std::uint8_t command = f.data[0];
  if (phase_ == Phase::upload_initiate) {
    if (cs != sdo::scs::initiate_upload) return fail(SdoAbort::command_specifier, false);
    if (sdo::multiplexer(f) != address_) return;
    const bool e = (command & sdo::bit_e) != 0, s = (command & sdo::bit_s) != 0;
    if (e) {
      // Expedited: 4 - n bytes if the size is indicated, else all four.
      const std::size_t n = s ? 4u - ((command >> 2) & 0x3u) : 4u;
      std::copy_n(f.data + 4, n, buffer_.begin());
      result_.size = n;
      return succeed();
    }
    if (s) {
      const std::uint32_t size = sdo::u32(f.data + 4);
      if (size > buffer_.size()) return fail(SdoAbort::out_of_memory, false);
      indicated_ = size;
    }
    phase_ = Phase::upload_segment;
    return send(sdo::frame(config_.channel.request, sdo::ccs::upload_segment << 5), now);
  }
  if (cs != sdo::scs::upload_segment) return fail(SdoAbort::command_specifier, false);
  if (((command & sdo::bit_t) != 0) != toggle_) return fail(SdoAbort::toggle_bit, false);
  const std::size_t chunk = sdo::segment_data - ((command >> 1) & 0x7u);
  const bool last = (command & sdo::bit_c) != 0;
  if (result_.size + chunk > buffer_.size()) return fail(SdoAbort::out_of_memory, false);
  if (indicated_ && result_.size + chunk > *indicated_) return fail(SdoAbort::length_mismatch, false);
  std::copy_n(f.data + 1, chunk, buffer_.begin() + static_cast<std::ptrdiff_t>(result_.size));
  result_.size += chunk;
  if (last) {
    if (indicated_ && result_.size != *indicated_) return fail(SdoAbort::length_mismatch, false);
    return succeed();
  }
  toggle_ = !toggle_;
  send(sdo::frame(config_.channel.request,
                  static_cast<std::uint8_t>(sdo::ccs::upload_segment << 5 | (toggle_ ? sdo::bit_t : 0))),
       now);
}

std::optional<can::Frame> SdoClient::poll(TimeNs now) noexcept {
  if (busy() && !pending_ && now >= deadline_) fail(SdoAbort::timeout, false);
  std::optional<can::Frame> out = pending_;
  pending_.reset();
  return out;
}

}  // namespace saw::canopen
