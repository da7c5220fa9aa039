// Participant security: a participant's enclave turned into Fast DDS's DDS Security properties.
#pragma once

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <string>

#include "saw/gateway/participant.hpp"

namespace saw::gateway {

// Resolves the enclave (ParticipantConfig::enclave, else the ROS 2 environment), checks it
// (saw::security::load_enclave) and sets the authentication (PKI-DH), access control
// (Permissions) and cryptography (AES-GCM-GMAC) plugins on `qos`. Returns the enclave's
// directory, or "" when the participant has none. Throws std::runtime_error with the reason.
std::string apply_security(eprosima::fastdds::dds::DomainParticipantQos& qos,
                           const ParticipantConfig& config);

}  // namespace saw::gateway
