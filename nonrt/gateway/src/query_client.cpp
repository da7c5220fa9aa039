#include "saw/gateway/query_client.hpp"

#include <algorithm>
#include <cstring>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <random>

#include "dds_context.hpp"
#include "reply_filter.hpp"
#include "saw_msgs/msg/QueryPubSubTypes.h"
#include "saw_msgs/msg/QueryReplyPubSubTypes.h"

namespace saw::gateway {

struct QueryClient::Impl {
  fdds::DomainParticipant* participant;
  fdds::Publisher* publisher = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  fdds::Topic *request_topic = nullptr, *reply_topic = nullptr;
  fdds::ContentFilteredTopic* my_replies = nullptr;
  fdds::DataWriter* writer = nullptr;
  fdds::DataReader* reader = nullptr;
  fdds::WaitSet waitset;
  std::uint64_t id = (std::random_device{}() * 0x100000001ULL ^ static_cast<std::uint64_t>(monotonic_now()));
  std::uint64_t sequence = 0;
  saw_msgs::msg::Query request;
  saw_msgs::msg::QueryReply reply;
};

namespace {
fdds::Topic* topic(fdds::DomainParticipant* p, const std::string& name, fdds::TopicDataType* type) {
  fdds::TypeSupport t(type);
  t.register_type(p);
  if (auto* d = p->lookup_topicdescription(name)) return dynamic_cast<fdds::Topic*>(d);
  return p->create_topic(name, t.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
}
}  // namespace

QueryClient::QueryClient(fdds::DomainParticipant* participant, const std::string& component,
                         const std::string& command)
    : impl_(std::make_unique<Impl>()) {
  auto& i = *impl_;
  i.participant = participant;
  i.publisher = participant->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  i.subscriber = participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  i.request_topic =
      topic(participant, "rq/" + component + "/" + command + "Request", new saw_msgs::msg::QueryPubSubType());
  i.reply_topic = topic(participant, "rr/" + component + "/" + command + "Reply",
                        new saw_msgs::msg::QueryReplyPubSubType());
  i.writer = i.publisher->create_datawriter(i.request_topic, DdsContext::writer_qos(Flow::command));
  // Only this client's replies: with the filter in the reader's discovery data, Fast DDS's
  // writer sends them to this reader alone instead of to every client of the command.
  const std::string filtered = "rr/" + component + "/" + command + "Reply/" + std::to_string(i.id);
  register_reply_filter(participant);
  i.my_replies = participant->create_contentfilteredtopic(filtered, i.reply_topic, "client = %0",
                                                          {std::to_string(i.id)}, reply_filter_class);
  if (i.my_replies != nullptr)
    i.reader = i.subscriber->create_datareader(i.my_replies, DdsContext::reader_qos(Flow::command));
  if (i.writer == nullptr || i.reader == nullptr)
    throw std::runtime_error(
        "query client: could not create the request writer or the filtered reply reader");
  i.reader->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
  i.waitset.attach_condition(i.reader->get_statuscondition());
}

QueryClient::~QueryClient() {
  auto& i = *impl_;
  i.waitset.detach_condition(i.reader->get_statuscondition());
  i.subscriber->delete_datareader(i.reader);
  i.participant->delete_contentfilteredtopic(i.my_replies);
  i.publisher->delete_datawriter(i.writer);
  i.participant->delete_subscriber(i.subscriber);
  i.participant->delete_publisher(i.publisher);
}

bool QueryClient::wait_matched(TimeNs timeout) {
  const TimeNs deadline = monotonic_now() + timeout;
  for (;;) {
    fdds::PublicationMatchedStatus pub;
    fdds::SubscriptionMatchedStatus sub;
    impl_->writer->get_publication_matched_status(pub);
    impl_->reader->get_subscription_matched_status(sub);
    if (pub.current_count > 0 && sub.current_count > 0) return true;
    if (monotonic_now() >= deadline) return false;
    timespec ts{0, 5'000'000};
    nanosleep(&ts, nullptr);
  }
}

Status QueryClient::call(const void* arg, std::size_t arg_size, void* result, std::size_t result_size,
                         TimeNs timeout) {
  auto& i = *impl_;
  i.request.client(i.id);
  i.request.number(++i.sequence);
  i.request.data().resize(arg_size);
  std::memcpy(i.request.data().data(), arg, arg_size);
  if (!i.writer->write(&i.request)) return Status::disconnected;
  const TimeNs deadline = monotonic_now() + timeout;
  // Several tries fit in every call's timeout (a resend only after the timeout never happened).
  const TimeNs resend_every = std::clamp<TimeNs>(timeout / 8, 10'000'000, 100'000'000);
  TimeNs resend_at = monotonic_now() + resend_every;
  fdds::SampleInfo info;
  for (;;) {
    while (i.reader->take_next_sample(&i.reply, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || i.reply.client() != i.id || i.reply.number() != i.sequence) continue;
      const auto st = static_cast<Status>(i.reply.status());
      if (st != Status::ok) return st;
      if (i.reply.data().size() != result_size) return Status::invalid;
      std::memcpy(result, i.reply.data().data(), result_size);
      return Status::ok;
    }
    const TimeNs now = monotonic_now();
    if (now >= deadline) return Status::timeout;
    // Our reader may be matched before the gateway's reply writer has discovered it (matching
    // is seen from each side in its own time), and a volatile writer drops a reply for a reader
    // it does not know yet. A qualified read is const: asking again is harmless, and a reply to
    // either request answers it.
    if (now >= resend_at) {
      if (!i.writer->write(&i.request)) return Status::disconnected;
      resend_at = now + resend_every;
    }
    const TimeNs left = std::min(deadline, resend_at) - now;
    fdds::ConditionSeq active;
    i.waitset.wait(active, eprosima::fastrtps::Duration_t(static_cast<std::int32_t>(left / 1'000'000'000),
                                                          static_cast<std::uint32_t>(left % 1'000'000'000)));
  }
}

}  // namespace saw::gateway
