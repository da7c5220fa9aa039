#include "saw/canopen/units.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace saw::canopen {

DriveUnits DriveUnits::rotary(double counts_per_revolution, double gear_ratio, double rated_torque_nm) {
  DriveUnits u{counts_per_revolution, gear_ratio, 2 * std::numbers::pi, rated_torque_nm};
  u.check();
  return u;
}

DriveUnits DriveUnits::linear(double counts_per_revolution, double gear_ratio, double lead_m,
                              double rated_torque_nm) {
  DriveUnits u{counts_per_revolution, gear_ratio, lead_m, rated_torque_nm};
  u.check();
  return u;
}

void DriveUnits::check() const {
  const auto positive = [](const char* name, double v) {
    if (!std::isfinite(v) || v <= 0)
      throw std::invalid_argument(std::string("drive units: ") + name + " must be finite and above 0, is " +
                                  std::to_string(v));
  };
  positive("counts per revolution", counts_per_revolution);
  positive("gear ratio", gear_ratio);
  positive("travel per revolution", si_per_revolution);
  positive("rated torque", rated_torque);
}

namespace {

// Rounds to the nearest integer of type T, refusing what T cannot hold.
template <class T>
Codec round_into(double v, T& out) noexcept {
  if (!std::isfinite(v)) return Codec::invalid;
  const double r = std::nearbyint(v);
  if (r > static_cast<double>(std::numeric_limits<T>::max())) return Codec::too_high;
  if (r < static_cast<double>(std::numeric_limits<T>::min())) return Codec::too_low;
  out = static_cast<T>(r);
  return Codec::ok;
}

// Units that were never set (a default-constructed DriveUnits) convert nothing, rather than
// turning every setpoint into 0 counts.
bool usable(double factor) noexcept { return std::isfinite(factor) && factor > 0; }

}  // namespace

Codec DriveUnits::position_to_counts(double si, std::int32_t& counts) const noexcept {
  if (!usable(counts_per_si())) return Codec::invalid;
  return round_into(si * counts_per_si(), counts);
}

Codec DriveUnits::velocity_to_counts(double si_per_s, std::int32_t& counts_per_s) const noexcept {
  if (!usable(counts_per_si())) return Codec::invalid;
  return round_into(si_per_s * counts_per_si(), counts_per_s);
}

Codec DriveUnits::torque_to_per_mille(double nm, std::int16_t& per_mille) const noexcept {
  if (!usable(rated_torque)) return Codec::invalid;
  return round_into(nm / rated_torque * 1000.0, per_mille);
}

}  // namespace saw::canopen
