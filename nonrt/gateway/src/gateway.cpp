#include "saw/gateway/gateway.hpp"

#include <unistd.h>

#include "attachment.hpp"
#include "imported_arm.hpp"
#include "mirror.hpp"
#include "saw/bridge/exporter.hpp"
#include "saw/manager.hpp"
#include "saw_msgs/msg/ManifestPubSubTypes.h"

namespace saw::gateway {

namespace {

std::string host_name() {
  char b[256] = {};
  gethostname(b, sizeof b - 1);
  return b;
}

}  // namespace

struct Gateway::Imports {
  std::vector<std::unique_ptr<ImportedArm>> arms;
  std::vector<std::unique_ptr<Mirror>> mirrors;
  std::vector<std::unique_ptr<bridge::Exporter>> exporters;
  Manager manager{ManagerOptions{.lock_memory = false, .hold_dma_latency = false}};
};

struct Gateway::Dds {
  DdsContext context;
  fdds::DataWriter* manifest = nullptr;
};

Gateway::Gateway(GatewayConfig config) : config_(std::move(config)), dds_(std::make_unique<Dds>()) {
  if (config_.name.empty()) config_.name = "gateway." + std::to_string(getpid());
  if (config_.dds.name == ParticipantConfig{}.name) config_.dds.name = config_.name;
  if (config_.mappings == nullptr)
    config_.mappings = std::make_shared<const MappingRegistry>(core_mappings());
  auto& ctx = dds_->context;
  ctx.mappings = config_.mappings.get();
  ctx.participant = make_participant(config_.dds);
  try {
    ctx.publisher = ctx.participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    ctx.subscriber = ctx.participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    fdds::TypeSupport manifest_type(new saw_msgs::msg::ManifestPubSubType());
    manifest_type.register_type(ctx.participant);
    fdds::Topic* topic = ctx.participant->create_topic("rt/saw/manifest", manifest_type.get_type_name(),
                                                       fdds::TOPIC_QOS_DEFAULT);
    ctx.manifest_topic = topic;
    dds_->manifest = ctx.publisher->create_datawriter(topic, DdsContext::writer_qos(Flow::registry));
    if (ctx.publisher == nullptr || ctx.subscriber == nullptr || dds_->manifest == nullptr)
      throw std::runtime_error(
          "DDS: could not create the gateway's publisher, subscriber or manifest writer");
    // Imports and mirrors are presented first: saw-rt starts its tasks (and so makes its exports
    // live, which an attachment waits for) only once they are here. The other order waits in a
    // circle, broken only while the exports' fresh heartbeat still passes (a slow start did not).
    imports_ = std::make_unique<Imports>();
    for (const auto& i : config_.imports) {
      imports_->arms.push_back(std::make_unique<ImportedArm>(ctx, i));
      imports_->exporters.push_back(std::make_unique<bridge::Exporter>(
          *imports_->arms.back(), imports_->arms.back()->interface_name()));
      imports_->manager.add(*imports_->arms.back());
      const auto& e = imports_->arms.back()->endpoints();
      endpoints_.insert(endpoints_.end(), e.begin(), e.end());
    }
    for (const auto& arg : config_.mirrors) {
      const auto [name, local] = split_mirror(arg);
      auto remote = find_remote(ctx, name, config_.name, config_.attach_timeout);
      imports_->mirrors.push_back(std::make_unique<Mirror>(ctx, name, remote, local));
      Mirror& m = *imports_->mirrors.back();
      imports_->exporters.push_back(std::make_unique<bridge::Exporter>(m, m.interface_name()));
      imports_->manager.add(m);
      for (auto& e : remote) {
        e.kind = "mirror";  // served here through the bridge; the topics are the remote gateway's
        e.component = local;
        endpoints_.push_back(std::move(e));
      }
    }
    if (!config_.imports.empty() || !config_.mirrors.empty()) imports_->manager.start();
    std::vector<EndpointInfo> attached;
    for (const auto& name : config_.attach) {
      attachments_.push_back(std::make_unique<Attachment>(ctx, name, config_.decimation, config_.display_rate,
                                                          config_.attach_timeout,
                                                          [this] { publish_manifest(); }));
      const auto& e = attachments_.back()->endpoints();
      attached.insert(attached.end(), e.begin(), e.end());
    }
    endpoints_.insert(endpoints_.begin(), attached.begin(), attached.end());  // the manifest's order
  } catch (...) {
    attachments_.clear();
    if (imports_ != nullptr) imports_->manager.stop();  // started before an attachment failed
    imports_.reset();
    delete_participant(ctx.participant);
    throw;
  }
  publish_manifest();
  for (auto& a : attachments_) a->start();
}

Gateway::~Gateway() {
  // Every thread joined before any attachment goes (a running one's liveness change publishes
  // the manifest, which reads them all), and before the DDS entities go.
  for (auto& a : attachments_) a->stop();
  attachments_.clear();
  if (imports_ != nullptr) {
    imports_->manager.stop();
    // An arm the client (saw-rt) was moving gets its safe command from here, whatever ended the
    // client: the dVRK keeps a last wrench or goal for ever (docs/devices.md).
    const TimeNs deadline = monotonic_now() + 300'000'000;
    for (auto& a : imports_->arms) a->leave_safely(deadline);
  }
  imports_.reset();
  delete_participant(dds_->context.participant);
}

void Gateway::announce_exit(const std::string& why, TimeNs wait) {
  for (auto& a : attachments_) a->publish_fault(why);
  const TimeNs deadline = monotonic_now() + wait;
  for (auto& a : attachments_) a->wait_for_acknowledgments(deadline);
}

GatewayStats Gateway::stats() const {
  GatewayStats s;
  for (const auto& a : attachments_) a->add_stats(s);
  if (imports_ != nullptr)
    for (const auto& a : imports_->arms) {
      s.imported += a->samples();
      s.imported_rejected += a->rejected();
      s.imported_bad_stamps += a->invalid_stamps() + a->repeated_stamps();
      s.arm_commands += a->commands_sent();
      s.arm_safe_commands += a->safe_commands();
    }
  if (imports_ != nullptr)
    for (const auto& m : imports_->mirrors) s.mirrored += m->samples();
  return s;
}

void Gateway::publish_manifest() {
  std::lock_guard lock(manifest_mutex_);
  saw_msgs::msg::Manifest m;
  const auto wall = wall_from_monotonic(monotonic_now());
  m.header().stamp().sec(static_cast<std::int32_t>(wall / 1'000'000'000));
  m.header().stamp().nanosec(static_cast<std::uint32_t>(wall % 1'000'000'000));
  m.header().frame_id(config_.name);
  m.host(host_name());
  m.pid(static_cast<std::int32_t>(getpid()));
  m.gateway(config_.name);
  bool all_alive = true;
  for (const auto& a : attachments_) all_alive = all_alive && a->alive();
  m.state(all_alive ? "ENABLED" : "FAULT");
  for (const auto& e : endpoints_) {
    saw_msgs::msg::Endpoint out;
    out.component_name(e.component);
    out.interface_name(e.interface_name);
    out.name(e.name);
    out.kind(e.kind);
    out.saw_type(e.saw_type);
    out.saw_size(e.saw_size);
    out.saw_version(e.saw_version);
    out.result_type(e.result_type);
    out.result_size(e.result_size);
    out.result_version(e.result_version);
    out.limited(e.limited);
    out.limit_min(e.limit_min);
    out.limit_max(e.limit_max);
    out.latched(e.latched);
    out.dds_type(e.dds_type);
    out.topic(e.topic);
    out.display_topic(e.display_topic);
    out.display_rate(e.display_rate);
    m.endpoints().push_back(std::move(out));
  }
  dds_->manifest->write(&m);
}

}  // namespace saw::gateway
