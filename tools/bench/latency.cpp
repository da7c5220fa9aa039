// saw-latency: the paper's Fig. 4 benchmark (a qualified read of a double, 10,000 calls × 5) in
// every configuration — Local 1P, Local 2P over shared memory, Local 2P over DDS through both
// gateways, Network 1H across a veth pair between two network namespaces, Network MH across a
// router between two subnets (DDS peers found by their peer lists) — beside, in the same
// run and with the same payload, ZeroC Ice 3.7 (the paper's middleware) and raw Fast DDS.
// Also the one-way latency of a state row from the server's process to the client's, and the DDS
// paths again with DDS Security (gateway and operator enclaves of a keystore made for the run),
// with a new peer's discovery time. Prints a Markdown table, the goals as ratios, and writes CSV
// for tools/plot_latency.py.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "child.hpp"
#include "dds_echo.hpp"
#include "ice_baseline.hpp"
#include "ping_pong.hpp"
#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/gateway/query_client.hpp"
#include "saw/manager.hpp"
#include "saw/security/keystore.hpp"
#include "saw/testing/dds_domain.hpp"
#include "stats.hpp"

namespace {

using namespace std::chrono_literals;
using saw::bench::Measured;

// The server of every configuration: add_one (the paper's qualified read) and, at 1 kHz, a row
// holding the time it was written (for the one-way state latency; one clock for all processes).
class Server : public saw::Task {
 public:
  explicit Server(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 50)) {
    auto& p = provide("bench");
    p.add_command_qualified_read<double, double>("add_one", [](const double& q, double& r) { r = q + 1; });
    p.add_command_read("stamp", state_table().add_column("stamp", &stamp_));
  }
  void run() override { stamp_ = saw::monotonic_now(); }

 private:
  std::int64_t stamp_ = 0;
};

class Caller : public saw::Component {
 public:
  Caller() : Component("caller") {
    auto& r = require("bench");
    r.add_function("add_one", add_one);
    r.add_function("stamp", stamp);
  }
  saw::FunctionQualifiedRead<double, double> add_one;
  saw::FunctionRead<std::int64_t> stamp;
};

struct Plan {
  int calls = 10000, reps = 5, rows = 3000, warmup = 200;
  int gateway_cpu = 1;  // of the gateways, the raw echo and the Ice server (-1: any)
};

// A qualified-read loop: `call(x, r)` returns true on success with r = x + 1.
template <class Call>
std::vector<std::int64_t> loop(const Plan& plan, std::uint64_t& failed, Call call) {
  double x = 0, r = 0;
  for (int i = 0; i < plan.warmup; ++i) (void)call(x, r);
  std::vector<std::int64_t> out;
  out.reserve(static_cast<std::size_t>(plan.calls));
  for (int i = 0; i < plan.calls; ++i) {
    const auto t0 = saw::monotonic_now();
    const bool ok = call(x, r) && r == x + 1;
    const auto t1 = saw::monotonic_now();
    if (!ok) {
      if (++failed > 20) break;  // the path is down: do not wait a timeout per call
      continue;
    }
    out.push_back(t1 - t0);
    x = r * 0.5;
  }
  return out;
}

// Until the first successful call, at most `limit` (discovery, a mirror being built).
template <class Call>
bool first_success(Call call, std::chrono::seconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  double r = 0;
  while (!call(1.0, r)) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

[[noreturn]] void serve(const std::string& name) {
  Server s(name);
  saw::bridge::Exporter exporter(s, "bench");
  saw::Manager m;
  m.add(s);
  m.start();
  pause();
  std::_Exit(0);
}

[[noreturn]] void run_gateway(saw::gateway::GatewayConfig c) {
  c.attach_timeout = 20'000'000'000;
  try {
    saw::gateway::Gateway g(c);
    pause();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "saw-latency: gateway %s: %s\n", c.name.c_str(), e.what());
  }
  std::_Exit(3);
}

