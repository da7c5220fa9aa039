// saw-socketcand's server: socketcand's raw mode over TCP on 127.0.0.1, one bus attachment per client.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/candump.hpp"
#include "saw/can/socketcand.hpp"

namespace saw::can {

struct SocketcandOptions {
  // The buses served: `virtual:<name>`, `socketcan:<ifname>`, or a bare name (virtual). A
  // client opens one by its name (the part after the colon).
  std::vector<std::string> buses;
  std::uint16_t port = 29536;  // 0: any free port (port() says which)
  std::string log;             // a candump -L file of every frame on the served buses, if set
  std::size_t max_clients = 16;
  // After the `< ok >` to `< rawmode >`, frames wait this long: python-can reads that `< ok >`
  // with one recv() and fails if a frame arrived in the same read.
  TimeNs handshake_quiet = 50'000'000;
};

// Single-threaded: one poll() loop accepts clients, reads and answers their elements, moves
// frames between them and the buses, and writes the log. Nothing a client sends can stop it:
// every element is checked, bad ones are answered with `< error ... >`.
class SocketcandServer {
 public:
  // Binds 127.0.0.1:port and attaches the log's readers; throws std::runtime_error saying why not.
  explicit SocketcandServer(SocketcandOptions options);
  ~SocketcandServer();
  SocketcandServer(const SocketcandServer&) = delete;
  SocketcandServer& operator=(const SocketcandServer&) = delete;

  std::uint16_t port() const noexcept { return port_; }
  // Serves until `stop` becomes true (a signal handler sets it).
  void run(const std::atomic<bool>& stop);

 private:
  enum class Mode { no_bus, bcm, raw };
  struct Client {
    int fd = -1;
    std::string peer;
    socketcand::Framer framer;
    Mode mode = Mode::no_bus;
    std::unique_ptr<Bus> bus;
    std::string channel;
    std::string out;   // bytes to send
    std::string held;  // frames waiting for the handshake's quiet time to pass
    TimeNs quiet_until = 0;
    std::uint64_t dropped = 0;  // frames not queued: the client reads too slowly
    bool close_after_flush = false;
    bool closed = false;
  };
  struct Served {
    std::string uri;
    std::string channel;
    std::unique_ptr<Bus> log_reader;  // sees every frame on the bus (it sends none)
  };

  void accept_clients();
  void read_from(Client& c);
  void handle(Client& c, const std::string& element);
  void queue_frame(Client& c, const Frame& f, TimeNs wall, TimeNs now);
  void move_frames(TimeNs now);
  void flush(Client& c);
  void close(Client& c, const char* why);

  SocketcandOptions options_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::vector<Served> served_;
  std::optional<CandumpWriter> log_;
  std::vector<std::unique_ptr<Client>> clients_;
  std::vector<Received> batch_;
};

}  // namespace saw::can
