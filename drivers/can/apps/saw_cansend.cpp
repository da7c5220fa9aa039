// saw-cansend: sends frames, written as cansend writes them (123#1122), on a sawrt CAN bus.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <vector>

#include "saw/can/bus.hpp"
#include "saw/can/candump.hpp"

int main(int argc, char** argv) {
  CLI::App app{"saw-cansend: send CAN frames on a bus (virtual:<name> or socketcan:<ifname>)"};
  std::string uri;
  std::vector<std::string> texts;
  app.add_option("bus", uri, "virtual:<name> or socketcan:<ifname>")->required();
  app.add_option("frames", texts, "frames: 123#1122, 12345678#, 123#R, 123##1AABB (FD)")->required();
  CLI11_PARSE(app, argc, argv);

  std::vector<saw::can::Frame> frames;
  bool fd = false;
  for (const auto& t : texts) {
    std::string error;
    const auto f = saw::can::parse_frame(t, &error);
    if (!f) {
      std::fprintf(stderr, "saw-cansend: '%s': %s\n", t.c_str(), error.c_str());
      return 2;
    }
    if (f->error()) {
      std::fprintf(stderr, "saw-cansend: '%s': error frames are the controller's to send\n", t.c_str());
      return 2;
    }
    fd = fd || f->fd();
    frames.push_back(*f);
  }
  saw::can::BusConfig config;
  config.uri = uri;
  config.fd = fd;
  try {
    const auto bus = saw::can::open_bus(config);
    const std::size_t sent = bus->send(frames);
    if (sent != frames.size()) {
      std::fprintf(stderr, "saw-cansend: %s took %zu of %zu frames\n", uri.c_str(), sent, frames.size());
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-cansend: %s\n", e.what());
    return 2;
  }
  return 0;
}
