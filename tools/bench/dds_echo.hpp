// Raw Fast DDS echo: answers rq/raw/add_oneRequest on rr/raw/add_oneReply with the gateway's
// types, QoS and WaitSet wait, but no bridge and no server process — the floor for our DDS path.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace saw::bench {

// With `enclave`, a DDS Security participant (docs/security.md).
[[noreturn]] void raw_dds_echo(int domain, const std::vector<std::string>& interfaces,
                               const std::optional<std::filesystem::path>& enclave = std::nullopt);

}  // namespace saw::bench
