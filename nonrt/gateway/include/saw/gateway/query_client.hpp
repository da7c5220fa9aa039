// QueryClient: calls one qualified read of a component served by a gateway, over DDS.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "saw/clock.hpp"
#include "saw/status.hpp"

namespace eprosima::fastdds::dds {
class DomainParticipant;
}

namespace saw::gateway {

// Request on rq/<component>/<command>Request, reply on rr/<component>/<command>Reply (the ROS 2
// service naming); replies are matched by this client's id and the call's sequence number. One
// call at a time, from one thread. Portable: Fast DDS only.
class QueryClient {
 public:
  QueryClient(eprosima::fastdds::dds::DomainParticipant* participant, const std::string& component,
              const std::string& command);
  ~QueryClient();
  QueryClient(const QueryClient&) = delete;
  QueryClient& operator=(const QueryClient&) = delete;

  // Waits until the server's reader and writer have matched ours (discovery), at most `timeout`.
  bool wait_matched(TimeNs timeout);
  // Sends `arg` (arg_size bytes), waits for the reply (result_size bytes into `result`).
  // timeout: no reply in time; invalid: the reply's size differs; else the server's status.
  Status call(const void* arg, std::size_t arg_size, void* result, std::size_t result_size, TimeNs timeout);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace saw::gateway
