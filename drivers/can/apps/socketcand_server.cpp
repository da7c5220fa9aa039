// saw-socketcand's poll() loop: clients in, frames both ways, the log.
#include "socketcand_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace saw::can {
namespace {

constexpr std::size_t max_queued = 4 << 20;    // bytes queued to one client before frames are dropped
constexpr std::size_t frames_per_pass = 1024;  // per bus attachment and loop pass

std::string channel_of(const std::string& uri) {
  const auto colon = uri.find(':');
  return colon == std::string::npos ? uri : uri.substr(colon + 1);
}

// Clients may send CAN FD frames (fdsend) and receive them (fdframe).
BusConfig config_for(const std::string& uri) {
  BusConfig c;
  c.uri = uri;
  c.fd = true;
  return c;
}

std::string uri_of(const std::string& bus) {
  return bus.find(':') == std::string::npos ? "virtual:" + bus : bus;
}

}  // namespace

SocketcandServer::SocketcandServer(SocketcandOptions options) : options_(std::move(options)) {
  if (options_.buses.empty()) throw std::runtime_error("no bus to serve (--bus)");
  for (const auto& b : options_.buses) {
    Served s;
    s.uri = uri_of(b);
    s.channel = channel_of(s.uri);
    for (const auto& other : served_)
      if (other.channel == s.channel)
        throw std::runtime_error("bus name '" + s.channel + "' is served twice");
    if (!options_.log.empty()) s.log_reader = open_bus(config_for(s.uri));
    served_.push_back(std::move(s));
  }
  if (!options_.log.empty()) log_.emplace(options_.log);
  batch_.resize(64);

  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  const int on = 1;
  (void)::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(options_.port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);  // loopback only, whatever the options say
  if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, 16) != 0) {
    const std::string e = std::strerror(errno);
    ::close(listen_fd_);
    throw std::runtime_error("listen on 127.0.0.1:" + std::to_string(options_.port) + ": " + e);
  }
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

SocketcandServer::~SocketcandServer() {
  for (auto& c : clients_)
    if (c->fd >= 0) ::close(c->fd);
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

void SocketcandServer::run(const std::atomic<bool>& stop) {
  std::vector<pollfd> fds;
  TimeNs last_log_flush = monotonic_now();
  while (!stop.load(std::memory_order_relaxed)) {
    fds.clear();
    fds.push_back(pollfd{listen_fd_, POLLIN, 0});
    const TimeNs now = monotonic_now();
    for (const auto& c : clients_) {
      short events = POLLIN;
      if (!c->out.empty()) events |= POLLOUT;
      fds.push_back(pollfd{c->fd, events, 0});
    }
    // The buses have no descriptor to wait on: with a reader attached, poll them every ms.
    bool busy = log_.has_value();
    for (const auto& c : clients_) busy = busy || c->bus != nullptr;
    (void)::poll(fds.data(), fds.size(), busy ? 1 : 100);
    if ((fds[0].revents & POLLIN) != 0) accept_clients();
    for (std::size_t i = 1; i < fds.size(); ++i) {
      Client& c = *clients_[i - 1];
      if ((fds[i].revents & (POLLIN | POLLHUP | POLLERR)) != 0) read_from(c);
    }
    move_frames(now);
    for (auto& c : clients_) flush(*c);
    std::erase_if(clients_, [](const std::unique_ptr<Client>& c) { return c->closed; });
    if (log_ && monotonic_now() - last_log_flush > 200'000'000) {
      log_->flush();
      last_log_flush = monotonic_now();
    }
  }
  if (log_) log_->flush();
}

void SocketcandServer::accept_clients() {
  for (;;) {
    sockaddr_in peer{};
    socklen_t len = sizeof peer;
    const int fd =
        ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // EAGAIN: none left; anything else: the next poll tries again
    char ip[INET_ADDRSTRLEN] = "?";
    ::inet_ntop(AF_INET, &peer.sin_addr, ip, sizeof ip);
    const std::string name = std::string(ip) + ":" + std::to_string(ntohs(peer.sin_port));
    if (clients_.size() >= options_.max_clients) {
      const std::string busy = socketcand::format_error("too many clients");
      (void)::send(fd, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      ::close(fd);
      std::fprintf(stderr, "saw-socketcand: %s refused: %zu clients already\n", name.c_str(),
                   clients_.size());
      continue;
    }
    const int on = 1;
    (void)::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    auto c = std::make_unique<Client>();
    c->fd = fd;
    c->peer = name;
    c->out = "< hi >";
    std::fprintf(stderr, "saw-socketcand: %s: connected\n", name.c_str());
    clients_.push_back(std::move(c));
  }
}

void SocketcandServer::read_from(Client& c) {
  char buf[4096];
  // A bounded amount per pass, each chunk answered before the next is read: one client cannot
  // hold the loop, and what it sends is never buffered whole.
  for (int chunk = 0; chunk < 16 && !c.closed && !c.close_after_flush; ++chunk) {
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0) return close(c, "disconnected");
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return;
      return close(c, std::strerror(errno));
    }
    c.framer.feed(std::string_view(buf, static_cast<std::size_t>(n)));
    std::string error;
    while (!c.closed && !c.close_after_flush) {
      auto element = c.framer.next(error);
      if (element)
        handle(c, *element);
      else if (!error.empty())
        c.out += socketcand::format_error(error);
      else
        break;
    }
    // Answers pile up only for a client that sends and never reads.
    if (c.out.size() > max_queued) return close(c, "sends and does not read its answers");
    if (static_cast<std::size_t>(n) < sizeof buf) return;
  }
}

