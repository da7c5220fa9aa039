// DdsComponent: a stand-in for a component served by a gateway, built from the registry (internal).
#pragma once

#include <deque>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <memory>
#include <thread>
#include <vector>

#include "dds_context.hpp"
#include "saw/component.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/query_client.hpp"

namespace saw::gateway {

// A DdsContext whose participant goes with the last component (or resolver) that uses it.
struct OwnedDds {
  // The registry ctx.mappings points into: a component's event thread takes through its mappings
  // until the component is gone, which may be after its resolver.
  std::shared_ptr<const MappingRegistry> mappings;
  DdsContext ctx;
  ~OwnedDds();
};

class DdsComponent : public Component {
 public:
  DdsComponent(std::shared_ptr<OwnedDds> dds, const std::string& name,
               const std::vector<EndpointInfo>& remote, TimeNs query_timeout, TimeNs stale_after);
  ~DdsComponent() override;

  bool is_remote() const noexcept override { return true; }

 private:
  detail::Mailbox* remote_events() noexcept override { return events_.get(); }

  struct State {
    const Mapping* mapping;
    fdds::DataReader* reader;
    std::unique_ptr<std::byte[]> value;
    bool valid = false;
    TimeNs arrival = 0;
  };
  struct Out {
    const Mapping* mapping;
    fdds::DataWriter* writer;
    std::string frame;
  };
  struct EventIn {
    const Mapping* mapping;
    fdds::DataReader* reader;
    std::uint32_t ordinal;
  };
  TypeInfo type(const std::string& name, std::uint32_t size, std::uint32_t version);
  void deliver_events();

  std::shared_ptr<OwnedDds> dds_;
  std::deque<std::string> type_names_;
  std::vector<std::unique_ptr<State>> states_;
  std::vector<std::unique_ptr<Out>> outs_;
  std::vector<std::unique_ptr<QueryClient>> queries_;
  std::vector<EventIn> event_ins_;
  std::unique_ptr<detail::Mailbox> events_;
  fdds::GuardCondition stop_;
  std::thread thread_;
};

}  // namespace saw::gateway
