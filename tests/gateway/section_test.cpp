// The `gateway:` deployment section, owned by the gateway package: parsed and checked with
// file:line errors, implied by placement on hosts, and handed to saw-gateway in one serialized
// form that the same parser reads back (each setting written once).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "../deploy/packages.hpp"
#include "saw/gateway/settings.hpp"

namespace {

using saw::deploy::ConfigError;
using saw::gateway::GatewaySettings;
using saw::gateway::ImportSettings;

saw::deploy::ComponentRegistry& registry() {
  static saw::deploy::ComponentRegistry r = [] {
    saw::deploy::ComponentRegistry x;
    saw::testing::register_packages(x);
    saw::gateway::register_components(x, /*start_processes=*/false);
    return x;
  }();
  return r;
}

const char* good = R"(deployment: {name: t, clock: stepped}
components:
  - name: master
    type: sim_haptic_device
    task: {period: 1ms}
  - name: slave
    type: sim_haptic_device
    task: {period: 1ms}
  - name: teleop
    type: teleop
    task: {period: 1ms}
connections:
  - {client: teleop, required: master, server: master, provided: arm}
  - {client: teleop, required: slave, server: slave, provided: arm}
)";
const std::string exported = "exports:\n  - {component: master, provided: arm}\n";

const GatewaySettings& settings_of(const saw::deploy::DeploymentSpec& spec) {
  for (const auto& s : spec.sections)
    if (s.key == "gateway") return std::any_cast<const GatewaySettings&>(s.value.value);
  throw std::logic_error("no gateway section");
}

saw::deploy::DeploymentSpec parse(const std::string& text, const std::string& host = "") {
  return saw::deploy::parse_deployment(text, "cfg.yaml", registry(), host);
}

void expect_error(const std::string& tail, const char* pattern) {
  std::string message;
  try {
    (void)parse(std::string(good) + tail);
  } catch (const ConfigError& e) {
    message = e.what();
  }
  EXPECT_TRUE(std::regex_search(message, std::regex(pattern)))
      << "message: " << message << "\nexpected: " << pattern;
}

TEST(GatewaySection, IsCheckedLikeTheRestOfTheFile) {
  expect_error("gateway: {domain: 3}\n", R"(^cfg\.yaml:15:\d+: key 'gateway': nothing to map)");
  expect_error(exported + "gateway: {attach: [slave]}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway\.attach': 'slave' is not exported)");
  expect_error(exported + "gateway: {domain: 300}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway\.domain': .*out of range)");
  expect_error(exported + "gateway: {domian: 3}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway\.domian': unknown parameter)");
  expect_error(exported + "gateway: {import: [{component: slave}]}\n",
               R"(key 'gateway\.import': a component named 'slave' exists already)");
  const auto spec = parse(std::string(good) + exported + "gateway: {domain: 3}\n");
  const GatewaySettings& g = settings_of(spec);
  EXPECT_EQ(g.attach, std::vector<std::string>{"master"}) << "default: every export";
  EXPECT_EQ(g.domain, 3);
  EXPECT_EQ(g.interfaces, std::vector<std::string>{"127.0.0.1"});
  EXPECT_EQ(g.display_rate, 50) << "live views read 50 samples/s by default";
}

TEST(GatewaySection, EverySettingOfTheGatewayCanBeWrittenInTheFile) {
  const auto spec = parse(std::string(good) + exported +
                          "gateway:\n  import: [{component: MTML, arm: MTML}]\n  namespace: dvrk\n"
                          "  clutch_topic: rt/pedals/clutch\n  operator_present_topic: ''\n  decimation: 4\n"
                          "  display_rate: 100\n  name: lab-gateway\n  mirror: [far=near]\n");
  const GatewaySettings& g = settings_of(spec);
  EXPECT_EQ(g.clutch_topic, "rt/pedals/clutch");
  EXPECT_EQ(g.operator_present_topic, "");
  EXPECT_EQ(g.ros_namespace, "dvrk");
  EXPECT_EQ(g.decimation, 4);
  EXPECT_EQ(g.display_rate, 100);
  EXPECT_EQ(g.name, "lab-gateway");
  EXPECT_EQ(g.mirrors, std::vector<std::string>{"far=near"});
  ASSERT_EQ(g.imports.size(), 1u);
  EXPECT_EQ(g.imports[0].arm, "MTML");
  EXPECT_TRUE(spec.sections[0].value.before_connect) << "imports and mirrors are presented before connect()";
}