void SocketcandServer::handle(Client& c, const std::string& element) {
  std::string error;
  const auto cmd = socketcand::parse_command(element, error);
  if (!cmd) {
    c.out += socketcand::format_error(error);
    return;
  }
  using Kind = socketcand::Command::Kind;
  if (cmd->kind == Kind::echo) {
    c.out += "< echo >";
    return;
  }
  if (cmd->kind == Kind::open) {
    if (c.mode != Mode::no_bus) {
      c.out += socketcand::format_error("a bus is open already");
      return;
    }
    const Served* s = nullptr;
    for (const auto& served : served_)
      if (served.channel == cmd->bus) s = &served;
    if (s == nullptr) {
      // As socketcand: an error, then the connection ends.
      c.out += socketcand::format_error("no bus '" + cmd->bus.substr(0, 64) + "' here");
      c.close_after_flush = true;
      return;
    }
    try {
      c.bus = open_bus(config_for(s->uri));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "saw-socketcand: %s: %s\n", c.peer.c_str(), e.what());
      c.out += socketcand::format_error("cannot open bus '" + cmd->bus + "'");
      c.close_after_flush = true;
      return;
    }
    c.channel = s->channel;
    c.mode = Mode::bcm;
    c.out += "< ok >";
    return;
  }
  if (c.mode == Mode::no_bus) {
    c.out += socketcand::format_error("open a bus first: < open <bus> >");
    return;
  }
  switch (cmd->kind) {
    case Kind::rawmode:
      c.mode = Mode::raw;
      c.out += "< ok >";
      c.quiet_until = monotonic_now() + options_.handshake_quiet;
      return;
    case Kind::bcmmode:
      c.mode = Mode::bcm;
      c.held.clear();
      c.out += "< ok >";
      return;
    case Kind::send:
      if (c.bus->send(std::span<const Frame>(&cmd->frame, 1)) != 1)
        c.out += socketcand::format_error("the bus refused the frame");
      return;
    default:
      return;
  }
}

void SocketcandServer::queue_frame(Client& c, const Frame& f, TimeNs wall, TimeNs now) {
  std::string& to = now < c.quiet_until ? c.held : c.out;
  if (c.out.size() + c.held.size() > max_queued) {
    if (c.dropped++ == 0)
      std::fprintf(stderr, "saw-socketcand: %s reads too slowly: dropping frames\n", c.peer.c_str());
    return;
  }
  to += socketcand::format_frame(f, wall);
}

void SocketcandServer::move_frames(TimeNs now) {
  const TimeNs to_wall = wall_clock_offset();
  for (auto& c : clients_) {
    if (c->bus == nullptr || c->closed) continue;
    if (now >= c->quiet_until && !c->held.empty()) {
      c->out += c->held;
      c->held.clear();
    }
    for (std::size_t moved = 0; moved < frames_per_pass;) {
      const std::size_t n = c->bus->receive(batch_);
      if (n == 0) break;
      moved += n;
      if (c->mode != Mode::raw) continue;  // BCM mode: nothing subscribed, nothing forwarded
      for (std::size_t i = 0; i < n; ++i) queue_frame(*c, batch_[i].frame, batch_[i].time + to_wall, now);
    }
  }
  if (!log_) return;
  for (auto& s : served_)
    for (std::size_t moved = 0; moved < frames_per_pass;) {
      const std::size_t n = s.log_reader->receive(batch_);
      if (n == 0) break;
      moved += n;
      for (std::size_t i = 0; i < n; ++i)
        log_->write_wall(batch_[i].time + to_wall, batch_[i].frame, s.channel);
    }
}

void SocketcandServer::flush(Client& c) {
  while (!c.closed && !c.out.empty()) {
    const ssize_t n = ::send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return;
      return close(c, std::strerror(errno));
    }
    c.out.erase(0, static_cast<std::size_t>(n));
  }
  if (c.close_after_flush && c.out.empty()) close(c, "closed after an error");
}

void SocketcandServer::close(Client& c, const char* why) {
  if (c.closed) return;
  std::fprintf(stderr, "saw-socketcand: %s: %s", c.peer.c_str(), why);
  if (c.dropped > 0)
    std::fprintf(stderr, " (%llu frames dropped: it read too slowly)",
                 static_cast<unsigned long long>(c.dropped));
  std::fputc('\n', stderr);
  ::close(c.fd);
  c.fd = -1;
  c.closed = true;
  c.bus.reset();
}

}  // namespace saw::can
