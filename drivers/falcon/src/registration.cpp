// The Falcon package's type for deployments: each parameter read, range-checked and located.
#include "saw/drivers/falcon/registration.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "saw/deploy/device_settings.hpp"
#include "saw/drivers/falcon/falcon_params.hpp"
#include "saw/drivers/falcon/threaded_transport.hpp"
#include "saw/eigen.hpp"

namespace saw::drivers::falcon {
namespace {

using namespace std::chrono_literals;
using deploy::Params;

std::uint8_t buttons(const Params& p, const std::string& key, std::uint8_t fallback) {
  const int v = p.get_or<int>(key, fallback);
  if (v < 0 || v > 0x0f) p.fail_at(key, "a mask of the four grip buttons: 0..15");
  return static_cast<std::uint8_t>(v);
}

std::string summary_line(const FalconSummary& s) {
  char b[400];
  std::snprintf(b, sizeof b,
                "%llu exchanges: %llu unanswered, %llu USB errors (last %d), %llu corrupt frames refused, "
                "%llu poses out of the model, %llu forces saturated, reopened %llu times after an unplug",
                static_cast<unsigned long long>(s.exchanges), static_cast<unsigned long long>(s.no_answer),
                static_cast<unsigned long long>(s.usb_errors), s.last_usb_error,
                static_cast<unsigned long long>(s.bad_frames),
                static_cast<unsigned long long>(s.out_of_model), static_cast<unsigned long long>(s.saturated),
                static_cast<unsigned long long>(s.reopened));
  return b;
}

}  // namespace

FalconSpec parse_falcon(const deploy::ComponentContext& ctx, Params& p) {
  FalconSpec s;
  s.transport = p.get_enum<TransportKind>(
      "transport", {{"usb", TransportKind::usb}, {"sim", TransportKind::sim}}, TransportKind::usb);
  s.task = deploy::periodic_task(ctx, p, "falcon");
  s.io_thread = p.get_or<bool>("io_thread", s.transport == TransportKind::usb);
  const int io_default = s.task.priority > 0 ? std::min(s.task.priority + 1, 99) : 0;
  s.io_priority = static_cast<int>(p.get_in_range("io_priority", 0, 99, io_default));
  // A Falcon unplugged and plugged in again is opened again by the I/O thread (its next enable
  // homes it): looked for every `reconnect`, 0 never.
  s.reconnect = p.get_or<std::chrono::nanoseconds>("reconnect", s.io_thread ? 1s : 0s).count();
  if (s.reconnect < 0 || s.reconnect > std::chrono::nanoseconds(60s).count())
    p.fail_at("reconnect", "in [0, 60 s] (0: an unplugged Falcon stays closed)");
  if (s.reconnect > 0 && !s.io_thread)
    p.fail_at("reconnect", "needs io_thread: true (the cycle never waits for a USB enumeration)");
  FalconConfig& c = s.device;
  if (p.has("homing_timeout")) p.fail_at("homing_timeout", "is now home_timeout (a key of every device)");
  c.contract = deploy::parse_device_settings(p, s.task, {.most_force = 20, .homes = true, .workspace = true},
                                             c.contract);
  if (p.has("origin")) c.origin = to_eigen(p.get<Vec3>("origin"));
  c.home_on_start = p.get_or<bool>("home_on_start", true);
  c.homing_dac = static_cast<std::int16_t>(p.get_in_range("homing_dac", 0, 4096, c.homing_dac));
  c.max_missed = static_cast<int>(p.get_in_range("max_missed", 1, 1000, c.max_missed));
  c.velocity_filter = p.get_in_range("velocity_filter", 0.01, 1, c.velocity_filter);
  c.clutch_buttons = buttons(p, "clutch_buttons", c.clutch_buttons);
  c.operator_buttons = buttons(p, "operator_buttons", c.operator_buttons);
  if (p.has("calibration")) {
    const Params k = p.child("calibration");
    DeltaGeometry& g = c.geometry;
    g.dac_per_newton_metre = k.get_in_range("dac_per_newton_metre", -1e6, 1e6, g.dac_per_newton_metre);
    if (g.dac_per_newton_metre == 0) k.fail_at("dac_per_newton_metre", "must not be zero");
    g.dac_limit = static_cast<int>(k.get_in_range("dac_limit", 1, 32767, g.dac_limit));
    g.angle_at_zero = k.get_in_range("angle_at_zero", -3.2, 3.2, g.angle_at_zero);
  }
  if (s.transport == TransportKind::usb) {
    std::filesystem::path fw = p.get<std::string>("firmware");
    if (fw.is_relative() && !ctx.directory.empty()) fw = std::filesystem::path(ctx.directory) / fw;
    s.usb.firmware = fw.string();
    if (p.has("usb")) {
      const Params u = p.child("usb");
      s.usb.bus = static_cast<int>(u.get_in_range("bus", -1, 255, -1));
      s.usb.index = static_cast<int>(u.get_in_range("index", 0, 15, 0));
      s.usb.exchange_timeout_ms = static_cast<int>(u.get_in_range("exchange_timeout_ms", 1, 100, 1));
      s.usb.handshake_tries =
          static_cast<int>(u.get_in_range("handshake_tries", 1, 1000, s.usb.handshake_tries));
      s.usb.load_attempts = static_cast<int>(u.get_in_range("load_attempts", 1, 100, s.usb.load_attempts));
    }
  } else {
    SimFirmwareConfig& f = s.sim;
    f.geometry = c.geometry;
    f.dt = static_cast<double>(s.task.period.count()) * 1e-9;
    if (p.has("sim")) {
      const Params m = p.child("sim");
      f.inertia = m.get_in_range("inertia", 1e-6, 1, f.inertia);
      f.damping = m.get_in_range("damping", 0, 1, f.damping);
      if (m.has("initial_angles")) f.initial_angles = to_eigen(m.get<Vec3>("initial_angles"));
      f.operator_homes = m.get_or<bool>("operator_homes", f.operator_homes);
      if (m.has("hand")) {
        const Params h = m.child("hand");
        f.hand = true;
        f.hand_amplitude = to_eigen(h.get_or<Vec3>("amplitude", {0, 0, 0}));
        f.hand_frequency = h.get_in_range("frequency", 0, 100, f.hand_frequency);
        f.hand_stiffness = h.get_in_range("stiffness", 0, 5000, f.hand_stiffness);
        f.hand_damping = h.get_in_range("damping", 0, 500, f.hand_damping);
      }
    }
  }
  return s;
}

std::unique_ptr<FalconTransport> make_transport(const FalconSpec& s) {
  std::unique_ptr<FalconTransport> t;
  if (s.transport == TransportKind::sim)
    t = std::make_unique<SimTransport>(s.sim);
  else
    t = std::make_unique<UsbTransport>(s.usb);
  if (s.io_thread) t = std::make_unique<ThreadedTransport>(std::move(t), s.io_priority, 100'000, s.reconnect);
  return t;
}

void register_components(deploy::ComponentRegistry& registry) {
  registry.add("falcon",
               "Novint Falcon (libusb-1.0, or its simulated firmware) as a CRTK arm, delta kinematics",
               parse_falcon, [](const std::string& name, const FalconSpec& s) {
                 return std::make_unique<FalconDevice>(name, s.task, s.device, make_transport(s));
               });
  registry.add_summary_format<FalconSummary>(summary_line);
}

}  // namespace saw::drivers::falcon
