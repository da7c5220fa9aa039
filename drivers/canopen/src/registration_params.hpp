// The parameter readers the CANopen types share (registration.cpp, registration_bus.cpp; not installed).
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "saw/canopen/axis.hpp"
#include "saw/canopen/eds.hpp"
#include "saw/canopen/pdo.hpp"
#include "saw/deploy/registry.hpp"

namespace saw::canopen {

namespace params {
// A duration within [lo, hi] (file:line:key otherwise).
TimeNs duration(const deploy::Params& p, const std::string& key, std::chrono::nanoseconds fallback,
                std::chrono::nanoseconds lo, std::chrono::nanoseconds hi);
cia402::Mode parse_mode(const deploy::Params& p);
// `pdo:` or `eds:` (its identity too, and the parsed file in `eds` if given); neither: the CiA
// 402 defaults for the mode.
std::vector<PdoMapping> parse_pdos(const deploy::Params& p, cia402::Mode mode, std::uint8_t node,
                                   const std::string& directory, std::optional<DriveIdentity>& identity,
                                   std::optional<Eds>* eds = nullptr);
// `sdo: ["0x60C2:01:u8=10", ...]`.
std::vector<SdoWrite> parse_writes(const deploy::Params& p);
// `rpdo_deadline: 5ms` (rounded up to whole ms, at least two periods), `off` or 0: not watched;
// absent: nullopt (the component's default, resolve_rpdo_deadline()).
std::optional<TimeNs> rpdo_deadline(const deploy::Params& p, TimeNs period);
// `bus:`: a URI, or the name of a canopen_bus component.
std::string parse_bus(const deploy::Params& p);
}  // namespace params

// canopen_bus and canopen_io (registration_bus.cpp).
void register_bus_components(deploy::ComponentRegistry& registry);

}  // namespace saw::canopen
