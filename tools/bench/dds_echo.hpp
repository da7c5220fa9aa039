// Raw Fast DDS echo: answers rq/raw/add_oneRequest on rr/raw/add_oneReply with the gateway's
// types, QoS and WaitSet wait, but no bridge and no server process — the floor for our DDS path.
#pragma once

#include <string>
#include <vector>

namespace saw::bench {

[[noreturn]] void raw_dds_echo(int domain, const std::vector<std::string>& interfaces);

}  // namespace saw::bench
