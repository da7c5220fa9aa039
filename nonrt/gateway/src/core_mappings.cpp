// The rt core's types over DDS: one registration line each, made when the registry is.
#include "core_mappings.hpp"

#include <memory>

#include "core_conversions.hpp"
#include "crtk_conversions.hpp"
#include "crtk_msgs/msg/OperatingStatePubSubTypes.h"
#include "crtk_msgs/msg/StringStampedPubSubTypes.h"
#include "geometry_msgs/msg/PoseStampedPubSubTypes.h"
#include "geometry_msgs/msg/TwistStampedPubSubTypes.h"
#include "geometry_msgs/msg/Vector3StampedPubSubTypes.h"
#include "geometry_msgs/msg/WrenchStampedPubSubTypes.h"
#include "saw_msgs/msg/ComponentDescriptionPubSubTypes.h"
#include "saw_msgs/msg/TaskStatisticsPubSubTypes.h"
#include "sensor_msgs/msg/JointStatePubSubTypes.h"
#include "sensor_msgs/msg/JoyPubSubTypes.h"
#include "std_msgs/msg/BoolPubSubTypes.h"
#include "std_msgs/msg/EmptyPubSubTypes.h"
#include "std_msgs/msg/Float64PubSubTypes.h"
#include "std_msgs/msg/Int64PubSubTypes.h"

namespace saw::gateway {
namespace {

class EmptyMapping final : public Mapping {
 public:
  std::string_view saw_type() const override { return ""; }
  std::uint32_t saw_version() const override { return 0; }
  std::string_view dds_type() const override { return name_; }
  eprosima::fastdds::dds::TypeSupport type_support() const override {
    return eprosima::fastdds::dds::TypeSupport(new std_msgs::msg::EmptyPubSubType());
  }
  std::size_t size() const override { return 0; }
  bool write(eprosima::fastdds::dds::DataWriter& w, const void*, std::int64_t,
             std::string_view) const override {
    std_msgs::msg::Empty m;
    return w.write(&m);
  }
  Take take(eprosima::fastdds::dds::DataReader& r, void*, std::string& why) const override {
    std_msgs::msg::Empty m;
    why.clear();
    if (convert::take_next(r, m, why) == ReturnCode_t::RETCODE_OK) return Take::ok;
    return why.empty() ? Take::none : Take::rejected;
  }
  std::string to_text(const void*) const override { return "(void)"; }
  bool from_text(std::string_view text, void*, std::string& why) const override {
    if (convert::trimmed(text).empty()) return true;
    why = "a void command takes no value";
    return false;
  }

 private:
  std::string name_ = std_msgs::msg::EmptyPubSubType().getName();
};

}  // namespace

void register_core_mappings(MappingRegistry& r) {
  using namespace conversions;
  using namespace geometry_msgs::msg;
  r.add<Pose, PoseStampedPubSubType, PoseConv>();
  r.add<Twist, TwistStampedPubSubType, TwistConv>();
  r.add<Wrench, WrenchStampedPubSubType, WrenchConv>();
  r.add<Vec3, Vector3StampedPubSubType, Vec3Conv>();
  r.add<JointState, sensor_msgs::msg::JointStatePubSubType, JointStateConv>();
  r.add<OperatingState, crtk_msgs::msg::OperatingStatePubSubType, OperatingStateConv>();
  r.add<StateCommand, crtk_msgs::msg::StringStampedPubSubType, StateCommandConv>();
  // After StateCommand: a lookup by DDS type (StringStamped) still finds the state command.
  r.add<FaultInfo, crtk_msgs::msg::StringStampedPubSubType, FaultInfoConv>();
  r.add<ButtonEvent, sensor_msgs::msg::JoyPubSubType, ButtonConv>();
  r.add<double, std_msgs::msg::Float64PubSubType, DataConv<double, std_msgs::msg::Float64>>();
  r.add<std::int64_t, std_msgs::msg::Int64PubSubType, DataConv<std::int64_t, std_msgs::msg::Int64>>();
  r.add<bool, std_msgs::msg::BoolPubSubType, DataConv<bool, std_msgs::msg::Bool>>();
  r.add<TaskStatistics, saw_msgs::msg::TaskStatisticsPubSubType, TaskStatisticsConv>();
  r.add<ComponentDescription, saw_msgs::msg::ComponentDescriptionPubSubType, DescriptionConv>();
}

const Mapping& empty_mapping() {
  static const EmptyMapping m;
  return m;
}

}  // namespace saw::gateway