TEST(GatewaySection, ItsSerializedFormReadsBackTheSameThroughTheSameParser) {
  GatewaySettings s;
  s.attach = {"a", "b"};
  s.mirrors = {"m=local"};
  ImportSettings mtm, psm;
  mtm.component = mtm.arm = "MTML";
  psm.component = "PSM";
  psm.arm = "PSM1";
  psm.commands = {"servo_cp", "hold"};
  psm.safe_command = "servo_cp_measured";
  psm.command_timeout = 20'000'000;
  psm.offset = 800'000;
  s.imports = {mtm, psm};
  s.ros_namespace = "dvrk";
  s.clutch_topic = "";
  s.operator_present_topic = "rt/head";
  s.domain = 42;
  s.interfaces = {"127.0.0.1", "10.0.0.1"};
  s.peers = {"10.0.1.9", "lab-gateway:7410"};
  s.decimation = 7;
  s.display_rate = 25;
  s.insecure = true;
  s.name = "g";
  EXPECT_EQ(saw::gateway::settings_from_yaml(saw::gateway::to_yaml(s), "--settings"), s);
  // And refused as a file is: one bad key names itself.
  try {
    (void)saw::gateway::settings_from_yaml("{attach: [a], domian: 3}", "--settings");
    ADD_FAILURE() << "a misspelt key was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'domian': unknown parameter"), std::string::npos) << e.what();
  }
}

