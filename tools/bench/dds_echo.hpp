// Raw Fast DDS echo: answers rq/raw/add_oneRequest on rr/raw/add_oneReply with the gateway's
// types, QoS and WaitSet wait, but no bridge and no server process — the floor for our DDS path.
#pragma once

#include "saw/gateway/participant.hpp"

namespace saw::bench {

// On a participant made as the gateway's are (its interfaces, peers and enclave: docs/security.md).
[[noreturn]] void raw_dds_echo(const saw::gateway::ParticipantConfig& pc);

}  // namespace saw::bench