// A client process that connects to `name` through this host's bridge (the server itself or a
// gateway's mirror of it), then: qualified reads, or one-way state rows when `rows` is set.
std::vector<std::int64_t> bridge_client(const Plan& plan, const std::string& name, bool rows,
                                        std::uint64_t& failed) {
  Caller c;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(c);
  for (int attempt = 0;; ++attempt) {
    try {
      m.connect("caller", "bench", name, "bench");
      break;
    } catch (const saw::ConnectError& e) {
      if (attempt > 2000) {
        std::fprintf(stderr, "saw-latency: connect %s: %s\n", name.c_str(), e.what());
        ++failed;
        return {};
      }
      std::this_thread::sleep_for(10ms);
    }
  }
  const auto call = [&](double x, double& r) { return c.add_one(x, r) == saw::Status::ok; };
  if (!rows) {
    if (!first_success(call, 20s)) {
      ++failed;
      return {};
    }
    return loop(plan, failed, call);
  }
  // State rows need no call through the mirror (its queries may time out behind its stream, as
  // under emulation): the first row read is the start.
  auto* proxy = dynamic_cast<saw::bridge::Proxy*>(m.find(name));
  std::vector<std::int64_t> out;
  std::uint32_t seen = 0;
  const auto first_row = [&](double, double&) {
    std::int64_t stamp = 0;
    return proxy->wait_for_update(seen, 100'000'000) && c.stamp(stamp) == saw::Status::ok;
  };
  if (!first_success(first_row, 20s)) {
    ++failed;
    return {};
  }
  while (static_cast<int>(out.size()) < plan.rows && failed < 20) {
    std::int64_t stamp = 0;
    if (!proxy->wait_for_update(seen, 100'000'000) || c.stamp(stamp) != saw::Status::ok) {
      ++failed;
      continue;
    }
    out.push_back(saw::monotonic_now() - stamp);
  }
  return out;
}

// A DDS peer (no bridge on its side) calling rq/<component>/add_oneRequest.
using Enclave = std::optional<std::filesystem::path>;

struct Site {           // where one side of a configuration runs
  std::string ns;       // network namespace ("" here)
  std::string address;  // the address DDS and Ice use there
  std::string peer{};   // beyond a router: the other side's address, a DDS peer (no multicast)
};

// A participant of this site: its interface, and the other side as its peer.
saw::gateway::ParticipantConfig participant_at(const Site& at, int domain, const char* name,
                                               const Enclave& enclave) {
  saw::gateway::ParticipantConfig pc;
  pc.domain = domain;
  pc.name = name;
  pc.interfaces = {at.address};
  if (!at.peer.empty()) pc.peers = {at.peer};
  pc.enclave = enclave;
  return pc;
}

