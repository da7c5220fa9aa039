// DdsContext: the gateway's participant, publisher, subscriber and topics (internal).
#pragma once

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include "saw/gateway/type_map.hpp"

namespace saw::gateway {

namespace fdds = eprosima::fastdds::dds;

// How a topic's samples flow, which fixes its QoS on both sides:
// - state: periodic values, newest only (best effort, keep last 1);
// - event, command: every sample matters (reliable, keep last 16);
// - latched: a state a late joiner must see at once, published on change (operating states):
//   reliable, transient local, keep last 1, as ROS 2 latches a topic;
// - log: the error topic, reliable and transient local, keep last 16: a late joiner sees the
//   recent faults and refusals (and their times), a volatile reader only new ones;
// - registry: every gateway's manifest, transient local.
enum class Flow { state, event, command, latched, log, registry };

struct DdsContext {
  // The types this program maps (its own registry, handed in: no process-wide one).
  const MappingRegistry* mappings = nullptr;
  const Mapping* mapping(std::string_view saw_type) const { return registry().find(saw_type); }
  const Mapping* mapping_by_dds(std::string_view dds_type) const { return registry().find_by_dds(dds_type); }
  const MappingRegistry& registry() const {
    if (mappings == nullptr) throw std::logic_error("DDS context without a mapping registry");
    return *mappings;
  }

  fdds::DomainParticipant* participant = nullptr;
  fdds::Publisher* publisher = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  fdds::Topic* manifest_topic = nullptr;  // rt/saw/manifest, the registry

  // One Topic per name; a name already used with another type is an error naming both.
  fdds::Topic* topic(const std::string& name, const Mapping& m) {
    std::lock_guard lock(mutex_);
    if (auto it = topics_.find(name); it != topics_.end()) {
      if (it->second->get_type_name() != m.dds_type())
        throw std::runtime_error("DDS topic " + name + " is already used with type " +
                                 it->second->get_type_name() + ", not " + std::string(m.dds_type()));
      return it->second;
    }
    fdds::TypeSupport type = m.type_support();
    type.register_type(participant);
    fdds::Topic* t = participant->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    if (t == nullptr) throw std::runtime_error("DDS: could not create topic " + name);
    topics_[name] = t;
    return t;
  }

  static fdds::DataWriterQos writer_qos(Flow f) {
    fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    switch (f) {
      case Flow::state:  // the newest value is all that matters
        q.reliability().kind = fdds::BEST_EFFORT_RELIABILITY_QOS;
        q.history().depth = 1;
        break;
      case Flow::event:
      case Flow::command:
        q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
        q.history().depth = 16;
        break;
      case Flow::latched:
      case Flow::registry:  // late joiners (sawctl) get every gateway's last manifest
        q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
        q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
        q.history().depth = 1;
        break;
      case Flow::log:
        q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
        q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
        q.history().depth = 16;
        break;
    }
    // No data-sharing: its /dev/shm files outlive a killed process; the SHM transport (loopback
    // deployments) already avoids the network stack between processes of one host.
    q.data_sharing().off();
    // A lost sample is repaired, and an acknowledgment asked for, within 50 ms (default: 3 s).
    q.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 50'000'000);
    return q;
  }

  static fdds::DataReaderQos reader_qos(Flow f) {
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    // The registry is unkeyed: one instance for all gateways, so keep enough for each's newest.
    q.history().depth = f == Flow::state || f == Flow::latched ? 1 : f == Flow::registry ? 256 : 16;
    q.reliability().kind =
        f == Flow::state ? fdds::BEST_EFFORT_RELIABILITY_QOS : fdds::RELIABLE_RELIABILITY_QOS;
    if (f == Flow::registry || f == Flow::latched || f == Flow::log)
      q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
    q.data_sharing().off();
    return q;
  }

 private:
  std::mutex mutex_;
  std::map<std::string, fdds::Topic*> topics_;
};

}  // namespace saw::gateway
