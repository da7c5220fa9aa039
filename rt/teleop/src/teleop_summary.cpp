#include <cstdio>
#include <cstring>
#include <string>

#include "saw/teleop/teleoperation.hpp"

namespace saw::teleop {

std::string to_string(const TeleopSummary& s) {
  // A FAULT says why: "FAULT (master input stale: 23.4 ms old, at t=4.512 s)".
  std::string out(saw::to_string(s.state));
  if (s.state == OperatingStateValue::fault) {
    out += " (" + to_string(s.fault);
    // Bounded: a summary may come from another process.
    const std::string reason(s.reason.data(), ::strnlen(s.reason.data(), s.reason.size()));
    if (!reason.empty()) out += ": " + reason;
    out += ")";
  }
  char b[320];
  std::snprintf(b, sizeof b,
                ", tracking error |e_s| RMS %.3f mm, max %.3f mm over %llu enabled cycles; rejected settings "
                "%llu, refused force commands %llu",
                s.tracking_rms * 1e3, s.tracking_max * 1e3, static_cast<unsigned long long>(s.enabled_cycles),
                static_cast<unsigned long long>(s.rejected_commands),
                static_cast<unsigned long long>(s.refused_sends));
  out += b;
  if (s.rejected_inputs != 0 || s.offset_errors != 0) {
    std::snprintf(b, sizeof b,
                  "\n%llu input rows refused (not finite, or from the future), %llu offset trajectories "
                  "refused by Ruckig",
                  static_cast<unsigned long long>(s.rejected_inputs),
                  static_cast<unsigned long long>(s.offset_errors));
    out += b;
  }
  if (s.enabled_cycles != 0) {
    std::snprintf(b, sizeof b,
                  "\nmaster sample -> force command: mean %.1f us, max %.1f us; %llu of %llu cycles used a "
                  "sample from an earlier cycle",
                  s.master_age_mean / 1e3, static_cast<double>(s.master_age_max) / 1e3,
                  static_cast<unsigned long long>(s.master_age_late),
                  static_cast<unsigned long long>(s.enabled_cycles));
    out += b;
  }
  return out;
}

}  // namespace saw::teleop
