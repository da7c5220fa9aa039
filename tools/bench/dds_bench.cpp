// saw-bench-dds: the paper's qualified-read benchmark over DDS (10,000 calls × 5): a client
// process → Fast DDS → saw-gateway → shared-memory bridge → the RT server process, and back;
// beside it, in the same run, raw Fast DDS: the same request/reply types, QoS and wait, answered
// directly by an echo process. Loopback only.
#include <fcntl.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstring>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/gateway/query_client.hpp"
#include "saw/manager.hpp"
#include "saw/rt_thread.hpp"
#include "saw_msgs/msg/QueryPubSubTypes.h"
#include "saw_msgs/msg/QueryReplyPubSubTypes.h"
#include "stats.hpp"

namespace {

namespace fdds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

class Server : public saw::Task {
 public:
  explicit Server(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    provide("bench").add_command_qualified_read<double, double>(
        "add_one", [](const double& q, double& r) { r = q + 1; });
  }
};

[[noreturn]] void serve(const std::string& name) {
  (void)saw::rt::set_affinity(1);
  Server s(name);
  saw::bridge::Exporter exporter(s, "bench");
  saw::Manager m;
  m.add(s);
  m.start();
  pause();
  std::_Exit(0);
}

// Across the veth pair: this process joins network namespace `ns` (made by main) first.
void enter(const std::string& ns) {
  if (ns.empty()) return;
  const int fd = open(("/var/run/netns/" + ns).c_str(), O_RDONLY);
  if (fd < 0 || setns(fd, CLONE_NEWNET) != 0) {
    std::perror(("saw-bench-dds: setns " + ns).c_str());
    std::_Exit(3);
  }
  close(fd);
}

struct Where {
  std::string ns;  // "" on this host's loopback
  std::vector<std::string> interfaces{"127.0.0.1"};
};

[[noreturn]] void gateway(const std::string& name, int domain, const Where& at) {
  (void)saw::rt::set_affinity(1);
  enter(at.ns);
  saw::gateway::GatewayConfig c;
  c.attach = {name};
  c.dds.domain = domain;
  c.dds.interfaces = at.interfaces;
  c.attach_timeout = 10'000'000'000;
  saw::gateway::Gateway g(c);
  pause();
  std::_Exit(0);
}

// Raw Fast DDS: the same topics' types and QoS, the same WaitSet wait, answered at once.
[[noreturn]] void echo(int domain, const Where& at) {
  (void)saw::rt::set_affinity(1);
  enter(at.ns);
  saw::gateway::ParticipantConfig pc;
  pc.domain = domain;
  pc.interfaces = at.interfaces;
  pc.name = "raw-echo";
  auto* p = saw::gateway::make_participant(pc);
  fdds::TypeSupport rq(new saw_msgs::msg::QueryPubSubType()), rr(new saw_msgs::msg::QueryReplyPubSubType());
  rq.register_type(p);
  rr.register_type(p);
  auto* req = p->create_topic("rq/raw/add_oneRequest", rq.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  auto* rep = p->create_topic("rr/raw/add_oneReply", rr.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::DataReaderQos rqos = fdds::DATAREADER_QOS_DEFAULT;
  rqos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  rqos.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  rqos.history().depth = 16;
  rqos.data_sharing().off();
  fdds::DataWriterQos wqos = fdds::DATAWRITER_QOS_DEFAULT;
  wqos.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  wqos.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  wqos.history().depth = 16;
  wqos.data_sharing().off();
  wqos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 50'000'000);
  auto* reader = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT)->create_datareader(req, rqos);
  auto* writer = p->create_publisher(fdds::PUBLISHER_QOS_DEFAULT)->create_datawriter(rep, wqos);
  fdds::WaitSet ws;
  reader->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
  ws.attach_condition(reader->get_statuscondition());
  saw_msgs::msg::Query q;
  saw_msgs::msg::QueryReply r;
  fdds::SampleInfo info;
  for (;;) {
    while (reader->take_next_sample(&q, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || q.data().size() != sizeof(double)) continue;
      double x;
      std::memcpy(&x, q.data().data(), sizeof x);
      x += 1;
      r.client(q.client());
      r.number(q.number());
      r.status(0);
      r.data().resize(sizeof x);
      std::memcpy(r.data().data(), &x, sizeof x);
      writer->write(&r);
    }
    fdds::ConditionSeq active;
    ws.wait(active, eprosima::fastrtps::Duration_t(1, 0));
  }
}

std::vector<std::int64_t> run(saw::gateway::QueryClient& c, int n, std::uint64_t& failed) {
  std::vector<std::int64_t> out;
  out.reserve(static_cast<std::size_t>(n));
  double x = 0;
  for (int i = 0; i < n; ++i) {
    const auto t0 = saw::monotonic_now();
    double r = 0;
    const auto st = c.call(&x, sizeof x, &r, sizeof r, 1'000'000'000);
    if (st != saw::Status::ok || r != x + 1) {
      if (failed++ == 0)
        std::fprintf(stderr, "saw-bench-dds: first failed call: %s\n",
                     std::string(saw::to_string(st)).c_str());
      if (failed > 20) break;  // the path is down: do not wait a second per call
    }
    out.push_back(saw::monotonic_now() - t0);
    x = r * 0.5;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-bench-dds: the paper's qualified read over DDS beside raw Fast DDS"};
  int n = 10000, reps = 5;
  bool markdown = false;
  app.add_option("--calls", n, "calls per repetition");
  app.add_option("--reps", reps, "repetitions");
  app.add_flag("--markdown", markdown, "Markdown table");
  bool veth = false;
  app.add_flag("--veth", veth,
               "Network 1H: the server side in one network namespace, the client in another, joined by a "
               "veth pair (made and removed by this run; needs root)");
  CLI11_PARSE(app, argc, argv);
  Where server_side, client_side;
  std::string ns_a, ns_b;
  if (veth) {
    const std::string tag = std::to_string(getpid());
    ns_a = "sawbench-a-" + tag;
    ns_b = "sawbench-b-" + tag;
    const std::string net = "10.212." + std::to_string(getpid() % 200 + 10);
    const std::string va = ("ba" + tag).substr(0, 15), vb = ("bb" + tag).substr(0, 15);
    const std::string setup = "ip netns add " + ns_a + " && ip netns add " + ns_b + " && ip link add " + va +
                              " type veth peer name " + vb + " && ip link set " + va + " netns " + ns_a +
                              " && ip link set " + vb + " netns " + ns_b + " && ip -n " + ns_a +
                              " addr add " + net + ".1/24 dev " + va + " && ip -n " + ns_b + " addr add " +
                              net + ".2/24 dev " + vb + " && ip -n " + ns_a + " link set " + va +
                              " up && ip -n " + ns_b + " link set " + vb + " up && ip -n " + ns_a +
                              " link set lo up && ip -n " + ns_b + " link set lo up";
    if (std::system(setup.c_str()) != 0) {
      std::fprintf(stderr, "saw-bench-dds: cannot make the two namespaces and the veth pair (root needed)\n");
      (void)std::system(
          ("ip netns del " + ns_a + " 2>/dev/null; ip netns del " + ns_b + " 2>/dev/null").c_str());
      return 2;
    }
    server_side = {ns_a, {net + ".1"}};
    client_side = {ns_b, {net + ".2"}};
  }
  saw::rt::DmaLatencyHold dma;
  const std::string name = "benchdds" + std::to_string(getpid());
  const int domain = 150 + getpid() % 80;
  std::vector<pid_t> children;
  for (int k = 0; k < 3; ++k) {
    const pid_t pid = fork();
    if (pid == 0) {
      if (k == 0) serve(name);
      if (k == 1) {
        std::this_thread::sleep_for(200ms);  // the server exports first (the gateway also waits)
        gateway(name, domain, server_side);
      }
      echo(domain, server_side);
    }
    children.push_back(pid);
  }
  (void)saw::rt::set_affinity(0);
  enter(client_side.ns);
  std::uint64_t failed = 0;
  std::vector<std::int64_t> ours, raw;
  {
    saw::gateway::ParticipantConfig pc;
    pc.domain = domain;
    pc.name = "bench-client";
    pc.interfaces = client_side.interfaces;
    auto* p = saw::gateway::make_participant(pc);
    {
      saw::gateway::QueryClient via_gateway(p, name, "add_one"), direct(p, "raw", "add_one");
      if (!via_gateway.wait_matched(20'000'000'000) || !direct.wait_matched(20'000'000'000)) {
        std::fprintf(stderr, "saw-bench-dds: the gateway or the echo process did not match\n");
        for (pid_t c : children) kill(c, SIGKILL);
        if (veth) (void)std::system(("ip netns del " + ns_a + "; ip netns del " + ns_b).c_str());
        return 1;
      }
      (void)run(via_gateway, 200, failed);  // warm-up: first calls carry discovery's tail
      (void)run(direct, 200, failed);
      failed = 0;
      for (int r = 0; r < reps; ++r) {
        auto a = run(via_gateway, n, failed);
        ours.insert(ours.end(), a.begin(), a.end());
        auto b = run(direct, n, failed);
        raw.insert(raw.end(), b.begin(), b.end());
      }
    }
    saw::gateway::delete_participant(p);
  }
  for (pid_t c : children) {
    kill(c, SIGKILL);
    waitpid(c, nullptr, 0);
  }
  if (veth) (void)std::system(("ip netns del " + ns_a + "; ip netns del " + ns_b).c_str());
  std::printf(
      "# saw-bench-dds: %d × %d calls, client on CPU 0; RT server, saw-gateway and raw echo on CPU 1; "
      "%s, Fast DDS reliable, WaitSet waits\n",
      reps, n, veth ? "across a veth pair between two network namespaces (UDP)" : "loopback (UDP + SHM)");
  saw::bench::print_header(markdown);
  const auto a = saw::bench::summarize(ours), b = saw::bench::summarize(raw);
  saw::bench::print_row(markdown, "qualified read<double> over DDS (gateway + bridge)", a);
  saw::bench::print_row(markdown, "raw Fast DDS request/reply (same types, QoS)", b);
  std::printf("\nratio of medians %.2f, of p99 %.2f; failed calls: %llu\n", a.median_us / b.median_us,
              a.p99_us / b.p99_us, static_cast<unsigned long long>(failed));
  return failed == 0 ? 0 : 1;
}
