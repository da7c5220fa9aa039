// The content filter that lets a qualified read's reply go to the client that asked (internal).
#pragma once

#include <fastdds/dds/domain/DomainParticipant.hpp>

namespace saw::gateway {

// Filter class "SAW_REPLY_CLIENT", expression "client = %0": passes a saw_msgs QueryReply whose
// `client` equals the parameter. It reads the serialized sample (no type object needed) and is
// registered on every participant of ours, so a gateway's reply writer evaluates its readers'
// filters itself and sends each reply to the one client that asked, not to every client.
inline constexpr const char* reply_filter_class = "SAW_REPLY_CLIENT";
void register_reply_filter(eprosima::fastdds::dds::DomainParticipant* p);

}  // namespace saw::gateway
