#include "saw/gateway/participant.hpp"

#include <arpa/inet.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <netdb.h>
#include <netinet/in.h>

#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <stdexcept>

#include "participant_security.hpp"
#include "reply_filter.hpp"

namespace saw::gateway {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;

namespace {

// The RTPS well-known port of participant `index`'s unicast discovery in `domain` (PB 7400,
// DG 250, PG 2, d1 10): what every DDS implementation listens on, Cyclone DDS included.
std::uint32_t discovery_port(int domain, int index) {
  return static_cast<std::uint32_t>(7400 + 250 * domain + 10 + 2 * index);
}

constexpr int max_local_participants = 32;
// A peer named without a port: its domain's first participants (a gateway, sawctl, a GUI or two).
constexpr int max_peer_participants = 8;

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::string item;
  for (const char ch : text + sep) {
    if (ch != sep) {
      if (ch != ' ' && ch != '\t') item += ch;
      continue;
    }
    if (!item.empty()) out.push_back(item);
    item.clear();
  }
  return out;
}

// "ADDRESS[:PORT]", ADDRESS an IPv4 address or a host name resolved once, here.
Locator_t peer_locator(const std::string& peer, std::uint32_t& port) {
  const auto colon = peer.rfind(':');
  const std::string host = colon == std::string::npos ? peer : peer.substr(0, colon);
  port = 0;
  if (colon != std::string::npos) {
    const std::string p = peer.substr(colon + 1);
    char* end = nullptr;
    const unsigned long v = std::strtoul(p.c_str(), &end, 10);
    if (p.empty() || *end != '\0' || v == 0 || v > 65535)
      throw std::runtime_error("DDS: peer '" + peer + "': the port is not a number from 1 to 65535");
    port = static_cast<std::uint32_t>(v);
  }
  addrinfo hints{};
  hints.ai_family = AF_INET;
  addrinfo* found = nullptr;
  if (host.empty() || getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0 || found == nullptr)
    throw std::runtime_error("DDS: peer '" + peer + "': not an IPv4 address or a known host name");
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr, text, sizeof text);
  freeaddrinfo(found);
  Locator_t l;
  IPLocator::setIPv4(l, text);
  return l;
}

std::vector<std::string> peers_of(const ParticipantConfig& config) {
  if (!config.peers.empty()) return config.peers;
  const char* env = std::getenv("ROS_STATIC_PEERS");
  return env == nullptr ? std::vector<std::string>{} : split(env, ';');
}

// ROS 2's ROS_AUTOMATIC_DISCOVERY_RANGE: how far discovery reaches without a peer list.
enum class Range { subnet, localhost, off };

Range discovery_range() {
  const char* env = std::getenv("ROS_AUTOMATIC_DISCOVERY_RANGE");
  const std::string v = env == nullptr ? "" : env;
  if (v.empty() || v == "SUBNET" || v == "SYSTEM_DEFAULT") return Range::subnet;
  if (v == "LOCALHOST") return Range::localhost;
  if (v == "OFF") return Range::off;
  throw std::runtime_error("DDS: ROS_AUTOMATIC_DISCOVERY_RANGE=" + v +
                           ": expected SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT");
}

// Each of `addresses` at the discovery ports of participant indices [0, n), or at its own port.
void add_initial_peers(eprosima::fastrtps::rtps::BuiltinAttributes& builtin, int domain,
                       const std::vector<std::string>& addresses, int n) {
  for (const auto& peer : addresses) {
    std::uint32_t port = 0;
    const Locator_t base = peer_locator(peer, port);
    for (int i = 0; i < (port != 0 ? 1 : n); ++i) {
      Locator_t l = base;
      l.port = port != 0 ? port : discovery_port(domain, i);
      builtin.initialPeersList.push_back(l);
    }
  }
}

// Unicast discovery: our own metatraffic locator on each of `interfaces` (its port assigned from
// the participant index), which keeps Fast DDS from adding its multicast one (a router forwards
// none), and the initial peers we announce ourselves to. One side's list suffices: a participant
// answers an announcement at the announcer's own locators.
void unicast_discovery(eprosima::fastrtps::rtps::BuiltinAttributes& builtin, const ParticipantConfig& config,
                       const std::vector<std::string>& peers, Range range) {
  for (const auto& address : config.interfaces) {
    Locator_t self;
    IPLocator::setIPv4(self, address);
    self.port = 0;
    builtin.metatrafficUnicastLocatorList.push_back(self);
  }
  // This host's participants: on loopback (unless discovery is off), or on our own interfaces.
  const bool loopback_only = config.interfaces.size() == 1 && config.interfaces.front() == "127.0.0.1";
  if ((loopback_only && range != Range::off) || range == Range::localhost)
    add_initial_peers(builtin, config.domain, config.interfaces, max_local_participants);
  add_initial_peers(builtin, config.domain, peers, max_peer_participants);
}

}  // namespace

fdds::DomainParticipant* make_participant(const ParticipantConfig& config) {
  if (config.interfaces.empty()) throw std::runtime_error("DDS: no network interface given");
  fdds::DomainParticipantQos qos;
  qos.name(config.name);
  qos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList = config.interfaces;
  qos.transport().user_transports.push_back(udp);
  qos.transport().user_transports.push_back(
      std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>());
  // Announce every 250 ms (default 3 s): a peer that missed our reply to its first announcement
  // (a process restarting under the same participant index) finds us within that, not seconds later.
  qos.wire_protocol().builtin.discovery_config.leaseDuration_announcementperiod =
      eprosima::fastrtps::Duration_t(0, 250'000'000);
  // A peer that vanishes without saying goodbye (killed, unplugged) is dropped by the others after
  // this lease (default 20 s): GUIs and sawctl must show a vanished gateway within about a second.
  // Four announcements fit in it, so one lost announcement does not drop a live peer.
  qos.wire_protocol().builtin.discovery_config.leaseDuration = eprosima::fastrtps::Duration_t(1, 0);
  const bool loopback_only = config.interfaces.size() == 1 && config.interfaces.front() == "127.0.0.1";
  if (!config.peers.empty() && loopback_only)
    throw std::runtime_error(
        "DDS: peers given, but DDS may use loopback only: name the interface that reaches them");
  const std::vector<std::string> peers = peers_of(config);
  const Range range = discovery_range();
  // Multicast discovery (Fast DDS's default) only on a subnet, with no peer list.
  if (loopback_only || !peers.empty() || range != Range::subnet)
    unicast_discovery(qos.wire_protocol().builtin, config, peers, range);
  const std::string enclave = apply_security(qos, config);
  auto* p = fdds::DomainParticipantFactory::get_instance()->create_participant(config.domain, qos);
  if (p == nullptr)
    throw std::runtime_error(
        "DDS: could not create a participant in domain " + std::to_string(config.domain) +
        (enclave.empty() ? "" : " with enclave " + enclave + " (DDS Security refused it)"));
  register_reply_filter(p);  // so our reply writers filter for their readers (reply_filter.hpp)
  return p;
}

void delete_participant(fdds::DomainParticipant* p) noexcept {
  if (p == nullptr) return;
  p->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
}

}  // namespace saw::gateway
