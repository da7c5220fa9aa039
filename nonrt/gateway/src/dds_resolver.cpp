#include "saw/gateway/dds_resolver.hpp"

#include "dds_component.hpp"
#include "mirror.hpp"
#include "saw_msgs/msg/ManifestPubSubTypes.h"

namespace saw::gateway {

DdsResolver::DdsResolver() : DdsResolver(Options{}) {}

DdsResolver::DdsResolver(Options options) : options_(std::move(options)) {
  if (options_.mappings == nullptr) {
    auto mappings = std::make_shared<MappingRegistry>(core_mappings());
    load_mapping_modules(*mappings);
    options_.mappings = std::move(mappings);
  }
  auto owned = std::make_shared<OwnedDds>();
  auto& ctx = owned->ctx;
  owned->mappings = options_.mappings;
  ctx.mappings = owned->mappings.get();
  ctx.participant = make_participant(options_.dds);
  ctx.publisher = ctx.participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  ctx.subscriber = ctx.participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  fdds::TypeSupport t(new saw_msgs::msg::ManifestPubSubType());
  t.register_type(ctx.participant);
  ctx.manifest_topic =
      ctx.participant->create_topic("rt/saw/manifest", t.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  if (ctx.publisher == nullptr || ctx.subscriber == nullptr || ctx.manifest_topic == nullptr)
    throw std::runtime_error("DDS resolver: could not create its publisher, subscriber or registry topic");
  dds_ = std::move(owned);
}

DdsResolver::~DdsResolver() = default;

std::unique_ptr<Component> DdsResolver::resolve(std::string_view name) {
  std::vector<EndpointInfo> remote;
  try {
    remote = find_remote(dds_->ctx, std::string(name), "", options_.lookup_timeout);
  } catch (const std::runtime_error&) {
    return nullptr;  // no gateway serves it: not ours to resolve
  }
  return std::make_unique<DdsComponent>(dds_, std::string(name), remote, options_.query_timeout,
                                        options_.stale_after);
}

}  // namespace saw::gateway
