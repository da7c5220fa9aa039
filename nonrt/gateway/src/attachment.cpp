#include "attachment.hpp"

#include <fastcdr/exceptions/Exception.h>

#include <chrono>
#include <cstring>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <thread>

#include "crtk_msgs/msg/OperatingState.h"
#include "crtk_msgs/msg/StringStamped.h"
#include "saw/crtk.hpp"
#include "saw/description.hpp"
#include "saw/detail/access.hpp"
#include "saw/fault.hpp"
#include "saw/task.hpp"
#include "saw_msgs/msg/QueryPubSubTypes.h"
#include "saw_msgs/msg/QueryReplyPubSubTypes.h"

namespace saw::gateway {

namespace {

// The gateway sees a dead RT process sooner than RT clients do (100 ms): it must publish FAULT
// within 100 ms of the death, and it sleeps at most `poll` between checks.
constexpr bridge::ProxyOptions proxy_options{.stale_after = 50'000'000};
constexpr TimeNs poll = 10'000'000;

std::string kind_name(CommandKind k) {
  switch (k) {
    case CommandKind::void_command:
      return "void";
    case CommandKind::write:
      return "write";
    case CommandKind::read:
      return "read";
    case CommandKind::qualified_read:
      return "qualified_read";
    case CommandKind::void_event:
      return "void_event";
    case CommandKind::write_event:
      return "write_event";
  }
  return "?";
}

EndpointInfo describe(const std::string& component, const std::string& interface, const std::string& name,
                      const Signature& sig) {
  EndpointInfo e;
  e.component = component;
  e.interface_name = interface;
  e.name = name;
  e.kind = kind_name(sig.kind);
  e.saw_type = sig.arg.name;
  e.saw_size = static_cast<std::uint32_t>(sig.arg.size);
  e.saw_version = sig.arg.version;
  e.result_type = sig.result.name;
  e.result_size = static_cast<std::uint32_t>(sig.result.size);
  e.result_version = sig.result.version;
  return e;
}

std::unique_ptr<Component> resolve(const std::string& name, TimeNs timeout) {
  const TimeNs deadline = monotonic_now() + timeout;
  std::string why =
      "no shared-memory segment /saw." + name + " (is the RT process running and exporting it?)";
  for (;;) {
    try {
      if (auto c = bridge::ShmResolver(proxy_options).resolve(name)) return c;
    } catch (const ConnectError& e) {
      why = e.what();
    }
    if (monotonic_now() >= deadline) throw std::runtime_error("attach " + name + ": " + why);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

}  // namespace

Attachment::Attachment(DdsContext& dds, const std::string& component, unsigned decimation,
                       double display_rate, TimeNs timeout, std::function<void()> liveness_changed)
    : dds_(dds),
      name_(component),
      decimation_(decimation == 0 ? 1 : decimation),
      display_period_(display_rate > 0 ? static_cast<TimeNs>(1e9 / display_rate) : 0),
      liveness_changed_(std::move(liveness_changed)),
      component_(resolve(component, timeout)),
      proxy_(dynamic_cast<bridge::Proxy*>(component_.get())) {
  if (proxy_ == nullptr) throw std::runtime_error("attach " + component + ": not a bridge proxy");
  const ProvidedInterface& p = *component_->provided_interfaces().front();
  const std::string prefix = "rt/" + name_ + "/";
  const Mapping* string_stamped = dds_.mapping(type_info_of<StateCommand>().name);
  error_writer_ = dds_.publisher->create_datawriter(dds_.topic(prefix + "error", *string_stamped),
                                                    DdsContext::writer_qos(Flow::log));
  const Mapping* operating_state = dds_.mapping(type_info_of<OperatingState>().name);
  for (const auto& e : p.events()) {
    const Signature& sig = e->signature();
    const Mapping* m = sig.arg.size == 0 ? &empty_mapping() : dds_.mapping(sig.arg.name);
    EndpointInfo info = describe(name_, p.name(), e->name(), sig);
    auto out = std::make_unique<EventOut>(EventOut{this, m, nullptr});
    if (m != nullptr) {
      info.dds_type = m->dds_type();
      info.topic = prefix + e->name();
      const bool latched = m == operating_state;
      info.latched = latched;
      out->writer = dds_.publisher->create_datawriter(
          dds_.topic(info.topic, *m), DdsContext::writer_qos(latched ? Flow::latched : Flow::event));
      if (latched) {
        fault_writer_ = out->writer;
        // Its read of the same name gives the state at attach time: a late joiner sees it at
        // once, not only after the next change.
        if (const Command* now = p.find_command(e->name());
            now != nullptr && now->signature.kind == CommandKind::read)
          initial_states_.push_back({now, m, out->writer, std::vector<std::byte>(m->size())});
      }
      // CRTK clients watch `error` for why an arm faulted; the fault event says it.
      out->fault_text = m == dds_.mapping(type_info_of<FaultInfo>().name);
    }
    // Numbered by ordinal among the interface's events, as the proxy's mailbox numbers them.
    detail::Access::remote_events(*proxy_)->set_target(
        static_cast<std::uint32_t>(events_.size()),
        detail::Invoker{[](void* self, const void* arg) {
                          auto* o = static_cast<EventOut*>(self);
                          if (o->writer == nullptr) return;
                          o->mapping->write(*o->writer, arg, wall_from_monotonic(monotonic_now()),
                                            o->self->name_);
                          o->self->event_count_.fetch_add(1, std::memory_order_relaxed);
                          // A FaultInfo of code none clears the fault (the component was
                          // enabled again): said as such, not as a FAULT.
                          if (o->fault_text)
                            o->self->publish_error(static_cast<const FaultInfo*>(arg)->code == FaultCode::none
                                                       ? "fault cleared"
                                                       : "FAULT: " + o->mapping->to_text(arg));
                        },
                        out.get()});
    events_.push_back(std::move(out));
    endpoints_.push_back(std::move(info));
  }
  detail::Access::remote_events(*proxy_)->set_consumer_attached();
  block_.resize(proxy_->mirror_bytes());
  for (const auto& c : p.commands()) {
    const Signature& sig = c->signature;
    EndpointInfo info = describe(name_, p.name(), c->name, sig);
    if (c->limits) {
      info.limited = true;
      info.limit_min = c->limits->min;
      info.limit_max = c->limits->max;
    }
    if (sig.kind == CommandKind::qualified_read) {
      if (query_component_ == nullptr) query_component_ = resolve(component, timeout);
      const Command* q = query_component_->provided_interfaces().front()->find_command(c->name);
      info.dds_type = "saw_msgs::msg::dds_::Query_";
      info.topic = "rq/" + name_ + "/" + c->name + "Request";
      fdds::TypeSupport rq(new saw_msgs::msg::QueryPubSubType()),
          rr(new saw_msgs::msg::QueryReplyPubSubType());
      rq.register_type(dds_.participant);
      rr.register_type(dds_.participant);
      auto* req_topic =
          dds_.participant->create_topic(info.topic, rq.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
      auto* rep_topic = dds_.participant->create_topic("rr/" + name_ + "/" + c->name + "Reply",
                                                       rr.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
      if (q == nullptr || req_topic == nullptr || rep_topic == nullptr)
        throw std::runtime_error("attach " + name_ + ": could not map the qualified read " + c->name);
      queries_.push_back(
          {q, dds_.subscriber->create_datareader(req_topic, DdsContext::reader_qos(Flow::command)),
           dds_.publisher->create_datawriter(rep_topic, DdsContext::writer_qos(Flow::command)), sig.arg.size,
           sig.result.size});
      endpoints_.push_back(std::move(info));
      continue;
    }
    const Mapping* m = sig.arg.size == 0 ? &empty_mapping() : dds_.mapping(sig.arg.name);
    if (m != nullptr) {
      info.dds_type = m->dds_type();
      info.topic = prefix + c->name;
      if (sig.kind == CommandKind::read) {
        // A read and an event of the same name share the topic: the event (on change, reliable) serves it.
        const bool event_too = std::any_of(p.events().begin(), p.events().end(),
                                           [&](const auto& e) { return e->name() == c->name; });
        // An operating state, a description and a setting's read-back (`X` beside `set_X`, of the
        // same type) are latched and published on change: a late joiner gets them at once, and a
        // value that changes when someone sets it costs no sample every row.
        const Command* set = p.find_command("set_" + c->name);
        const bool read_back = set != nullptr && set->signature.kind == CommandKind::write &&
                               set->signature.arg.name == sig.arg.name;
        info.latched = event_too ? m == operating_state : gateway::latched(m) || read_back;
        if (!event_too) {
          const bool latched = info.latched;
          auto* w = dds_.publisher->create_datawriter(
              dds_.topic(info.topic, *m), DdsContext::writer_qos(latched ? Flow::latched : Flow::state));
          (latched ? changed_states_ : states_).push_back({c.get(), m, w, std::vector<std::byte>(m->size())});
          if (!latched && !proxy_->read_slice(c->name, states_.back().offset, states_.back().size))
            throw std::runtime_error("attach " + name_ + ": " + c->name +
                                     " is not in the bridge's state rows");
          // A task's statistics are cumulative: a tenth of the rows tells a GUI as much, for a
          // tenth of the samples every subscriber takes.
          if (!latched && m == dds_.mapping(type_info_of<TaskStatistics>().name)) states_.back().every = 10;
          // What a live view draws: the same values at the display rate, on a topic of their own,
          // so that a GUI's reader is not sent (and does not decode) a thousand rows a second.
          if (!latched && display_period_ > 0) {
            info.display_topic = info.topic + "/display";
            info.display_rate = display_rate;
            states_.back().display = dds_.publisher->create_datawriter(dds_.topic(info.display_topic, *m),
                                                                       DdsContext::writer_qos(Flow::state));
          }
          if (m == operating_state && fault_writer_ == nullptr) fault_writer_ = w;
        }
      } else {
        auto* r = dds_.subscriber->create_datareader(dds_.topic(info.topic, *m),
                                                     DdsContext::reader_qos(Flow::command));
        commands_.push_back({c.get(), m, r, std::vector<std::byte>(std::max<std::size_t>(m->size(), 1))});
      }
    }
    endpoints_.push_back(std::move(info));
  }
}

Attachment::~Attachment() { stop(); }

void Attachment::stop() {
  stop_.store(true, std::memory_order_release);
  if (query_stop_ != nullptr) query_stop_->set_trigger_value(true);
  if (query_thread_.joinable()) query_thread_.join();
  if (thread_.joinable()) thread_.join();
}

void Attachment::start() {
  thread_ = std::thread([this] { run(); });
  if (!queries_.empty()) {
    query_stop_ = std::make_unique<fdds::GuardCondition>();
    query_thread_ = std::thread([this] { serve_queries(); });
  }
}

void Attachment::serve_queries() {
  fdds::WaitSet waitset;
  waitset.attach_condition(*query_stop_);
  for (auto& q : queries_) {
    q.requests->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    waitset.attach_condition(q.requests->get_statuscondition());
  }
  saw_msgs::msg::Query request;
  saw_msgs::msg::QueryReply reply;
  fdds::SampleInfo info;
  alignas(16) std::byte arg[256], result[256];
  while (!stop_.load(std::memory_order_acquire)) {
    for (auto& q : queries_) {
      for (;;) {
        try {  // a request Fast CDR cannot read throws from take_next_sample: dropped, not fatal
          if (q.requests->take_next_sample(&request, &info) != ReturnCode_t::RETCODE_OK) break;
        } catch (const eprosima::fastcdr::exception::Exception&) {
          rejected_.fetch_add(1, std::memory_order_relaxed);
          continue;
        }
        if (!info.valid_data) continue;
        reply.client(request.client());
        reply.number(request.number());
        Status st = Status::invalid;  // a qualifier of the wrong size never reaches the bridge
        if (request.data().size() == q.arg_size) {
          std::memcpy(arg, request.data().data(), q.arg_size);
          st = q.command->read(arg, result);
        }
        reply.status(static_cast<std::int32_t>(st));
        const auto* bytes = reinterpret_cast<const std::uint8_t*>(result);
        reply.data().assign(bytes, bytes + (st == Status::ok ? q.result_size : 0));
        q.replies->write(&reply);
        queries_served_.fetch_add(1, std::memory_order_relaxed);
      }
    }
    fdds::ConditionSeq active;
    waitset.wait(active, eprosima::fastrtps::Duration_t(0, 100'000'000));
  }
  for (auto& q : queries_) waitset.detach_condition(q.requests->get_statuscondition());
  waitset.detach_condition(*query_stop_);
}

void Attachment::add_stats(GatewayStats& s) const {
  s.published += published_.load(std::memory_order_relaxed);
  s.displayed += displayed_.load(std::memory_order_relaxed);
  s.rows_skipped += rows_skipped_.load(std::memory_order_relaxed);
  s.events += event_count_.load(std::memory_order_relaxed);
  s.commands += commands_in_.load(std::memory_order_relaxed);
  s.rejected += rejected_.load(std::memory_order_relaxed);
  s.reconnects += proxy_->reconnects();
  s.queries += queries_served_.load(std::memory_order_relaxed);
}

void Attachment::reject(const std::string& command, const std::string& why) {
  rejected_.fetch_add(1, std::memory_order_relaxed);
  publish_error(command + " rejected: " + why);
}

void Attachment::publish_error(const std::string& text) {
  crtk_msgs::msg::StringStamped m;
  const auto wall = wall_from_monotonic(monotonic_now());
  m.header().stamp().sec(static_cast<std::int32_t>(wall / 1'000'000'000));
  m.header().stamp().nanosec(static_cast<std::uint32_t>(wall % 1'000'000'000));
  m.header().frame_id(name_);
  m.string(text);
  if (error_writer_ != nullptr) error_writer_->write(&m);
}

void Attachment::publish_fault(const std::string& why) {
  publish_error("FAULT: " + why);
  if (fault_writer_ == nullptr) return;
  const OperatingState fault{OperatingStateValue::fault, false, false};
  dds_.mapping(type_info_of<OperatingState>().name)
      ->write(*fault_writer_, &fault, wall_from_monotonic(monotonic_now()), name_);
}

void Attachment::wait_for_acknowledgments(TimeNs deadline) {
  for (fdds::DataWriter* w : {error_writer_, fault_writer_}) {
    const TimeNs left = std::max<TimeNs>(deadline - monotonic_now(), 0);
    if (w != nullptr)
      w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
          static_cast<std::int32_t>(left / 1'000'000'000), static_cast<std::uint32_t>(left % 1'000'000'000)));
  }
}

bool Attachment::within_limits(CommandIn& c, std::string& why) {
  if (!c.command->limits) return true;
  return gateway::within_limits(*c.mapping, c.value.data(), *c.command->limits, why);
}

bool Attachment::publish_state(StateOut& s, bool only_if_changed) {
  RowStamp stamp;
  if (only_if_changed) s.previous = s.value;
  if (detail::Access::read_stamped(*s.command)(s.value.data(), stamp) != Status::ok) return false;
  if (only_if_changed && s.value == s.previous) return false;
  if (!s.mapping->write(*s.writer, s.value.data(), wall_from_monotonic(stamp.time), name_)) return false;
  published_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void Attachment::publish_rows() {
  const std::uint64_t written = proxy_->rows_written();
  if (written == 0) return;
  // From the newest row at attach, and again at a new server (whose rows count from 0 again).
  if (!rows_known_ || written < next_row_) {
    next_row_ = written - 1;
    rows_known_ = true;
  }
  const std::uint64_t depth = proxy_->history_rows();
  if (written - next_row_ > depth) {  // gone before we could read them
    rows_skipped_.fetch_add(written - depth - next_row_, std::memory_order_relaxed);
    next_row_ = written - depth;
  }
  for (; next_row_ < written; ++next_row_) {
    const bool newest = next_row_ + 1 == written;
    const bool full = rows_ + 1 >= decimation_;
    if (full || (newest && display_period_ > 0)) {
      const auto st = proxy_->read_row(next_row_, block_.data());
      if (st == bridge::Proxy::RowStatus::overwritten)
        rows_skipped_.fetch_add(1, std::memory_order_relaxed);
      else if (st != bridge::Proxy::RowStatus::ok)
        return;  // the server is gone (or the row not there yet): from this row at the next wake
      else
        publish_block(full, newest);
    }
    rows_ = full ? 0 : rows_ + 1;
    if (full) ++published_rows_;
  }
}

void Attachment::publish_block(bool full, bool newest) {
  TimeNs time = 0;
  std::memcpy(&time, block_.data(), sizeof time);  // each row starts with its time
  // Due by the rows' own times: the display samples are a period apart in the server's time (on
  // a fixed grid, which a late gateway rejoins), whenever the gateway woke.
  const bool display = newest && display_period_ > 0 && time >= next_display_;
  if (display) next_display_ += display_period_;
  if (display && next_display_ <= time) next_display_ = time + display_period_;  // a period behind
  const TimeNs wall = wall_from_monotonic(time);
  for (auto& s : states_) {
    const bool full_here = full && published_rows_ % s.every == 0;
    if (!full_here && !display) continue;
    std::memcpy(s.value.data(), block_.data() + s.offset, std::min<std::size_t>(s.size, s.value.size()));
    if (full_here && s.mapping->write(*s.writer, s.value.data(), wall, name_))
      published_.fetch_add(1, std::memory_order_relaxed);
    if (display && s.display != nullptr && s.mapping->write(*s.display, s.value.data(), wall, name_))
      displayed_.fetch_add(1, std::memory_order_relaxed);
  }
}

void Attachment::run() {
  std::uint32_t seen = 0;
  bool was_alive = true;
  bool announce = true;  // the latched states, once the mirror has a row (again)
  std::string why;
  while (!stop_.load(std::memory_order_acquire)) {
    const bool row = proxy_->wait_for_update(seen, poll);
    const bool alive = proxy_->server_alive();
    if (alive != was_alive) {
      was_alive = alive;
      alive_.store(alive, std::memory_order_release);
      if (!alive) {
        const std::string last = proxy_->last_error();
        publish_fault("the RT process serving it stopped answering" +
                      (last.empty() ? "" : " (" + last + ")"));
      }
      announce = alive;
      rows_known_ = false;  // a server back, or another: from its newest row
      liveness_changed_();
    }
    if (row && alive && announce) {
      announce = false;
      for (auto& s : initial_states_) publish_state(s, false);
      for (auto& s : changed_states_) publish_state(s, false);
    } else if (row && alive) {
      for (auto& s : changed_states_) publish_state(s, true);
    }
    if (row && alive) publish_rows();
    detail::Access::remote_events(*proxy_)->drain();
    for (auto& c : commands_) {
      for (;;) {
        const auto t = c.mapping->take(*c.reader, c.value.data(), why);
        if (t == Mapping::Take::none) break;
        if (t == Mapping::Take::rejected || !within_limits(c, why)) {
          reject(c.command->name, why);
          continue;
        }
        const Status st = detail::Access::forward(*c.command)(c.value.data());
        if (st == Status::ok)
          commands_in_.fetch_add(1, std::memory_order_relaxed);
        else
          reject(c.command->name, std::string(to_string(st)));
      }
    }
  }
}

}  // namespace saw::gateway
