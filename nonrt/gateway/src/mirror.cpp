#include "mirror.hpp"

#include <cmath>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <thread>

#include "saw/crtk.hpp"
#include "saw/detail/access.hpp"
#include "saw_msgs/msg/ManifestPubSubTypes.h"

namespace saw::gateway {

TypeInfo Mirror::type(const std::string& name, std::uint32_t size, std::uint32_t version) {
  if (size == 0) return {};
  type_names_.push_back(name);
  return {type_names_.back(), size, version};
}

void Mirror::watch(fdds::DataReader* r) {
  r->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
  arrivals_.attach_condition(r->get_statuscondition());
}

std::pair<std::string, std::string> split_mirror(const std::string& arg) {
  const auto eq = arg.find('=');
  if (eq == std::string::npos) return {arg, arg};
  return {arg.substr(0, eq), arg.substr(eq + 1)};
}

Mirror::Mirror(DdsContext& dds, const std::string& component, const std::vector<EndpointInfo>& remote,
               const std::string& local_name, TimeNs query_timeout)
    : Task(local_name.empty() ? component : local_name, TaskConfig::continuous()), dds_(dds) {
  if (remote.empty()) throw std::runtime_error("mirror " + component + ": the remote manifest lists nothing");
  interface_ = remote.front().interface_name;
  auto& p = provide(interface_);
  for (const auto& e : remote) {
    if (e.interface_name != interface_ || e.topic.empty())
      continue;  // one interface per segment; mapped only
    if (e.kind == "qualified_read") {
      queries_.push_back(std::unique_ptr<Query>(new Query{
          {}, QueryClient(dds_.participant, component, e.name), e.saw_size, e.result_size, query_timeout}));
      Command c;
      c.name = e.name;
      c.signature = {CommandKind::qualified_read, type(e.saw_type, e.saw_size, e.saw_version),
                     type(e.result_type, e.result_size, e.result_version)};
      c.read = [q = queries_.back().get()](const void* arg, void* out) {
        std::lock_guard lock(q->lock);
        return q->client.call(arg, q->arg_size, out, q->result_size, q->timeout);
      };
      detail::Access::add_command(p, std::move(c));
      continue;
    }
    const Mapping* m = dds_.mapping_by_dds(e.dds_type);
    if (m == nullptr || (e.saw_size != 0 && m->size() != e.saw_size)) continue;
    const TypeInfo t = type(e.saw_type, e.saw_size, e.saw_version);
    if (e.kind == "read") {
      // An operating state and a description are published on change only (latched): a mirror that joins
      // later takes the last one the writer keeps, or it would show the default (DISABLED) until the next
      // change.
      const bool latched = e.latched;
      auto* r = dds_.subscriber->create_datareader(
          dds_.topic(e.topic, *m), DdsContext::reader_qos(latched ? Flow::latched : Flow::state));
      states_.push_back({m, r, std::make_unique<std::byte[]>(m->size())});
      watch(r);
      // The remote task's period_statistics: this mirror task has a column of that name already
      // (its own statistics, on its `task` interface).
      const std::string column_name = e.name == "period_statistics" ? "remote_period_statistics" : e.name;
      const auto column = state_table().add_column_erased(column_name, t, states_.back().value.get());
      Command c;
      c.name = e.name;
      c.signature = {CommandKind::read, t};
      c.table = &state_table();
      c.column = column;
      c.read = [table = &state_table(), column](const void*, void* out) {
        return table->read_latest_erased(column, out, nullptr);
      };
      detail::Access::add_command(p, std::move(c));
    } else if (e.kind == "write_event" || e.kind == "void_event") {
      auto* r =
          dds_.subscriber->create_datareader(dds_.topic(e.topic, *m), DdsContext::reader_qos(Flow::event));
      EventBase& ev = detail::Access::add_event_remote(
          p, e.name, {e.kind == "write_event" ? CommandKind::write_event : CommandKind::void_event, t});
      events_.push_back({m, r, std::make_unique<std::byte[]>(std::max<std::size_t>(m->size(), 1)), &ev});
      watch(r);
    } else if (e.kind == "write" || e.kind == "void") {
      auto* w =
          dds_.publisher->create_datawriter(dds_.topic(e.topic, *m), DdsContext::writer_qos(Flow::command));
      outs_.push_back(std::make_unique<Out>(Out{m, w, component}));
      Command c;
      c.name = e.name;
      c.signature = {e.kind == "write" ? CommandKind::write : CommandKind::void_command, t};
      c.execute = [o = outs_.back().get()](const void* arg) {
        o->mapping->write(*o->writer, arg, wall_from_monotonic(monotonic_now()), o->frame);
      };
      // The remote component's bounds, declared here too: this host's clients are refused at
      // the call, not by the remote gateway a network away.
      if (e.limited && std::isfinite(e.limit_min) && std::isfinite(e.limit_max) && e.limit_min <= e.limit_max)
        c.limits = Limits{e.limit_min, e.limit_max};
      detail::Access::add_command(p, std::move(c));
    }
  }
}

void Mirror::run() {
  fdds::ConditionSeq active;
  (void)arrivals_.wait(active, eprosima::fastrtps::Duration_t(0, 1'000'000));
  std::string why;
  for (auto& s : states_) {
    bool got = false;
    for (auto t = s.mapping->take(*s.reader, s.value.get(), why); t != Mapping::Take::none;
         t = s.mapping->take(*s.reader, s.value.get(), why))
      got = got || t == Mapping::Take::ok;
    if (got) {
      arrival_ = now();
      samples_.fetch_add(1, std::memory_order_relaxed);
    }
  }
  for (auto& e : events_)
    for (auto t = e.mapping->take(*e.reader, e.value.get(), why); t != Mapping::Take::none;
         t = e.mapping->take(*e.reader, e.value.get(), why))
      if (t == Mapping::Take::ok) (void)detail::Access::emit_described(*e.event, e.value.get());
  stamp_row(arrival_);
}

std::vector<EndpointInfo> find_remote(DdsContext& dds, const std::string& component, const std::string& self,
                                      TimeNs timeout) {
  auto* reader =
      dds.subscriber->create_datareader(dds.manifest_topic, DdsContext::reader_qos(Flow::registry));
  const TimeNs deadline = monotonic_now() + timeout;
  std::vector<EndpointInfo> found;
  while (found.empty()) {
    saw_msgs::msg::Manifest m;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || m.gateway() == self || m.state() != "ENABLED") continue;
      std::vector<EndpointInfo> mine;
      for (const auto& e : m.endpoints())
        if (e.component_name() == component && !e.topic().empty() && e.kind() != "import" &&
            e.kind() != "import_command" && e.kind() != "mirror")
          mine.push_back({e.component_name(), e.interface_name(), e.name(), e.kind(), e.saw_type(),
                          e.saw_size(), e.saw_version(), e.dds_type(), e.topic(), e.result_type(),
                          e.result_size(), e.result_version(), e.limited(), e.limit_min(), e.limit_max(),
                          e.latched(), e.display_topic(), e.display_rate()});
      if (!mine.empty()) found = std::move(mine);
    }
    if (!found.empty()) break;
    if (monotonic_now() >= deadline) {
      dds.subscriber->delete_datareader(reader);
      throw std::runtime_error("mirror " + component + ": no other gateway serves it (waited " +
                               std::to_string(timeout / 1'000'000) + " ms)");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  dds.subscriber->delete_datareader(reader);
  return found;
}

}  // namespace saw::gateway