std::vector<std::int64_t> dds_client(const Plan& plan, int domain, const Site& at,
                                     const std::string& component, std::uint64_t& failed,
                                     const Enclave& enclave) {
  auto* p = saw::gateway::make_participant(participant_at(at, domain, "latency-client", enclave));
  std::vector<std::int64_t> out;
  {
    saw::gateway::QueryClient q(p, component, "add_one");
    const auto call = [&](double x, double& r) {
      return q.call(&x, sizeof x, &r, sizeof r, 1'000'000'000) == saw::Status::ok;
    };
    if (q.wait_matched(20'000'000'000) && first_success(call, 20s))
      out = loop(plan, failed, call);
    else
      ++failed;
  }
  saw::gateway::delete_participant(p);
  return out;
}

// A new peer's discovery: from making its participant until its qualified-read client has
// matched the server's gateway (with security: authentication and key exchange included).
std::vector<std::int64_t> discovery(int times, int domain, const Site& at, const std::string& component,
                                    std::uint64_t& failed, const Enclave& enclave) {
  const auto pc = participant_at(at, domain, "latency-discovery", enclave);
  std::vector<std::int64_t> out;
  for (int i = 0; i < times; ++i) {
    const auto t0 = saw::monotonic_now();
    auto* p = saw::gateway::make_participant(pc);
    {
      saw::gateway::QueryClient q(p, component, "add_one");
      if (q.wait_matched(20'000'000'000))
        out.push_back(saw::monotonic_now() - t0);
      else
        ++failed;
    }
    saw::gateway::delete_participant(p);
  }
  return out;
}

// Reads the Ice server's proxy string from the pipe it was given.
std::string read_line(int fd) {
  std::string s;
  char ch;
  while (read(fd, &ch, 1) == 1 && ch != '\n') s.push_back(ch);
  close(fd);
  return s;
}

struct Row {
  std::string config, path, transport;
  saw::bench::Summary s;
  std::uint64_t failed = 0;
  bool completed = false;
};

// Runs every path of a configuration once per repetition, interleaved (A B C, A B C, ...), so
// that a slow minute of the VM falls on all of them alike; each run is a fresh client process.
class Suite {
 public:
  // `enclaves`: a keystore's enclaves/ with `gateway` and `operator`, for the secure configurations.
  Suite(Plan plan, std::filesystem::path enclaves) : plan_(plan), enclaves_(std::move(enclaves)) {}

  void local() {
    const std::string name = "lat" + std::to_string(getpid());
    std::vector<Path> paths;
    paths.push_back({"qualified read, two threads of one process", "function call", {}, [&](auto& f) {
                       Server s(name);
                       Caller c;
                       saw::Manager m;
                       m.add(s);
                       m.add(c);
                       m.connect("caller", "bench", name, "bench");
                       m.start();
                       return loop(plan_, f,
                                   [&](double x, double& r) { return c.add_one(x, r) == saw::Status::ok; });
                     }});
    run("Local 1P", paths);
    const Site here{"", "127.0.0.1"};
    remote("Local 2P", name, here, here, false);
    if (!enclaves_.empty()) remote("Local 2P secure", name + "s", here, here, true);
  }

  void network(const saw::bench::VethPair& veth) {
    const std::string name = "latn" + std::to_string(getpid());
    remote("Network 1H", name, {veth.ns_a(), veth.addr_a()}, {veth.ns_b(), veth.addr_b()}, false);
    if (!enclaves_.empty())
      remote("Network 1H secure", name + "s", {veth.ns_a(), veth.addr_a()}, {veth.ns_b(), veth.addr_b()},
             true);
  }

  // The server at the patient's end, the client at the operator's, a router between: every DDS
  // participant finds the other side by its peer list (multicast does not cross the router).
  void routed(const saw::bench::RoutedNet& net, const std::string& config) {
    const std::string name = "latr" + std::to_string(getpid());
    const Site patient{net.ns_patient(), net.addr_patient(), net.addr_operator()};
    const Site operator_{net.ns_operator(), net.addr_operator(), net.addr_patient()};
    remote(config, name, patient, operator_, false);
    if (!enclaves_.empty()) remote(config + " secure", name + "s", patient, operator_, true);
  }

  const std::vector<Row>& rows() const { return rows_; }

 private:
  struct Path {
    std::string path, transport;
    Site at;  // where the client runs
    std::function<std::vector<std::int64_t>(std::uint64_t&)> body;
  };

  void run(const std::string& config, const std::vector<Path>& paths) {
    std::vector<Measured> all(paths.size());
    for (auto& m : all) m.completed = true;
    for (int rep = 0; rep < plan_.reps; ++rep)
      for (std::size_t i = 0; i < paths.size(); ++i) {
        const auto m = saw::bench::measure_in_child(
            paths[i].at.ns, 0, static_cast<std::size_t>(plan_.calls) + 16, 120s, paths[i].body);
        all[i].samples.insert(all[i].samples.end(), m.samples.begin(), m.samples.end());
        all[i].failed += m.failed;
        all[i].completed = all[i].completed && m.completed;
      }
    for (std::size_t i = 0; i < paths.size(); ++i) {
      Row r{config, paths[i].path, paths[i].transport, {}, all[i].failed, all[i].completed};
      r.s = saw::bench::summarize(all[i].samples);
      std::fprintf(stderr, "  %-10s %-60s median %8.2f us  (n=%zu, failed %llu%s)\n", config.c_str(),
                   r.path.c_str(), r.s.median_us, r.s.n, static_cast<unsigned long long>(r.failed),
                   r.completed ? "" : ", did not complete");
      rows_.push_back(std::move(r));
    }
  }

  // The server's process and its gateway at `server`; the client's gateway (a mirror) and the
  // client process at `client`; and the baselines between the same two places. `secure`: the DDS
  // paths only, every participant with an enclave (gateways: gateway; DDS peers: operator). Each
  // configuration on a DDS domain it holds alone (saw/testing/dds_domain.hpp).
  void remote(const std::string& config, const std::string& name, const Site& server, const Site& client,
              bool secure) {
    const Enclave gateway_enclave = secure ? Enclave(enclaves_ / "gateway") : std::nullopt;
    const Enclave peer_enclave = secure ? Enclave(enclaves_ / "operator") : std::nullopt;
    const bool same_host = server.ns == client.ns;
    const bool routed = !client.peer.empty();
    const std::string dds = same_host ? "DDS loopback" : routed ? "DDS routed" : "DDS veth";
    const saw::testing::DdsDomain claim;
    const int domain = claim.id();
    const std::string mirrored = name + "m";
    saw::bench::Children servers;
    servers.spawn(server.ns, 1, [&] { serve(name); });
    saw::gateway::GatewayConfig a, b;
    a.name = "gateway-server";
    a.attach = {name};
    a.dds.domain = domain;
    a.dds.interfaces = {server.address};
    if (!server.peer.empty()) a.dds.peers = {server.peer};
    b.name = "gateway-client";
    b.mirrors = {name + "=" + mirrored};
    b.dds.domain = domain;
    b.dds.interfaces = {client.address};
    if (!client.peer.empty()) b.dds.peers = {client.peer};
    a.dds.enclave = b.dds.enclave = gateway_enclave;
    servers.spawn(server.ns, plan_.gateway_cpu, [&] { run_gateway(a); });
    servers.spawn(server.ns, plan_.gateway_cpu, [&] {
      saw::bench::raw_dds_echo(participant_at(server, domain, "raw-echo", gateway_enclave));
    });
    int fds[2];
    if (pipe(fds) != 0) return;
    servers.spawn(server.ns, plan_.gateway_cpu, [&] {
      close(fds[0]);
      saw::bench::ice_serve(server.address, fds[1]);
    });
    close(fds[1]);
    const std::string endpoint = read_line(fds[0]);
    Plan one_rep = plan_;
    one_rep.rows = std::max(1, plan_.rows / plan_.reps);
    std::vector<Path> paths;
    if (same_host && !secure) {
      paths.push_back({"qualified read over the shared-memory bridge", "shared memory", client,
                       [&](auto& f) { return bridge_client(plan_, name, false, f); }});
      paths.push_back({"bare futex ping-pong (the floor for a sleeping waiter)", "shared memory", client,
                       [&](auto&) { return saw::bench::futex_ping_pong(plan_.calls, 1); }});
      paths.push_back({"state row, server task -> client process (one way)", "shared memory", client,
                       [&](auto& f) { return bridge_client(one_rep, name, true, f); }});
    }
    paths.push_back({"qualified read, DDS peer -> server's gateway -> bridge", dds, client,
                     [&](auto& f) { return dds_client(plan_, domain, client, name, f, peer_enclave); }});
    paths.push_back({"raw Fast DDS request/reply (same types, QoS, wait)", dds, client,
                     [&](auto& f) { return dds_client(plan_, domain, client, "raw", f, peer_enclave); }});
    paths.push_back({"discovery: a new DDS peer until its qualified-read client matched", dds, client,
                     [&](auto& f) { return discovery(4, domain, client, name, f, peer_enclave); }});
    if (!secure)
      paths.push_back({"ZeroC Ice 3.7 two-way call addOne(double)",
                       same_host ? "TCP loopback"
                       : routed  ? "TCP routed"
                                 : "TCP veth",
                       client, [&](auto& f) {
                         std::uint64_t warm = 0;
                         (void)saw::bench::ice_calls(endpoint, plan_.warmup, 0, warm);
                         return saw::bench::ice_calls(endpoint, plan_.calls, 0, f);
                       }});
    run(config, paths);
    // Then the client's gateway, mirroring the server: not earlier, because the mirror's 1 kHz
    // state stream would load the server's gateway during the paths above and not the raw echo.
    servers.spawn(client.ns, plan_.gateway_cpu, [&] { run_gateway(b); });
    paths.clear();
    paths.push_back({"qualified read, both gateways (bridge, DDS, bridge)", dds, client,
                     [&](auto& f) { return bridge_client(plan_, mirrored, false, f); }});
    paths.push_back({"state row, server task -> client process via both gateways", dds, client,
                     [&](auto& f) { return bridge_client(one_rep, mirrored, true, f); }});
    run(config, paths);
  }

  Plan plan_;
  std::filesystem::path enclaves_;
  std::vector<Row> rows_;
};

// A keystore for the secure configurations, in a directory of its own (removed by the caller).
std::filesystem::path make_keystore() {
  char dir[] = "/tmp/saw-latency-keystore-XXXXXX";
  if (mkdtemp(dir) == nullptr) throw std::runtime_error("saw-latency: cannot make a keystore directory");
  const std::filesystem::path ks = std::filesystem::path(dir) / "keystore";
  saw::security::create_keystore(ks);
  for (auto [name, role] : {std::pair{"gateway", saw::security::Role::gateway},
                            std::pair{"operator", saw::security::Role::operator_}}) {
    saw::security::EnrollOptions o;
    o.role = role;
    saw::security::enroll(ks, name, o);
  }
  return ks;
}

const Row* find(const std::vector<Row>& rows, const std::string& config, const std::string& path_start) {
  for (const auto& r : rows)
    if (r.config == config && r.path.rfind(path_start, 0) == 0 && r.s.n > 0) return &r;
  return nullptr;
}

struct Case {
  std::string config, path_start;
};

void goal(const std::vector<Row>& rows, const char* what, const Case& ours, const Case& theirs,
          double limit) {
  const Row* a = find(rows, ours.config, ours.path_start);
  const Row* b = find(rows, theirs.config, theirs.path_start);
  if (a == nullptr || b == nullptr) {
    std::printf("| %s | — | not measured |\n", what);
    return;
  }
  const double ratio = a->s.median_us / b->s.median_us;
  std::printf("| %s | %.3g × (p99 %.3g ×) | %s |\n", what, ratio, a->s.p99_us / b->s.p99_us,
              limit <= 0       ? "reported"
              : ratio <= limit ? "met"
                               : "**missed**");
}

// Across the router: ours against the baselines of the same configuration (reported: a router
// adds the same hop to each, and a netem link its delay).
void routed_goals(const std::vector<Row>& rows, const std::string& mh) {
  const Case raw{mh, "raw Fast DDS"}, ice{mh, "ZeroC Ice"};
  goal(rows, "routed: DDS peer → gateway → bridge, against raw Fast DDS", {mh, "qualified read, DDS peer"},
       raw, 0);
  goal(rows, "routed: both gateways, against raw Fast DDS", {mh, "qualified read, both"}, raw, 0);
  goal(rows, "routed: DDS peer → gateway, against Ice", {mh, "qualified read, DDS peer"}, ice, 0);
  goal(rows, "routed, secure: DDS peer → gateway, against without security",
       {mh + " secure", "qualified read, DDS peer"}, {mh, "qualified read, DDS peer"}, 0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"saw-latency: the paper's Fig. 4 qualified-read benchmark with Ice and raw Fast DDS beside"};
  Plan plan;
  std::string csv;
  bool no_veth = false;
  app.add_option("--calls", plan.calls, "calls per repetition");
  app.add_option("--reps", plan.reps, "repetitions");
  app.add_option("--rows", plan.rows, "state rows for the one-way latencies (1 kHz)");
  app.add_option("--csv", csv, "write the table as CSV to this file");
  app.add_option("--gateway-cpu", plan.gateway_cpu,
                 "CPU of the gateways, the raw echo and the Ice server (-1: any; the RT server is on CPU 1)");
  app.add_flag("--no-veth", no_veth, "skip Network 1H (two network namespaces joined by a veth pair)");
  bool no_local = false, no_routed = false;
  app.add_flag("--no-local", no_local, "skip Local 1P and Local 2P (this host's loopback)");
  std::string netem;
  app.add_flag("--no-routed", no_routed, "skip Network MH (two subnets joined by a router namespace)");
  app.add_option("--netem", netem,
                 "Network MH: shape the patient's link both ways with this tc netem spec (a kernel with "
                 "sch_netem), e.g. \"delay 20ms 5ms loss 1%\"");
  bool no_secure = false;
  std::string given_keystore;
  app.add_flag("--no-secure", no_secure, "skip the DDS Security configurations");
  app.add_option("--keystore", given_keystore,
                 "measure the secure configurations with this keystore's enclaves gateway and operator "
                 "(default: a new keystore, sawctl security init's governance)");
  CLI11_PARSE(app, argc, argv);
  saw::rt::DmaLatencyHold dma;
  (void)saw::rt::set_affinity(0);
  const std::filesystem::path keystore =
      no_secure || !given_keystore.empty() ? std::filesystem::path() : make_keystore();
  const std::filesystem::path enclaves = no_secure ? std::filesystem::path()
                                         : given_keystore.empty()
                                             ? keystore / "enclaves"
                                             : std::filesystem::path(given_keystore) / "enclaves";
  Suite suite(plan, enclaves);
  std::fprintf(stderr, "saw-latency: %d × %d calls per configuration\n", plan.reps, plan.calls);
  if (!no_local) suite.local();
  std::string network_note;
  if (no_veth) {
    network_note = "Network 1H: skipped (--no-veth)";
  } else {
    saw::bench::VethPair veth("sawlat");
    if (veth.ok())
      suite.network(veth);
    else
      network_note =
          "Network 1H: skipped — network namespaces or a veth pair cannot be made here (root needed)";
  }
  std::string routed_note;
  if (no_routed) {
    routed_note = "Network MH: skipped (--no-routed)";
  } else {
    saw::bench::RoutedNet net("sawlat", netem);
    if (net.ok())
      suite.routed(net, netem.empty() ? "Network MH" : "Network MH netem");
    else
      routed_note = "Network MH: skipped — namespaces, routing" +
                    std::string(netem.empty() ? "" : " or netem") + " cannot be made here (root needed" +
                    (netem.empty() ? "" : "; sch_netem for --netem") + ")";
  }
  const auto& rows = suite.rows();
  std::printf(
      "# saw-latency: %d × %d calls; client on CPU 0, RT server on CPU 1, gateways and baselines' servers "
      "on %s%s\n\n",
      plan.reps, plan.calls,
      plan.gateway_cpu < 0 ? "any CPU" : ("CPU " + std::to_string(plan.gateway_cpu)).c_str(),
      dma.error().empty() ? "; cpu_dma_latency held at 0" : "");
  std::printf(
      "| configuration | path | transport | median µs | p90 µs | p99 µs | p99.9 µs | max µs | n | failed "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows)
    std::printf("| %s | %s | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %zu | %llu%s |\n", r.config.c_str(),
                r.path.c_str(), r.transport.c_str(), r.s.median_us, r.s.p90_us, r.s.p99_us, r.s.p999_us,
                r.s.max_us, r.s.n, static_cast<unsigned long long>(r.failed),
                r.completed ? "" : " (incomplete)");
  if (!network_note.empty()) std::printf("\n%s\n", network_note.c_str());
  if (!routed_note.empty()) std::printf("\n%s\n", routed_note.c_str());
  std::printf("\n| goal (ratio of medians, one run) | measured | verdict |\n|---|---|---|\n");
  const Case ice_lo{"Local 2P", "ZeroC Ice"}, raw_lo{"Local 2P", "raw Fast DDS"};
  const Case ice_net{"Network 1H", "ZeroC Ice"}, raw_net{"Network 1H", "raw Fast DDS"};
  goal(rows, "Local 1P ≤ 1/100 of Ice on loopback", {"Local 1P", "qualified read"}, ice_lo, 0.01);
  goal(rows, "Local 2P over shared memory ≤ 1/2 of Ice on loopback", {"Local 2P", "qualified read over the"},
       ice_lo, 0.5);
  goal(rows, "Local 2P over shared memory, against the futex floor", {"Local 2P", "qualified read over the"},
       {"Local 2P", "bare futex"}, 0);
  goal(rows, "loopback: DDS peer → gateway → bridge ≤ 1.1 × raw Fast DDS",
       {"Local 2P", "qualified read, DDS peer"}, raw_lo, 1.1);
  goal(rows, "loopback: both gateways, against raw Fast DDS", {"Local 2P", "qualified read, both"}, raw_lo,
       0);
  goal(rows, "loopback: DDS peer → gateway ≤ Ice (stretch)", {"Local 2P", "qualified read, DDS peer"}, ice_lo,
       1.0);
  goal(rows, "veth: DDS peer → gateway → bridge ≤ 1.1 × raw Fast DDS",
       {"Network 1H", "qualified read, DDS peer"}, raw_net, 1.1);
  goal(rows, "veth: both gateways, against raw Fast DDS", {"Network 1H", "qualified read, both"}, raw_net, 0);
  goal(rows, "veth: DDS peer → gateway ≤ Ice (stretch)", {"Network 1H", "qualified read, DDS peer"}, ice_net,
       1.0);
  const Case qr_lo{"Local 2P", "qualified read, DDS peer"}, qr_net{"Network 1H", "qualified read, DDS peer"};
  goal(rows, "loopback, secure: DDS peer → gateway ≤ 1.2 × without security",
       {"Local 2P secure", "qualified read, DDS peer"}, qr_lo, 1.2);
  goal(rows, "loopback, secure: raw Fast DDS ≤ 1.2 × without security", {"Local 2P secure", "raw Fast DDS"},
       raw_lo, 1.2);
  goal(rows, "loopback, secure: state via both gateways, against without security",
       {"Local 2P secure", "state row"}, {"Local 2P", "state row, server task -> client process via"}, 0);
  goal(rows, "veth, secure: DDS peer → gateway ≤ 1.2 × without security",
       {"Network 1H secure", "qualified read, DDS peer"}, qr_net, 1.2);
  goal(rows, "veth, secure: raw Fast DDS ≤ 1.2 × without security", {"Network 1H secure", "raw Fast DDS"},
       raw_net, 1.2);
  goal(rows, "loopback, secure: a new peer's discovery, against without security",
       {"Local 2P secure", "discovery"}, {"Local 2P", "discovery"}, 0);
  routed_goals(rows, netem.empty() ? "Network MH" : "Network MH netem");
  if (!keystore.empty()) std::filesystem::remove_all(keystore.parent_path());
  if (!csv.empty()) {
    std::ofstream out(csv);
    out << "configuration,path,transport,median_us,p90_us,p99_us,p999_us,max_us,n,failed\n";
    for (const auto& r : rows)
      out << r.config << ',' << '"' << r.path << '"' << ',' << r.transport << ',' << r.s.median_us << ','
          << r.s.p90_us << ',' << r.s.p99_us << ',' << r.s.p999_us << ',' << r.s.max_us << ',' << r.s.n << ','
          << r.failed << '\n';
  }
  bool ok = true;
  for (const auto& r : rows) ok = ok && r.completed && r.failed == 0;
  return ok ? 0 : 1;
}
