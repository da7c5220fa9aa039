// Mirror: a component served by a gateway on another host, rebuilt here from its manifest (internal).
#pragma once

#include <deque>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "dds_context.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/query_client.hpp"
#include "saw/task.hpp"

namespace saw::gateway {

// The remote component's mapped interface, as a local component that this host's bridge exports
// under the same name: `connect()` from an RT process here reaches it exactly as a local one.
// Reads are state columns fed by the remote topics; the row is stamped with the newest
// sample's arrival, so a stream that stops ages (a client's stale check sees the remote host
// die). Write and void commands, run in this task's thread, are published to the remote
// gateway; remote events are emitted here; qualified reads, called by the bridge's service
// thread, are requests to the remote gateway (waiting at most `query_timeout`). A continuous
// task of normal priority that waits for samples (at most 1 ms): a row leaves for this host's
// clients as soon as the remote one arrives, not on a polling grid. `local_name` is its name
// here (the remote one by default).
class Mirror : public Task {
 public:
  Mirror(DdsContext& dds, const std::string& component, const std::vector<EndpointInfo>& remote,
         const std::string& local_name = "", TimeNs query_timeout = 100'000'000);
  void run() override;
  const std::string& interface_name() const noexcept { return interface_; }
  std::uint64_t samples() const noexcept { return samples_.load(std::memory_order_relaxed); }

 private:
  struct Stream {
    const Mapping* mapping;
    fdds::DataReader* reader;
    std::unique_ptr<std::byte[]> value;
    EventBase* event = nullptr;  // for events; state columns read `value`
  };
  struct Out {
    const Mapping* mapping;
    fdds::DataWriter* writer;
    std::string frame;
  };
  struct Query {  // QueryClient is one caller at a time; callers here are non-RT threads
    std::mutex lock;
    QueryClient client;
    std::size_t arg_size, result_size;
    TimeNs timeout;
  };
  void watch(fdds::DataReader* r);
  TypeInfo type(const std::string& name, std::uint32_t size, std::uint32_t version);

  DdsContext& dds_;
  std::string interface_;
  std::deque<std::string> type_names_;  // TypeInfo points into these
  std::vector<Stream> states_, events_;
  std::vector<std::unique_ptr<Out>> outs_;
  std::vector<std::unique_ptr<Query>> queries_;
  fdds::WaitSet arrivals_;
  TimeNs arrival_ = 0;
  std::atomic<std::uint64_t> samples_{0};
};

// Splits a --mirror argument: "NAME" (here as there) or "NAME=LOCAL" (here under another name,
// e.g. when a component of that name already runs on this host). Returns {remote, local}.
std::pair<std::string, std::string> split_mirror(const std::string& arg);

// The endpoints of `component` in a manifest of another gateway (not `self`), waiting up to
// `timeout`; throws naming what is missing.
std::vector<EndpointInfo> find_remote(DdsContext& dds, const std::string& component, const std::string& self,
                                      TimeNs timeout);

}  // namespace saw::gateway
