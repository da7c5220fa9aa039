#include "saw/canopen/rpdo_deadline.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace saw::canopen {

namespace {
constexpr TimeNs ms = 1'000'000;
}  // namespace

std::uint16_t deadline_ms(TimeNs t) noexcept {
  if (t <= 0) return 0;
  return static_cast<std::uint16_t>(std::min<TimeNs>((t + ms - 1) / ms, 0xFFFF));
}

TimeNs resolve_rpdo_deadline(std::optional<TimeNs> deadline, TimeNs period) {
  // Three periods by default, as the command timeout: one late cycle is jitter, not starvation.
  if (!deadline) return static_cast<TimeNs>(deadline_ms(std::max<TimeNs>(5 * ms, 3 * period))) * ms;
  if (*deadline == 0) return 0;
  if (*deadline < 0 || *deadline > 0xFFFF * ms)
    throw std::invalid_argument("rpdo_deadline must be 0 (off) or up to 65.535 s (0x1400:05 holds ms)");
  const TimeNs rounded = static_cast<TimeNs>(deadline_ms(*deadline)) * ms;
  if (rounded < 2 * period)
    throw std::invalid_argument("rpdo_deadline (" + std::to_string(rounded / ms) +
                                " ms in whole ms) must be at least two periods (" +
                                std::to_string(2 * period / 1000) + " us), or 0 (off)");
  return rounded;
}

std::vector<std::uint16_t> rpdos_without_event_timer(const Eds& eds, std::span<const PdoMapping> pdos) {
  std::vector<std::uint16_t> out;
  for (const PdoMapping& m : pdos) {
    if (m.kind != PdoKind::rpdo || !m.enabled) continue;
    const EdsEntry* e = eds.find({m.communication_index(), 5});
    if (e == nullptr || !writable(e->access)) out.push_back(m.number);
  }
  return out;
}

std::vector<std::uint16_t> unwatched_rpdos(std::span<const PdoMapping> pdos, const RpdoDeadline& deadline,
                                           std::span<const SdoWrite> written) {
  std::vector<std::uint16_t> out;
  if (!deadline.time || *deadline.time == 0) return out;
  for (const PdoMapping& m : pdos) {
    if (m.kind != PdoKind::rpdo || !m.enabled) continue;
    const ObjectAddress timer{m.communication_index(), 5};
    const bool made = std::any_of(written.begin(), written.end(), [&](const SdoWrite& w) {
      return w.address == timer && w.value == deadline_ms(*deadline.time);
    });
    if (!made) out.push_back(m.number);
  }
  return out;
}

}  // namespace saw::canopen
