// NMT (CiA 301 7.2.8): commands as frames, node states, boot-up and heartbeat, a node's NMT machine.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "saw/can/frame.hpp"

namespace saw::canopen {

enum class NmtCommand : std::uint8_t {
  start = 0x01,
  stop = 0x02,
  enter_pre_operational = 0x80,
  reset_node = 0x81,
  reset_communication = 0x82,
};

// A node's state as its heartbeat carries it; initialising is what the boot-up message says.
enum class NmtState : std::uint8_t {
  initialising = 0x00,
  stopped = 0x04,
  operational = 0x05,
  pre_operational = 0x7F
};

std::string_view to_string(NmtCommand c) noexcept;
std::string_view to_string(NmtState s) noexcept;

// The NMT command frame (identifier 0, 2 bytes) for `node`, or for every node when node is 0.
can::Frame nmt_frame(NmtCommand command, std::uint8_t node) noexcept;

struct NmtRequest {
  NmtCommand command = NmtCommand::start;
  std::uint8_t node = 0;  // 0: all nodes
  bool addresses(std::uint8_t n) const noexcept { return node == 0 || node == n; }
};
// An NMT command frame, checked: identifier 0, exactly 2 bytes, a known command, node 0..127.
std::optional<NmtRequest> parse_nmt(const can::Frame& f) noexcept;

// The heartbeat (0x700 + node, 1 byte: the state); the boot-up message is one saying initialising.
can::Frame heartbeat_frame(std::uint8_t node, NmtState state) noexcept;
inline can::Frame boot_up_frame(std::uint8_t node) noexcept {
  return heartbeat_frame(node, NmtState::initialising);
}

struct Heartbeat {
  std::uint8_t node = 0;
  NmtState state = NmtState::initialising;
  bool boot_up() const noexcept { return state == NmtState::initialising; }
};
// A heartbeat or boot-up frame, checked: identifier 0x701..0x77F, 1 byte, bit 7 clear (the
// node-guarding toggle has no place in a heartbeat), a known state.
std::optional<Heartbeat> parse_heartbeat(const can::Frame& f) noexcept;

// What a reset command asks the device to do before it boots again.
enum class NmtReset : std::uint8_t { none, communication, application };

// The NMT state machine of a node (CiA 301 figure 48), without the resets themselves: those are
// the device's, which calls boot() once done. No allocation, no exception.
class NmtNode {
 public:
  explicit NmtNode(std::uint8_t node) noexcept : node_(node) {}

  // Initialisation finished (power-on or after a reset): queues the boot-up message and
  // enters pre-operational, as CiA 301 does without being told.
  void boot() noexcept;
  // Applies an NMT command addressed to this node (others are ignored). A reset leaves the
  // node initialising and says which reset the device must perform.
  NmtReset on_frame(const can::Frame& f) noexcept;
  // The boot-up message, once after each boot().
  std::optional<can::Frame> poll() noexcept;

  NmtState state() const noexcept { return state_; }
  std::uint8_t node() const noexcept { return node_; }

 private:
  std::uint8_t node_;
  NmtState state_ = NmtState::initialising;
  bool boot_up_pending_ = false;
};

}  // namespace saw::canopen
