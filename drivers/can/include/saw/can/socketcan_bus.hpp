// A kernel CAN interface (can0, vcan0) through a non-blocking CAN_RAW socket.
#pragma once

#include <sys/socket.h>
#include <sys/uio.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"

namespace saw::can {

// Opened outside the RT cycle with everything configured (FD, filters, error frames, kernel
// timestamps, drop counts); in the cycle only recvmmsg/sendmmsg with MSG_DONTWAIT on arrays made
// at open. Error frames move state() and are counted, never returned as data. receive() is called
// by one thread at a time, send() by one thread at a time; the rest from any thread.
class SocketCanBus final : public Bus {
 public:
  // Frames moved by one recvmmsg/sendmmsg call.
  static constexpr std::size_t batch = 64;

  // Opens `config.uri` ("socketcan:<ifname>"); throws std::runtime_error naming the bus and the
  // reason (no AF_CAN in this kernel, no such interface, not CAN FD capable, ...).
  explicit SocketCanBus(const BusConfig& config);
  // Adopts `fd`, a socket that carries one frame per datagram as CAN_RAW does (struct can_frame
  // or canfd_frame), and closes it when done: how the tests drive this class where the kernel
  // has no AF_CAN. Timestamps and drop counts are asked for and used if the socket gives them.
  SocketCanBus(int fd, std::string name, bool fd_frames);
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  std::size_t receive(std::span<Received> out) noexcept override;
  std::size_t send(std::span<const Frame> frames) noexcept override;
  BusState state() const noexcept override { return state_.load(std::memory_order_relaxed); }
  BusCounters counters() const noexcept override;
  const std::string& name() const noexcept override { return name_; }

 private:
  // A relaxed load and store: each counter has one writing thread; readers want figures.
  static void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
    c.store(c.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
  }
  void prepare_arrays();
  void note_errno(int error) noexcept;

  std::string name_;
  int fd_ = -1;
  bool fd_frames_ = false;

  // Per-message control space: a timestamp (SO_TIMESTAMPNS) and a drop count (SO_RXQ_OVFL).
  struct alignas(cmsghdr) Control {
    unsigned char bytes[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  };
  std::vector<mmsghdr> in_msgs_, out_msgs_;
  std::vector<iovec> in_iov_, out_iov_;
  std::vector<Control> control_;

  std::atomic<BusState> state_{BusState::error_active};
  std::atomic<std::uint64_t> received_{0}, overruns_{0}, malformed_{0}, error_frames_{0};
  std::atomic<std::uint64_t> sent_{0}, refused_{0};
};

// The controller state an error frame reports (bus-off, restarted, the controller's warning and
// passive bits), or `before` when it reports none of them.
BusState error_frame_state(const Frame& error_frame, BusState before) noexcept;

}  // namespace saw::can
