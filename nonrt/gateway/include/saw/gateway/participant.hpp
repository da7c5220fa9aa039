// Participant: a Fast DDS domain participant restricted to the network interfaces it is given.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace eprosima::fastdds::dds {
class DomainParticipant;
}

namespace saw::gateway {

struct ParticipantConfig {
  std::string name = "saw";
  int domain = 0;
  // IPv4 addresses of the interfaces DDS may use. Loopback only unless a deployment names
  // others: Fast DDS would otherwise announce itself on every interface.
  std::vector<std::string> interfaces{"127.0.0.1"};
  // Discovery beyond this subnet, where no multicast reaches (a router, a VPN): the peers' IPv4
  // addresses or host names, each tried on the well-known discovery ports of the domain's first
  // participants, or "ADDRESS:PORT" for one port. With peers, this participant announces itself
  // by unicast only. Empty: those of $ROS_STATIC_PEERS (';'-separated), as ROS 2 users set them.
  std::vector<std::string> peers{};
  // DDS Security enclave (a keystore's enclaves/NAME directory). Unset: the one the ROS 2
  // environment names (ROS_SECURITY_ENABLE, ROS_SECURITY_KEYSTORE, ROS_SECURITY_ENCLAVE_OVERRIDE),
  // else none. An enclave that does not check out is an error, never a plaintext participant.
  std::optional<std::filesystem::path> enclave{};
};

// Builtin transports off; UDPv4 on the listed interfaces only (discovery by unicast to the
// loopback peers when loopback is the only interface, and to the configured peers when there are
// any, so nothing is multicast at all), plus
// shared memory between processes on this host; with an enclave, DDS Security's builtin plugins
// (participant_security.cpp). Throws std::runtime_error on failure.
eprosima::fastdds::dds::DomainParticipant* make_participant(const ParticipantConfig& config);
// Deletes the participant and every entity it holds.
void delete_participant(eprosima::fastdds::dds::DomainParticipant* p) noexcept;

}  // namespace saw::gateway
