// The SocketCAN backend: a CAN_RAW socket configured at open, moved in batches in the cycle.
#include "saw/can/socketcan_bus.hpp"

#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace saw::can {
namespace {

constexpr std::string_view scheme = "socketcan:";

// The error classes that say something about the bus state or a lost transmission. Bus errors
// (CAN_ERR_PROT, CAN_ERR_ACK) come only when the driver reports them; they are counted too.
constexpr can_err_mask_t error_classes = CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_CRTL | CAN_ERR_PROT |
                                         CAN_ERR_TRX | CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_BUSERROR |
                                         CAN_ERR_RESTARTED;

TimeNs realtime_now() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

BusState error_frame_state(const Frame& f, BusState before) noexcept {
  const std::uint32_t classes = f.id & CAN_ERR_MASK;
  if ((classes & CAN_ERR_BUSOFF) != 0) return BusState::bus_off;
  BusState s = before;
  if ((classes & CAN_ERR_RESTARTED) != 0) s = BusState::error_active;
  if ((classes & CAN_ERR_CRTL) != 0 && f.len > 1) {
    const std::uint8_t c = f.data[1];
    if ((c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0)
      s = BusState::error_passive;
    else if ((c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0)
      s = BusState::error_warning;
    else if ((c & CAN_ERR_CRTL_ACTIVE) != 0)
      s = BusState::error_active;
  }
  return s;
}

SocketCanBus::SocketCanBus(const BusConfig& config) : name_(config.uri), fd_frames_(config.fd) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("CAN bus '" + name_ + "': " + why);
  };
  const auto failed = [&](const std::string& call) {
    const std::string e = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return fail(call + ": " + e);
  };
  if (name_.rfind(scheme, 0) != 0) throw fail("not a socketcan:<ifname> bus");
  const std::string ifname = name_.substr(scheme.size());
  if (ifname.empty() || ifname.size() >= IFNAMSIZ || ifname.find('/') != std::string::npos)
    throw fail("'" + ifname + "' is not a network interface name (1 to " + std::to_string(IFNAMSIZ - 1) +
               " characters)");

  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    if (errno == EAFNOSUPPORT)
      throw fail(std::string("this kernel has no AF_CAN (socket(PF_CAN, SOCK_RAW, CAN_RAW): ") +
                 std::strerror(errno) + "); use a virtual:<name> bus here");
    throw failed("socket(PF_CAN, SOCK_RAW, CAN_RAW)");
  }
  const unsigned index = ::if_nametoindex(ifname.c_str());
  if (index == 0) {
    const std::string e = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw fail("no such network interface '" + ifname + "' (" + e + ")");
  }
  if (fd_frames_) {
    ifreq ifr{};
    std::memcpy(ifr.ifr_name, ifname.c_str(), ifname.size() + 1);
    if (::ioctl(fd_, SIOCGIFMTU, &ifr) < 0) throw failed("SIOCGIFMTU " + ifname);
    if (ifr.ifr_mtu < static_cast<int>(CANFD_MTU)) {
      ::close(fd_);
      fd_ = -1;
      throw fail("interface '" + ifname + "' is not CAN FD capable (MTU " + std::to_string(ifr.ifr_mtu) +
                 "); open it without fd, or set it up with `ip link set " + ifname + " mtu 72`");
    }
    const int on = 1;
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0)
      throw failed("setsockopt CAN_RAW_FD_FRAMES");
  }
  if (!config.filters.empty()) {
    std::vector<can_filter> filters;
    for (const auto& f : config.filters) filters.push_back(can_filter{f.id, f.mask});
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                     static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0)
      throw failed("setsockopt CAN_RAW_FILTER");
  }
  const can_err_mask_t errors = error_classes;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) != 0)
    throw failed("setsockopt CAN_RAW_ERR_FILTER");
  const int on = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) != 0)
    throw failed("setsockopt SO_TIMESTAMPNS");
  if (::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) != 0) throw failed("setsockopt SO_RXQ_OVFL");
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0)
    throw failed("bind to " + ifname);
  prepare_arrays();
}

SocketCanBus::SocketCanBus(int fd, std::string name, bool fd_frames)
    : name_(std::move(name)), fd_(fd), fd_frames_(fd_frames) {
  const int on = 1;
  // Best effort: a socket that gives no timestamps is stamped when read, one with no drop
  // count reports none.
  (void)::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  (void)::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
  prepare_arrays();
}

SocketCanBus::~SocketCanBus() {
  if (fd_ >= 0) ::close(fd_);
}

void SocketCanBus::prepare_arrays() {
  in_msgs_.assign(batch, mmsghdr{});
  out_msgs_.assign(batch, mmsghdr{});
  in_iov_.assign(batch, iovec{});
  out_iov_.assign(batch, iovec{});
  control_.assign(batch, Control{});
}

void SocketCanBus::note_errno(int error) noexcept {
  // The interface went down (or away): the state says so until frames flow again.
  if (error == ENETDOWN || error == ENODEV || error == ENXIO)
    state_.store(BusState::down, std::memory_order_relaxed);
}

