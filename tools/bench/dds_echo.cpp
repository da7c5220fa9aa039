#include "dds_echo.hpp"

#include <cstring>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>

#include "saw/gateway/participant.hpp"
#include "saw_msgs/msg/QueryPubSubTypes.h"
#include "saw_msgs/msg/QueryReplyPubSubTypes.h"

namespace saw::bench {

namespace fdds = eprosima::fastdds::dds;

// Raw Fast DDS: the same topics' types and QoS, the same WaitSet wait, answered at once.
void raw_dds_echo(const saw::gateway::ParticipantConfig& pc) {
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

}  // namespace saw::bench
