// sawctl: the whole system from the registry (list), one topic's values (echo), one command (call).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <map>
#include <thread>

#include "dds_context.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/gateway/participant.hpp"
#include "saw_msgs/msg/ManifestPubSubTypes.h"
#include "security_cli.hpp"

namespace {

using namespace saw::gateway;
using Clock = std::chrono::steady_clock;

std::string label(const saw_msgs::msg::Endpoint& e) {
  return e.saw_type().empty() ? "" : e.saw_type() + " v" + std::to_string(e.saw_version());
}

struct Session {
  explicit Session(const ParticipantConfig& c) : mappings(core_mappings()) {
    load_mapping_modules(mappings);  // the packages' types, as the gateway maps them
    ctx.mappings = &mappings;
    ctx.participant = make_participant(c);
    ctx.publisher = ctx.participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    ctx.subscriber = ctx.participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    fdds::TypeSupport t(new saw_msgs::msg::ManifestPubSubType());
    t.register_type(ctx.participant);
    auto* topic =
        ctx.participant->create_topic("rt/saw/manifest", t.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    registry = ctx.subscriber->create_datareader(topic, DdsContext::reader_qos(Flow::registry));
  }
  ~Session() { delete_participant(ctx.participant); }

  // Every gateway's newest manifest; stops early once `done` says so.
  template <class Done>
  const std::map<std::string, saw_msgs::msg::Manifest>& manifests(double timeout, Done done) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
    for (;;) {
      saw_msgs::msg::Manifest m;
      fdds::SampleInfo info;
      while (registry->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
        if (info.valid_data) known[m.gateway()] = m;
      if (done(known) || Clock::now() >= deadline) return known;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  const saw_msgs::msg::Endpoint* find(const std::string& topic, double timeout) {
    const saw_msgs::msg::Endpoint* found = nullptr;
    manifests(timeout, [&](const auto& ms) {
      for (const auto& [name, m] : ms)
        for (const auto& e : m.endpoints())
          if (e.topic() == topic) found = &e;
      return found != nullptr;
    });
    return found;
  }

  MappingRegistry mappings;
  DdsContext ctx;
  fdds::DataReader* registry = nullptr;
  std::map<std::string, saw_msgs::msg::Manifest> known;
};

// DDS refuses an endpoint its access control does not permit (DDS Security: the enclave's role).
int refused(const char* what, const std::string& topic) {
  std::fprintf(stderr, "sawctl: DDS refused to %s %s (does this enclave's role permit it?)\n", what,
               topic.c_str());
  return 1;
}

int list(Session& s, double timeout) {
  // Done when gateways have answered and no new one for half a second (they answer together:
  // their manifests are transient local), or at the timeout.
  std::size_t seen = 0;
  auto quiet_since = Clock::now();
  const auto& ms = s.manifests(timeout, [&](const auto& known) {
    if (known.size() != seen) {
      seen = known.size();
      quiet_since = Clock::now();
    }
    return seen > 0 && Clock::now() - quiet_since > std::chrono::milliseconds(500);
  });
  if (ms.empty()) {
    std::printf("no gateway answered within %.1f s\n", timeout);
    return 1;
  }
  for (const auto& [name, m] : ms) {
    std::printf("%s on %s (pid %d): %s\n", name.c_str(), m.host().c_str(), m.pid(), m.state().c_str());
    for (const auto& e : m.endpoints()) {
      char bounds[64] = "";
      if (e.limited()) std::snprintf(bounds, sizeof bounds, "  in [%g, %g]", e.limit_min(), e.limit_max());
      std::printf("  %-14s %-28s %-26s %s%s\n", e.kind().c_str(),
                  (e.component_name() + "." + e.name()).c_str(), label(e).c_str(),
                  e.topic().empty() ? "(not mapped)" : e.topic().c_str(), bounds);
    }
  }
  return 0;
}

int echo(Session& s, const std::string& topic, int count, double timeout) {
  const auto* e = s.find(topic, timeout);
  if (e == nullptr) {
    std::fprintf(stderr, "sawctl: no gateway serves %s\n", topic.c_str());
    return 1;
  }
  const Mapping* m = s.ctx.mapping_by_dds(e->dds_type());
  if (m == nullptr) {
    std::fprintf(stderr, "sawctl: %s carries %s, which sawctl cannot decode\n", topic.c_str(),
                 e->dds_type().c_str());
    return 1;
  }
  // Latched topics (operating states, descriptions, settings' read-backs: the manifest says): the
  // newest sample at once, however long ago it was written. Others best effort: that matches both
  // the state writers (best effort) and the event writers (reliable).
  const bool latched = e->latched();
  auto* r = s.ctx.subscriber->create_datareader(
      s.ctx.topic(topic, *m), DdsContext::reader_qos(latched ? Flow::latched : Flow::state));
  if (r == nullptr) return refused("read", topic);
  std::vector<std::byte> value(std::max<std::size_t>(m->size(), 1));
  std::string why;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  bool had_writer = false;
  for (int n = 0; n < count;) {
    const auto t = m->take(*r, value.data(), why);
    if (t == Mapping::Take::none) {
      // A writer that was matched and is no longer: its gateway left, or its lease ran out
      // (killed, unplugged). Silence from a matched writer is only a quiet topic.
      fdds::SubscriptionMatchedStatus st;
      r->get_subscription_matched_status(st);
      if (st.current_count > 0) had_writer = true;
      if (had_writer && st.current_count == 0) {
        std::fprintf(stderr, "sawctl: %s: the gateway serving it is gone\n", topic.c_str());
        return 3;
      }
      if (Clock::now() >= deadline) {
        std::fprintf(stderr, "sawctl: nothing on %s within %.1f s (%s)\n", topic.c_str(), timeout,
                     had_writer ? "its gateway is there and quiet" : "no gateway's writer matched");
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    std::printf("%s\n", t == Mapping::Take::ok ? m->to_text(value.data()).c_str()
                                               : ("(invalid: " + why + ")").c_str());
    std::fflush(stdout);  // a line as it comes, also into a pipe
    ++n;
  }
  return 0;
}

int call(Session& s, const std::string& topic, const std::vector<std::string>& words, double timeout) {
  const auto* e = s.find(topic, timeout);
  if (e == nullptr) {
    std::fprintf(stderr, "sawctl: no gateway serves %s\n", topic.c_str());
    return 1;
  }
  if (e->kind() != "write" && e->kind() != "void") {
    std::fprintf(stderr, "sawctl: %s is a %s, not a command\n", topic.c_str(), e->kind().c_str());
    return 1;
  }
  const Mapping* m = s.ctx.mapping_by_dds(e->dds_type());
  std::string text, why;
  for (const auto& w : words) text += (text.empty() ? "" : " ") + w;
  std::vector<std::byte> value(std::max<std::size_t>(m->size(), 1));
  if (!m->from_text(text, value.data(), why)) {
    std::fprintf(stderr, "sawctl: %s takes %s: %s\n", topic.c_str(), label(*e).c_str(), why.c_str());
    return 2;
  }
  // The bounds the component declares, checked as the gateway and the bridge check them.
  if (e->limited() && !within_limits(*m, value.data(), saw::Limits{e->limit_min(), e->limit_max()}, why)) {
    std::fprintf(stderr, "sawctl: %s: %s\n", topic.c_str(), why.c_str());
    return 2;
  }
  auto* w = s.ctx.publisher->create_datawriter(s.ctx.topic(topic, *m), DdsContext::writer_qos(Flow::command));
  if (w == nullptr) return refused("write", topic);
  // Wait for the gateway's reader, so the command is not sent into the void.
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  fdds::PublicationMatchedStatus st;
  while (w->get_publication_matched_status(st) == ReturnCode_t::RETCODE_OK && st.current_count == 0) {
    if (Clock::now() >= deadline) {
      std::fprintf(stderr, "sawctl: the gateway's reader of %s did not match within %.1f s\n", topic.c_str(),
                   timeout);
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  m->write(*w, value.data(), wall_from_monotonic(saw::monotonic_now()), "sawctl");
  const auto acked =
      w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(timeout)) == ReturnCode_t::RETCODE_OK;
  std::printf("%s %s: %s\n", topic.c_str(), m->to_text(value.data()).c_str(),
              acked ? "delivered" : "not acknowledged");
  return acked ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"sawctl: the sawrt system as its gateways publish it"};
  ParticipantConfig dds;
  dds.name = "sawctl";
  double timeout = 2.0;
  app.add_option("--domain", dds.domain, "DDS domain id");
  app.add_option("--interface", dds.interfaces,
                 "IPv4 address of an interface DDS may use (default loopback)");
  app.add_option(
      "--peer", dds.peers,
      "a gateway beyond this subnet, found by unicast: ADDRESS or ADDRESS:PORT (repeatable; default "
      "$ROS_STATIC_PEERS)");
  app.add_option("--timeout", timeout, "seconds to wait for the registry and for samples");
  add_enclave_option(app, dds);
  const SecurityCommands security(app);
  app.require_subcommand(1);
  app.fallthrough();  // --timeout, --domain also after the subcommand
  auto* list_cmd = app.add_subcommand("list", "every gateway, its components, commands, events and topics");
  std::string topic;
  int count = 1;
  auto* echo_cmd = app.add_subcommand(
      "echo", "print values published on a topic (exit 3 when the gateway serving it goes away)");
  echo_cmd->add_option("topic", topic, "e.g. rt/master/measured_cp")->required();
  echo_cmd->add_option("--count,-n", count, "samples to print")->check(CLI::PositiveNumber);
  std::vector<std::string> words;
  auto* call_cmd = app.add_subcommand("call", "send a command: sawctl call rt/master/state_command enable");
  call_cmd->add_option("topic", topic, "the command's topic")->required();
  call_cmd->add_option("value", words, "the value: numbers (x y z ...) or a word");
  CLI11_PARSE(app, argc, argv);
  if (security.chosen()) return security.run();
  try {
    Session s(dds);
    if (*list_cmd) return list(s, timeout);
    if (*echo_cmd) return echo(s, topic, count, timeout);
    if (*call_cmd) return call(s, topic, words, timeout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sawctl: %s\n", e.what());
    return 1;
  }
  return 2;
}