std::size_t SocketCanBus::receive(std::span<Received> out) noexcept {
  std::size_t n = 0;
  std::uint64_t malformed = 0, errors = 0;
  TimeNs realtime_to_monotonic = 0;
  bool offset_known = false;
  while (n < out.size()) {
    const std::size_t want = std::min(out.size() - n, batch);
    // The kernel writes each frame straight into the caller's array; what is not a good data
    // frame is squeezed out below.
    for (std::size_t i = 0; i < want; ++i) {
      in_iov_[i] = iovec{&out[n + i].frame, sizeof(Frame)};
      msghdr& h = in_msgs_[i].msg_hdr;
      h = msghdr{};
      h.msg_iov = &in_iov_[i];
      h.msg_iovlen = 1;
      h.msg_control = control_[i].bytes;
      h.msg_controllen = sizeof control_[i].bytes;
    }
    const int got = ::recvmmsg(fd_, in_msgs_.data(), static_cast<unsigned>(want), MSG_DONTWAIT, nullptr);
    if (got <= 0) {
      if (got < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) note_errno(errno);
      break;
    }
    std::size_t kept = n;
    for (std::size_t i = 0; i < static_cast<std::size_t>(got); ++i) {
      Frame f = out[n + i].frame;
      const mmsghdr& m = in_msgs_[i];
      TimeNs time = 0;
      for (cmsghdr* c = CMSG_FIRSTHDR(&m.msg_hdr); c != nullptr;
           c = CMSG_NXTHDR(const_cast<msghdr*>(&m.msg_hdr), c)) {
        if (c->cmsg_level != SOL_SOCKET) continue;
        if (c->cmsg_type == SCM_TIMESTAMPNS && c->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
          timespec ts;
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          if (!offset_known) {  // the kernel stamps CLOCK_REALTIME; the cycle's clock is MONOTONIC
            realtime_to_monotonic = monotonic_now() - realtime_now();
            offset_known = true;
          }
          time = static_cast<TimeNs>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec + realtime_to_monotonic;
        } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
          std::uint32_t drops;  // the socket's drops since open, as the kernel counts them
          std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
          if (drops > overruns_.load(std::memory_order_relaxed))
            overruns_.store(drops, std::memory_order_relaxed);
        }
      }
      if (time == 0) time = monotonic_now();
      bool good = (m.msg_hdr.msg_flags & MSG_TRUNC) == 0;
      if (good && m.msg_len == CAN_MTU) {
        good = f.flags == 0;  // a classic frame's flags byte is padding the kernel zeroes
      } else if (good && m.msg_len == CANFD_MTU) {
        f.flags |= CANFD_FDF;  // kernels before 5.14 tell FD frames by their size only
      } else {
        good = false;
      }
      if (good && f.error()) {
        ++errors;
        state_.store(error_frame_state(f, state_.load(std::memory_order_relaxed)), std::memory_order_relaxed);
        continue;
      }
      if (!good || !well_formed(f)) {
        ++malformed;
        continue;
      }
      if (state_.load(std::memory_order_relaxed) == BusState::down)
        state_.store(BusState::error_active, std::memory_order_relaxed);
      out[kept].frame = f;
      out[kept].time = time;
      ++kept;
    }
    n = kept;
    if (static_cast<std::size_t>(got) < want) break;  // drained
  }
  if (n > 0) bump(received_, n);
  if (malformed > 0) bump(malformed_, malformed);
  if (errors > 0) bump(error_frames_, errors);
  return n;
}

std::size_t SocketCanBus::send(std::span<const Frame> frames) noexcept {
  std::size_t accepted = 0;
  bool stop = false;
  while (!stop && accepted < frames.size()) {
    std::size_t count = 0;
    while (count < batch && accepted + count < frames.size()) {
      const Frame& f = frames[accepted + count];
      // The caller's mistakes are refused here, not by the kernel's EINVAL.
      if (!well_formed(f) || f.error() || (f.fd() && !fd_frames_)) {
        stop = true;
        break;
      }
      out_iov_[count] = iovec{const_cast<Frame*>(&f), f.fd() ? CANFD_MTU : CAN_MTU};
      msghdr& h = out_msgs_[count].msg_hdr;
      h = msghdr{};
      h.msg_iov = &out_iov_[count];
      h.msg_iovlen = 1;
      ++count;
    }
    if (count == 0) break;
    const int sent = ::sendmmsg(fd_, out_msgs_.data(), static_cast<unsigned>(count), MSG_DONTWAIT);
    if (sent <= 0) {
      // EAGAIN/ENOBUFS: the interface's queue is full. Refused, counted; the caller decides.
      if (sent < 0) note_errno(errno);
      break;
    }
    accepted += static_cast<std::size_t>(sent);
    if (state_.load(std::memory_order_relaxed) == BusState::down)  // the interface is back
      state_.store(BusState::error_active, std::memory_order_relaxed);
    if (static_cast<std::size_t>(sent) < count) break;
  }
  if (accepted > 0) bump(sent_, accepted);
  if (accepted < frames.size()) bump(refused_, frames.size() - accepted);
  return accepted;
}

BusCounters SocketCanBus::counters() const noexcept {
  BusCounters c;
  c.received = received_.load(std::memory_order_relaxed);
  c.sent = sent_.load(std::memory_order_relaxed);
  c.send_refused = refused_.load(std::memory_order_relaxed);
  c.overruns = overruns_.load(std::memory_order_relaxed);
  c.malformed = malformed_.load(std::memory_order_relaxed);
  c.error_frames = error_frames_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace saw::can
