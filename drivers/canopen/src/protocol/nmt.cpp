#include "saw/canopen/nmt.hpp"

#include "saw/canopen/cob.hpp"

namespace saw::canopen {

std::string_view to_string(NmtCommand c) noexcept {
  switch (c) {
    case NmtCommand::start:
      return "start remote node";
    case NmtCommand::stop:
      return "stop remote node";
    case NmtCommand::enter_pre_operational:
      return "enter pre-operational";
    case NmtCommand::reset_node:
      return "reset node";
    case NmtCommand::reset_communication:
      return "reset communication";
  }
  return "unknown NMT command";
}

std::string_view to_string(NmtState s) noexcept {
  switch (s) {
    case NmtState::initialising:
      return "initialising";
    case NmtState::stopped:
      return "stopped";
    case NmtState::operational:
      return "operational";
    case NmtState::pre_operational:
      return "pre-operational";
  }
  return "unknown NMT state";
}

can::Frame nmt_frame(NmtCommand command, std::uint8_t node) noexcept {
  const std::uint8_t bytes[2] = {static_cast<std::uint8_t>(command), node};
  return can::classic(cob::nmt, bytes);
}

std::optional<NmtRequest> parse_nmt(const can::Frame& f) noexcept {
  if (!canopen_data_frame(f) || f.can_id() != cob::nmt || f.len != 2) return std::nullopt;
  if (f.data[1] > max_node_id) return std::nullopt;
  switch (f.data[0]) {
    case 0x01:
    case 0x02:
    case 0x80:
    case 0x81:
    case 0x82:
      return NmtRequest{static_cast<NmtCommand>(f.data[0]), f.data[1]};
    default:
      return std::nullopt;
  }
}

can::Frame heartbeat_frame(std::uint8_t node, NmtState state) noexcept {
  const std::uint8_t byte = static_cast<std::uint8_t>(state);
  return can::classic(cob::heartbeat + node, {&byte, 1});
}

std::optional<Heartbeat> parse_heartbeat(const can::Frame& f) noexcept {
  if (!canopen_data_frame(f) || f.len != 1) return std::nullopt;
  const std::uint32_t id = f.can_id();
  if (id <= cob::heartbeat || id > cob::heartbeat + max_node_id) return std::nullopt;
  switch (f.data[0]) {
    case 0x00:
    case 0x04:
    case 0x05:
    case 0x7F:
      return Heartbeat{static_cast<std::uint8_t>(id - cob::heartbeat), static_cast<NmtState>(f.data[0])};
    default:
      return std::nullopt;
  }
}

void NmtNode::boot() noexcept {
  state_ = NmtState::pre_operational;
  boot_up_pending_ = true;
}

NmtReset NmtNode::on_frame(const can::Frame& f) noexcept {
  const auto request = parse_nmt(f);
  if (!request || !request->addresses(node_) || state_ == NmtState::initialising) return NmtReset::none;
  switch (request->command) {
    case NmtCommand::start:
      state_ = NmtState::operational;
      return NmtReset::none;
    case NmtCommand::stop:
      state_ = NmtState::stopped;
      return NmtReset::none;
    case NmtCommand::enter_pre_operational:
      state_ = NmtState::pre_operational;
      return NmtReset::none;
    case NmtCommand::reset_node:
      state_ = NmtState::initialising;
      boot_up_pending_ = false;
      return NmtReset::application;
    case NmtCommand::reset_communication:
      state_ = NmtState::initialising;
      boot_up_pending_ = false;
      return NmtReset::communication;
  }
  return NmtReset::none;
}

std::optional<can::Frame> NmtNode::poll() noexcept {
  if (!boot_up_pending_) return std::nullopt;
  boot_up_pending_ = false;
  return boot_up_frame(node_);
}

}  // namespace saw::canopen
