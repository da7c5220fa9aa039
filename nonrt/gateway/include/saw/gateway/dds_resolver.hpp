// DdsResolver: connect() to components served by gateways anywhere on the network (remote clients).
#pragma once

#include <memory>
#include <string>

#include "saw/gateway/participant.hpp"
#include "saw/manager.hpp"

namespace saw::gateway {

class MappingRegistry;

struct OwnedDds;

// For a non-RT program on any machine: `manager.add_resolver(std::make_unique<DdsResolver>())`,
// then the same `connect(client, required, server, provided)` as in the RT process. The server
// is looked up in the registry; the stand-in component it returns reads state from the
// gateway's topics (the newest sample; `no_data` before the first; `disconnected` when no gateway
// serves it or the state is older than `stale_after`), publishes write and void commands
// (`disconnected` when no gateway reads them), calls qualified reads as request/reply (waiting at most
// `query_timeout`), and delivers events into the client's thread. Types are compared at connect by name, size
// and layout version, as for local and shared-memory servers.
class DdsResolver : public RemoteResolver {
 public:
  struct Options {
    ParticipantConfig dds{.name = "saw-client"};
    TimeNs lookup_timeout = 3'000'000'000;  // waiting for the registry to list the server
    TimeNs query_timeout = 1'000'000'000;
    // State older than this reads as `disconnected` (the server's RT process stopped); keep it
    // above the gateway's publishing period (its decimation).
    TimeNs stale_after = 100'000'000;
    // The types it maps; none: the rt core's and the installation's mapping modules, as
    // saw-gateway maps them.
    std::shared_ptr<const MappingRegistry> mappings;
  };
  DdsResolver();
  explicit DdsResolver(Options options);
  ~DdsResolver() override;
  std::unique_ptr<Component> resolve(std::string_view name) override;

 private:
  Options options_;
  std::shared_ptr<OwnedDds> dds_;  // shared with the components it made
};

}  // namespace saw::gateway
