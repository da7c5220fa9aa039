#include "dds_component.hpp"

#include <cstring>
#include <fastdds/dds/core/condition/WaitSet.hpp>

#include "saw/detail/access.hpp"

namespace saw::gateway {

OwnedDds::~OwnedDds() { delete_participant(ctx.participant); }

TypeInfo DdsComponent::type(const std::string& name, std::uint32_t size, std::uint32_t version) {
  if (size == 0) return {};
  type_names_.push_back(name);
  return {type_names_.back(), size, version};
}

DdsComponent::DdsComponent(std::shared_ptr<OwnedDds> dds, const std::string& name,
                           const std::vector<EndpointInfo>& remote, TimeNs query_timeout, TimeNs stale_after)
    : Component(name), dds_(std::move(dds)) {
  auto& ctx = dds_->ctx;
  auto& p = provide(remote.front().interface_name);
  std::size_t max_event = 8;
  for (const auto& e : remote)
    if (e.kind.ends_with("event")) max_event = std::max<std::size_t>(max_event, e.saw_size);
  events_ = std::make_unique<detail::Mailbox>(name + " events (DDS)", 64, max_event);
  for (const auto& e : remote) {
    if (e.interface_name != p.name() || e.topic.empty()) continue;
    const TypeInfo t = type(e.saw_type, e.saw_size, e.saw_version);
    if (e.kind == "qualified_read") {
      queries_.push_back(std::make_unique<QueryClient>(ctx.participant, name, e.name));
      Command c;
      c.name = e.name;
      c.signature = {CommandKind::qualified_read, t, type(e.result_type, e.result_size, e.result_version)};
      c.read = [q = queries_.back().get(), as = e.saw_size, rs = e.result_size, query_timeout](
                   const void* a, void* r) { return q->call(a, as, r, rs, query_timeout); };
      detail::Access::add_command(p, std::move(c));
      continue;
    }
    const Mapping* m = ctx.mapping_by_dds(e.dds_type);
    if (m == nullptr || (e.saw_size != 0 && m->size() != e.saw_size)) continue;  // not decodable here
    if (e.kind == "read") {
      auto* r = ctx.subscriber->create_datareader(
          ctx.topic(e.topic, *m), DdsContext::reader_qos(e.latched ? Flow::latched : Flow::state));
      states_.push_back(std::make_unique<State>(State{m, r, std::make_unique<std::byte[]>(m->size())}));
      Command c;
      c.name = e.name;
      c.signature = {CommandKind::read, t};
      // The newest sample, stamped with its arrival (this process's monotonic clock).
      // A gateway gone (no writer matched) or a server silent for `stale_after` (its RT process
      // died: the gateway publishes FAULT and stops the state): disconnected, as over the bridge.
      auto& stamped = detail::Access::read_stamped(c);
      stamped = [s = states_.back().get(), stale_after](void* out, RowStamp& stamp) {
        std::string why;
        for (auto k = s->mapping->take(*s->reader, s->value.get(), why); k != Mapping::Take::none;
             k = s->mapping->take(*s->reader, s->value.get(), why))
          if (k == Mapping::Take::ok) {
            s->valid = true;
            s->arrival = monotonic_now();
          }
        fdds::SubscriptionMatchedStatus matched;
        s->reader->get_subscription_matched_status(matched);
        if (matched.current_count == 0) return Status::disconnected;
        if (!s->valid) return Status::no_data;
        if (monotonic_now() - s->arrival > stale_after) return Status::disconnected;
        std::memcpy(out, s->value.get(), s->mapping->size());
        stamp.time = s->arrival;
        stamp.tick = 0;
        return Status::ok;
      };
      c.read = [f = stamped](const void*, void* out) {
        RowStamp ignored;
        return f(out, ignored);
      };
      detail::Access::add_command(p, std::move(c));
    } else if (e.kind == "write" || e.kind == "void") {
      auto* w =
          ctx.publisher->create_datawriter(ctx.topic(e.topic, *m), DdsContext::writer_qos(Flow::command));
      outs_.push_back(std::make_unique<Out>(Out{m, w, "saw-client"}));
      Command c;
      c.name = e.name;
      c.signature = {e.kind == "write" ? CommandKind::write : CommandKind::void_command, t};
      c.execute = [](const void*) {};  // never used: forward takes the call
      detail::Access::forward(c) = [o = outs_.back().get()](const void* arg) {
        fdds::PublicationMatchedStatus matched;  // no gateway reads it: it would go nowhere
        o->writer->get_publication_matched_status(matched);
        if (matched.current_count == 0) return Status::disconnected;
        return o->mapping->write(*o->writer, arg, wall_from_monotonic(monotonic_now()), o->frame)
                   ? Status::ok
                   : Status::disconnected;
      };
      detail::Access::add_command(p, std::move(c));
    } else if (e.kind.ends_with("event")) {
      auto* r =
          ctx.subscriber->create_datareader(ctx.topic(e.topic, *m), DdsContext::reader_qos(Flow::event));
      detail::Access::add_event_remote(
          p, e.name, {e.kind == "write_event" ? CommandKind::write_event : CommandKind::void_event, t});
      const auto ordinal = static_cast<std::uint32_t>(p.events().size() - 1);
      events_->set_target(ordinal, detail::Invoker{[](void*, const void*) {}, nullptr});
      event_ins_.push_back({m, r, ordinal});
    }
  }
  if (!event_ins_.empty()) thread_ = std::thread([this] { deliver_events(); });
}

DdsComponent::~DdsComponent() {
  stop_.set_trigger_value(true);
  if (thread_.joinable()) thread_.join();
}

// The event mailbox's one producer: takes events as they arrive and queues them for the
// client's thread, as the bridge's event ring does.
void DdsComponent::deliver_events() {
  fdds::WaitSet waitset;
  waitset.attach_condition(stop_);
  for (auto& e : event_ins_) {
    e.reader->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    waitset.attach_condition(e.reader->get_statuscondition());
  }
  alignas(16) std::byte value[512];
  std::string why;
  while (!stop_.get_trigger_value()) {
    for (auto& e : event_ins_)
      for (auto k = e.mapping->take(*e.reader, value, why); k != Mapping::Take::none;
           k = e.mapping->take(*e.reader, value, why))
        if (k == Mapping::Take::ok) (void)events_->push(e.ordinal, value, e.mapping->size());
    fdds::ConditionSeq active;
    waitset.wait(active, eprosima::fastrtps::Duration_t(0, 100'000'000));
  }
  for (auto& e : event_ins_) waitset.detach_condition(e.reader->get_statuscondition());
  waitset.detach_condition(stop_);
}

}  // namespace saw::gateway
