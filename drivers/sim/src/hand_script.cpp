#include "saw/drivers/hand_script.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace saw::drivers {

std::vector<HandSample> HandScript::load_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the hand trajectory");
  std::vector<HandSample> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#' ||
        (number == 1 && !std::isdigit(static_cast<unsigned char>(line[0])) && line[0] != '-' &&
         line[0] != '.'))
      continue;  // comments and a header line
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) {
      try {
        std::size_t used = 0;
        v.push_back(std::stod(cell, &used));
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(number) + ": '" + cell + "' is not a number");
      }
    }
    if (v.size() != 4 && v.size() != 5)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected t,x,y,z[,clutch], got " +
                               std::to_string(v.size()) + " values");
    if (!out.empty() && v[0] <= out.back().t)
      throw std::runtime_error(path + ":" + std::to_string(number) + ": time must increase");
    out.push_back({v[0], {v[1], v[2], v[3]}, v.size() == 5 && v[4] != 0});
  }
  if (out.empty()) throw std::runtime_error(path + ": no samples");
  return out;
}

namespace {

// The minimum-jerk blend at u in [0, 1]: 10u³ − 15u⁴ + 6u⁵.
double minimum_jerk(double u) noexcept {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (10 + u * (-15 + 6 * u));
}

// Origin → targets[0] → … → targets[n-1] → origin, repeated: each leg a reach, then a dwell.
Eigen::Vector3d reach_position(const HandScript& h, double t) noexcept {
  const std::size_t legs = h.targets.size() + 1;
  const double leg_time = h.reach_time + h.dwell;
  if (h.targets.empty() || leg_time <= 0) return Eigen::Vector3d::Zero();
  const double cycle = std::fmod(std::max(t, 0.0), leg_time * static_cast<double>(legs));
  const auto leg = std::min(static_cast<std::size_t>(cycle / leg_time), legs - 1);
  const auto point = [&](std::size_t i) {
    return i == 0 || i == legs ? Eigen::Vector3d::Zero() : h.targets[i - 1];
  };
  const Eigen::Vector3d from = point(leg), to = point(leg + 1);
  const double within = cycle - static_cast<double>(leg) * leg_time;
  return from + minimum_jerk(h.reach_time > 0 ? within / h.reach_time : 1.0) * (to - from);
}

Eigen::Vector3d tremor(const HandScript& h, double t) noexcept {
  // Three incommensurate frequencies and phases: the tremor does not repeat as one sinusoid would.
  static constexpr double ratio[3] = {1.0, 1.09, 0.93}, phase[3] = {0.0, 1.3, 2.6};
  Eigen::Vector3d d;
  for (int k = 0; k < 3; ++k)
    d[k] = h.tremor_amplitude * std::sin(2 * M_PI * h.tremor_frequency * ratio[k] * t + phase[k]);
  return d;
}

}  // namespace

HandSample HandScript::target(double t, std::size_t& cursor) const noexcept {
  HandSample s{t, Eigen::Vector3d::Zero(), false};
  switch (kind) {
    case Kind::none:
      break;
    case Kind::line: {
      double u = duration > 0 ? t / duration : 1.0;
      if (back_and_forth) {
        const double cycle = std::fmod(u, 2.0);
        u = cycle <= 1.0 ? cycle : 2.0 - cycle;
      }
      u = std::clamp(u, 0.0, 1.0);
      s.position = from + u * (to - from);
      break;
    }
    case Kind::sinusoid:
      s.position = amplitude * std::sin(2 * M_PI * frequency * t + phase);
      break;
    case Kind::csv: {
      if (samples.empty()) break;
      while (cursor + 1 < samples.size() && samples[cursor + 1].t <= t) ++cursor;
      const HandSample& a = samples[cursor];
      if (cursor + 1 >= samples.size() || t <= a.t) {
        s.position = a.position;
        s.clutch = a.clutch;
        break;
      }
      const HandSample& b = samples[cursor + 1];
      const double u = (t - a.t) / (b.t - a.t);
      s.position = a.position + u * (b.position - a.position);
      s.clutch = a.clutch;
      break;
    }
    case Kind::reach:
      s.position = reach_position(*this, t);
      break;
  }
  if (kind != Kind::none && tremor_amplitude > 0) s.position += tremor(*this, t);
  const double wave = std::sin(2 * M_PI * frequency * t + phase);
  for (const auto& [pressed, released] : clutch_windows)
    s.clutch = s.clutch || (t >= pressed && t < released);
  s.turn = turn_amplitude * wave;
  s.grip = grip_mean + grip_amplitude * wave;
  return s;
}

}  // namespace saw::drivers
