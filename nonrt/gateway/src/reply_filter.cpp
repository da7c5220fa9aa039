#include "reply_filter.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fastdds/dds/topic/IContentFilter.hpp>
#include <fastdds/dds/topic/IContentFilterFactory.hpp>

namespace saw::gateway {
namespace {

namespace fdds = eprosima::fastdds::dds;
using ReturnCode_t = eprosima::fastrtps::types::ReturnCode_t;

class ClientFilter final : public fdds::IContentFilter {
 public:
  explicit ClientFilter(std::uint64_t client) : client_(client) {}
  // XCDR1: 4 bytes of encapsulation (byte 1 odd: little endian), then the uint64 `client`.
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo&, const GUID_t&) const override {
    if (payload.data == nullptr || payload.length < 12) return false;
    std::uint8_t b[8];
    std::memcpy(b, payload.data + 4, 8);
    const bool little = (payload.data[1] & 1) != 0;
    std::uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= static_cast<std::uint64_t>(b[little ? k : 7 - k]) << (8 * k);
    return v == client_;
  }

 private:
  std::uint64_t client_;
};

class ClientFilterFactory final : public fdds::IContentFilterFactory {
 public:
  ReturnCode_t create_content_filter(const char*, const char*, const fdds::TopicDataType*,
                                     const char* expression, const ParameterSeq& parameters,
                                     fdds::IContentFilter*& filter) override {
    // Called with a null expression when only the parameters change.
    if (expression != nullptr && std::strcmp(expression, "client = %0") != 0)
      return ReturnCode_t::RETCODE_BAD_PARAMETER;
    if (parameters.length() != 1) return ReturnCode_t::RETCODE_BAD_PARAMETER;
    char* end = nullptr;
    const std::uint64_t client = std::strtoull(parameters[0], &end, 10);
    if (end == parameters[0] || *end != '\0') return ReturnCode_t::RETCODE_BAD_PARAMETER;
    if (filter != nullptr) delete static_cast<ClientFilter*>(filter);
    filter = new ClientFilter(client);
    return ReturnCode_t::RETCODE_OK;
  }
  ReturnCode_t delete_content_filter(const char*, fdds::IContentFilter* filter) override {
    delete static_cast<ClientFilter*>(filter);
    return ReturnCode_t::RETCODE_OK;
  }
};

}  // namespace

void register_reply_filter(fdds::DomainParticipant* p) {
  static ClientFilterFactory factory;  // stateless; outlives every participant
  if (p->lookup_content_filter_factory(reply_filter_class) == nullptr)
    (void)p->register_content_filter_factory(reply_filter_class, &factory);
}

}  // namespace saw::gateway
