// The ZeroC Ice 3.7 baseline (the paper's middleware): a server and a client loop over TCP.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace saw::bench {

// Serves sawbench::Latency on TCP at `host` (an ephemeral port), writes its proxy string to
// `report_fd` (one line), and never returns.
[[noreturn]] void ice_serve(const std::string& host, int report_fd);

// `n` round trips through the proxy `endpoint`: addOne(double) when payload is 0, else echo of
// `payload` bytes. Failed calls are counted in `failed` (and their time not recorded).
std::vector<std::int64_t> ice_calls(const std::string& endpoint, int n, std::size_t payload,
                                    std::uint64_t& failed);

}  // namespace saw::bench
