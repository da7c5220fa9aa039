// What a CANopen master counts of the frames of its bus: the figures a bus task and a node driver share.
#pragma once

#include <cstdint>

namespace saw::canopen {

// Figures since construction; each only grows.
struct FrameCounters {
  std::uint64_t cycles = 0;
  std::uint64_t frames_received = 0;
  std::uint64_t frames_sent = 0;
  std::uint64_t send_refused = 0;  // frames the bus did not take (full, down)
  std::uint64_t syncs = 0;
  std::uint64_t heartbeats = 0;       // the master's own
  std::uint64_t foreign_frames = 0;   // frames for no one here (another master's, unknown nodes)
  std::uint64_t receive_limited = 0;  // cycles that left frames for the next (max_frames)
};

}  // namespace saw::canopen