TEST(GatewaySection, AnImportThatSendsCommandsSaysWhichAndItsSafeCommandFollows) {
  const auto read = [&](const std::string& entry) {
    return settings_of(parse(std::string(good) + exported + "gateway:\n  import: [" + entry + "]\n"))
        .imports.at(0);
  };
  const ImportSettings mtm = read("{component: MTML, commands: [servo_cf, hold]}");
  EXPECT_EQ(mtm.safe_command, "zero_wrench") << "an MTM's wrench is zeroed";
  EXPECT_EQ(mtm.command_timeout, 50'000'000);
  EXPECT_EQ(read("{component: PSM1, commands: [servo_cp, hold]}").safe_command, "hold");
  EXPECT_EQ(read("{component: PSM1, commands: [servo_cp]}").safe_command, "servo_cp_measured");
  EXPECT_TRUE(read("{component: MTML}").commands.empty()) << "read-only unless it says";
  const auto bad = [&](const std::string& entry, const std::string& pattern) {
    expect_error(exported + "gateway:\n  import: [" + entry + "]\n", pattern.c_str());
  };
  bad("{component: MTML, commands: [servo_jf]}",
      R"(^cfg\.yaml:18:\d+: key 'gateway\.import\[0\]\.commands': 'servo_jf' is not one of)");
  bad("{component: MTML, commands: [servo_cf, servo_cp]}",
      R"(key 'gateway\.import\[0\]\.commands': servo_cf .* not both)");
  bad("{component: PSM1, commands: [servo_cp], safe_command: hold}",
      R"(key 'gateway\.import\[0\]\.safe_command': hold needs hold in commands)");
  bad("{component: MTML, commands: [servo_cf], safe_command: brake}",
      R"(key 'gateway\.import\[0\]\.safe_command': 'brake' is not one of)");
  bad("{component: MTML, safe_command: hold}",
      R"(key 'gateway\.import\[0\]\.safe_command': only for an import that sends commands)");
  bad("{component: MTML, commands: [servo_cf], command_timeout: 1ms}",
      R"(key 'gateway\.import\[0\]\.command_timeout': must be from 0\.002 to 1 s)");
  // Its cycle's phase: after its client's, so what the client sent goes out in the same cycle.
  EXPECT_EQ(read("{component: PSM1, commands: [servo_cp], offset: 800us}").offset, 800'000);
  bad("{component: PSM1, commands: [servo_cp], offset: 1ms}",
      R"(key 'gateway\.import\[0\]\.offset': at least 0 and less than the import's 1 ms period)");
  bad("{component: MTML, offset: 800us}",
      R"(key 'gateway\.import\[0\]\.offset': only for an import that sends)");
}

TEST(GatewaySection, PeersNeedAnInterfaceThatReachesThem) {
  expect_error(exported + "gateway: {peers: [10.0.1.9]}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway\.peers': DDS uses loopback only)");
  const auto spec = parse(std::string(good) + exported +
                          "gateway: {interfaces: [10.0.2.2], peers: [10.0.1.9], security: none}\n");
  EXPECT_EQ(settings_of(spec).peers, std::vector<std::string>{"10.0.1.9"});
}

TEST(GatewaySection, OffLoopbackNeedsAnEnclaveOrSaysSecurityNone) {
  expect_error(exported + "gateway: {interfaces: [10.0.0.1]}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway': the gateway's DDS leaves loopback and no security)");
  expect_error(exported + "gateway: {interfaces: [10.0.0.1], security: plain}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway\.security': 'plain': the only value is none)");
  const std::string enclave = ::testing::TempDir() + "section-enclave-" + std::to_string(getpid());
  std::filesystem::create_directories(enclave);
  expect_error(exported + "gateway: {interfaces: [10.0.0.1], enclave: " + enclave + "}\n",
               R"(^cfg\.yaml:17:\d+: key 'gateway\.enclave': enclave .* has no cert\.pem)");
  for (const char* f : {"cert.pem", "key.pem", "identity_ca.cert.pem", "permissions_ca.cert.pem",
                        "governance.p7s", "permissions.p7s"})
    std::ofstream(enclave + "/" + f) << "x";
  expect_error(exported + "gateway: {interfaces: [10.0.0.1], enclave: " + enclave + ", security: none}\n",
               R"(key 'gateway\.security': security: none and an enclave: choose one)");
  EXPECT_EQ(settings_of(parse(std::string(good) + exported +
                              "gateway: {interfaces: [10.0.0.1], enclave: " + enclave + "}\n"))
                .enclave,
            enclave);
  const GatewaySettings plain = settings_of(
      parse(std::string(good) + exported + "gateway: {interfaces: [10.0.0.1], security: none}\n"));
  EXPECT_TRUE(plain.insecure);
  EXPECT_TRUE(plain.enclave.empty());
  // A host's own enclave (hosts: NAME: {address, enclave}) is the gateway's too.
  const std::string hosts = std::string(R"(deployment: {name: h}
hosts:
  a: {address: 10.0.0.1, enclave: )") +
                            enclave + R"(}
  b: {address: 10.0.0.2}
components:
  - {name: master, type: sim_haptic_device, host: a}
  - {name: teleop, type: teleop, host: b}
  - {name: slave, type: sim_haptic_device, host: b}
connections:
  - {client: teleop, required: master, server: master, provided: arm}
  - {client: teleop, required: slave, server: slave, provided: arm}
)";
  const GatewaySettings a = settings_of(parse(hosts, "a"));
  EXPECT_EQ(a.enclave, enclave);
  EXPECT_EQ(a.attach, std::vector<std::string>{"master"}) << "what another machine uses is attached";
  EXPECT_EQ(a.interfaces, std::vector<std::string>{"10.0.0.1"}) << "on the host's address";
  std::string message;
  try {
    (void)parse(hosts, "b");
  } catch (const ConfigError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("no security is configured"), std::string::npos)
      << "host b has no enclave and leaves loopback: " << message;
  std::filesystem::remove_all(enclave);
}

// rt/deploy knows no DDS or security term: those belong to the gateway package.
TEST(GatewaySection, TheDeploymentLibraryKnowsNoDdsOrSecurityTerm) {
  const std::regex forbidden(R"(\b(enclave|dds|DDS|Dds|security|Security)\b)");
  int files = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(SAW_SOURCE_DIR "/rt/deploy")) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path());
    std::string line;
    for (int n = 1; std::getline(in, line); ++n)
      EXPECT_FALSE(std::regex_search(line, forbidden)) << e.path() << ":" << n << ": " << line;
    ++files;
  }
  EXPECT_GT(files, 10);
}

}  // namespace
