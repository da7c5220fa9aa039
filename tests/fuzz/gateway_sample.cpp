// Fuzz target: what a remote DDS peer controls in the gateway. Its serialized samples (CDR, as
// received) are deserialized and converted to rt values by every registered mapping; its
// qualified-read requests (saw_msgs/Query) are deserialized and its replies' client filter
// evaluated; sawctl's text values are parsed. A conversion either rejects with a reason or yields
// a valid rt value (finite numbers, unit quaternion, a known state, at most max_joints joints).
//
// Input: byte 0 chooses what (see LLVMFuzzerTestOneInput), the rest is the sample or text.
// The reply filter lives in reply_filter.cpp's anonymous namespace: this file includes it.
#include <fastdds/rtps/common/SerializedPayload.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core_conversions.hpp"
#include "crtk_conversions.hpp"
#include "crtk_msgs/msg/OperatingStatePubSubTypes.h"
#include "crtk_msgs/msg/StringStampedPubSubTypes.h"
#include "geometry_msgs/msg/PoseStampedPubSubTypes.h"
#include "geometry_msgs/msg/TwistStampedPubSubTypes.h"
#include "geometry_msgs/msg/Vector3StampedPubSubTypes.h"
#include "geometry_msgs/msg/WrenchStampedPubSubTypes.h"
#include "reply_filter.cpp"
#include "saw/gateway/fields_conversion.hpp"
#include "saw/teleop/dds/mappings.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/teleop_law.hpp"
#include "saw_msgs/msg/ComponentDescriptionPubSubTypes.h"
#include "saw_msgs/msg/MasterSlavePubSubTypes.h"
#include "saw_msgs/msg/OffsetLimitsPubSubTypes.h"
#include "saw_msgs/msg/PredictionPubSubTypes.h"
#include "saw_msgs/msg/QueryPubSubTypes.h"
#include "saw_msgs/msg/TaskStatisticsPubSubTypes.h"
#include "sensor_msgs/msg/JointStatePubSubTypes.h"
#include "sensor_msgs/msg/JoyPubSubTypes.h"
#include "std_msgs/msg/BoolPubSubTypes.h"
#include "std_msgs/msg/Float64PubSubTypes.h"
#include "std_msgs/msg/Int64PubSubTypes.h"

namespace saw::gateway {
namespace {

using namespace conversions;
using Payload = eprosima::fastrtps::rtps::SerializedPayload_t;

[[noreturn]] void defect(const char* what) {
  std::fprintf(stderr, "gateway conversion defect: %s\n", what);
  std::abort();
}

// An exact-size copy of the peer's bytes, as Fast DDS hands a received sample to deserialize().
Payload payload_of(const std::uint8_t* data, std::size_t size) {
  Payload p(static_cast<std::uint32_t>(size));
  if (size != 0) std::memcpy(p.data, data, size);
  p.length = static_cast<std::uint32_t>(size);
  return p;
}

bool finite3(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// What the rt side may assume of every value a mapping accepts.
void check(const Pose& p) {
  const auto& q = p.orientation;
  if (!finite3(p.position) ||
      std::abs(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) - 1) > 1e-3)
    defect("pose not finite or not a unit quaternion");
}
void check(const Twist& t) {
  if (!finite3(t.linear) || !finite3(t.angular)) defect("twist not finite");
}
void check(const Wrench& w) {
  if (!finite3(w.force) || !finite3(w.torque)) defect("wrench not finite");
}
void check(const Vec3& v) {
  if (!finite3(v)) defect("vector not finite");
}
void check(const JointState& j) {
  if (j.size > JointState::max_joints) defect("too many joints");
  if (!JointState::valid(j)) defect("joint names not bounded, terminated, one per joint or none");
  for (std::uint32_t i = 0; i < j.size; ++i)
    if (!std::isfinite(j.position[i]) || !std::isfinite(j.velocity[i]) || !std::isfinite(j.effort[i]))
      defect("joint not finite");
}
void check(const OperatingState& s) {
  if (static_cast<unsigned>(s.state) > static_cast<unsigned>(OperatingStateValue::fault))
    defect("unknown operating state");
}
void check(const StateCommand& c) {
  if (static_cast<unsigned>(c) > static_cast<unsigned>(StateCommand::home)) defect("unknown state command");
}
void check(const ButtonEvent&) {}
void check(const FaultInfo&) {}
void check(double d) {
  if (!std::isfinite(d)) defect("double not finite");
}
void check(std::int64_t) {}
void check(bool) {}
void check(const TaskStatistics& t) {
  if (!std::isfinite(t.mean_compute)) defect("task statistics not finite");
}
void check(const teleop::Gains& g) {
  if (!std::isfinite(g.master) || !std::isfinite(g.slave)) defect("gains not finite");
}
void check(const teleop::ForceLimits& l) {
  if (!std::isfinite(l.master) || !std::isfinite(l.slave)) defect("force limits not finite");
}
// Each carries its own range (valid), checked where a value enters from another process.
void check(const teleop::OffsetLimits& l) {
  if (!teleop::OffsetLimits::valid(l)) defect("offset limits out of their range");
}
void check(const teleop::Prediction& p) {
  if (!teleop::Prediction::valid(p)) defect("prediction out of its range");
}
void check(const ComponentDescription& d) {
  if (d.setting_count > ComponentDescription::max_settings) defect("too many settings");
  for (std::size_t i = 0; i < d.setting_count; ++i)
    if (!(d.settings[i].min <= d.settings[i].max)) defect("setting bounds not in order");
  for (const auto& r : d.roles)
    if (r.back() != '\0') defect("role not terminated");
}

// A sample of message Msg from a peer, as Typed<...>::take converts it.
template <class Rt, class Msg, class PubSub, class Conv>
void sample(const std::uint8_t* data, std::size_t size) {
  PubSub type;
  Payload p = payload_of(data, size);
  Msg m;
  try {
    if (!type.deserialize(&p, &m)) return;
  } catch (const eprosima::fastcdr::exception::Exception&) {
    return;  // refused by take_next() in type_map.cpp (crash-bad-encapsulation)
  }
  Rt v{};
  std::string why;
  if (!Conv::from_msg(m, v, why)) {
    if (why.empty()) defect("rejected without a reason");
    return;
  }
  check(v);
  (void)Conv::text(v);
}

// The mappings the gateway would have: the core's and the teleop package's (as its module adds).
const MappingRegistry& mappings() {
  static const MappingRegistry r = [] {
    MappingRegistry x = core_mappings();
    teleop::dds::register_mappings(x);
    return x;
  }();
  return r;
}

template <class Rt, class Msg, class PubSub, class Conv>
struct Entry {
  static void run(const std::uint8_t* d, std::size_t n) { sample<Rt, Msg, PubSub, Conv>(d, n); }
  // This list must be the registry's: the same rt type for the same DDS type.
  static bool listed() {
    const Mapping* m = mappings().find(type_info_of<Rt>().name);
    return m != nullptr && m->dds_type() == PubSub().getName();
  }
};

using namespace geometry_msgs::msg;
template <class T, class M, class P>
using Data = Entry<T, M, P, DataConv<T, M>>;
using Samples = std::tuple<
    Entry<Pose, PoseStamped, PoseStampedPubSubType, PoseConv>,
    Entry<Twist, TwistStamped, TwistStampedPubSubType, TwistConv>,
    Entry<Wrench, WrenchStamped, WrenchStampedPubSubType, WrenchConv>,
    Entry<Vec3, Vector3Stamped, Vector3StampedPubSubType, Vec3Conv>,
    Entry<JointState, sensor_msgs::msg::JointState, sensor_msgs::msg::JointStatePubSubType, JointStateConv>,
    Entry<OperatingState, crtk_msgs::msg::OperatingState, crtk_msgs::msg::OperatingStatePubSubType,
          OperatingStateConv>,
    Entry<StateCommand, crtk_msgs::msg::StringStamped, crtk_msgs::msg::StringStampedPubSubType,
          StateCommandConv>,
    Entry<FaultInfo, crtk_msgs::msg::StringStamped, crtk_msgs::msg::StringStampedPubSubType, FaultInfoConv>,
    Entry<ButtonEvent, sensor_msgs::msg::Joy, sensor_msgs::msg::JoyPubSubType, ButtonConv>,
    Data<double, std_msgs::msg::Float64, std_msgs::msg::Float64PubSubType>,
    Data<std::int64_t, std_msgs::msg::Int64, std_msgs::msg::Int64PubSubType>,
    Data<bool, std_msgs::msg::Bool, std_msgs::msg::BoolPubSubType>,
    Entry<teleop::Gains, saw_msgs::msg::MasterSlave, saw_msgs::msg::MasterSlavePubSubType,
          FieldsConv<teleop::Gains, saw_msgs::msg::MasterSlave>>,
    Entry<teleop::ForceLimits, saw_msgs::msg::MasterSlave, saw_msgs::msg::MasterSlavePubSubType,
          FieldsConv<teleop::ForceLimits, saw_msgs::msg::MasterSlave>>,
    Entry<TaskStatistics, saw_msgs::msg::TaskStatistics, saw_msgs::msg::TaskStatisticsPubSubType,
          TaskStatisticsConv>,
    Entry<ComponentDescription, saw_msgs::msg::ComponentDescription,
          saw_msgs::msg::ComponentDescriptionPubSubType, DescriptionConv>,
    // Appended, so that the corpus's earlier kinds keep their first byte.
    Entry<teleop::OffsetLimits, saw_msgs::msg::OffsetLimits, saw_msgs::msg::OffsetLimitsPubSubType,
          FieldsConv<teleop::OffsetLimits, saw_msgs::msg::OffsetLimits>>,
    Entry<teleop::Prediction, saw_msgs::msg::Prediction, saw_msgs::msg::PredictionPubSubType,
          FieldsConv<teleop::Prediction, saw_msgs::msg::Prediction>>>;
constexpr std::size_t sample_kinds = std::tuple_size_v<Samples>;

void run_sample(std::size_t kind, const std::uint8_t* d, std::size_t n) {
  [&]<std::size_t... I>(std::index_sequence<I...>) {
    ((kind == I ? std::tuple_element_t<I, Samples>::run(d, n) : void()), ...);
  }
  (std::make_index_sequence<sample_kinds>{});
}

const bool list_checked = [] {
  const bool all = [&]<std::size_t... I>(std::index_sequence<I...>) {
    return (std::tuple_element_t<I, Samples>::listed() && ...);
  }
  (std::make_index_sequence<sample_kinds>{});
  if (!all || mappings().all().size() != sample_kinds)
    defect("the fuzzer's list differs from the registry's mappings");
  return true;
}();

// A qualified-read request as the gateway's query thread takes it.
void query(const std::uint8_t* d, std::size_t n) {
  saw_msgs::msg::QueryPubSubType type;
  Payload p = payload_of(d, n);
  saw_msgs::msg::Query q;
  try {
    if (type.deserialize(&p, &q)) (void)q.data().size();
  } catch (const eprosima::fastcdr::exception::Exception&) {  // dropped by serve_queries()
  }
}

// The reply filter on any payload (it reads the serialized `client` itself).
void reply_filter(const std::uint8_t* d, std::size_t n) {
  Payload p = payload_of(d, n);
  const ClientFilter filter(42);
  (void)filter.evaluate(p, {}, {});
}

// sawctl call: text parsed into a value and validated as a sample.
void from_text(const std::uint8_t* d, std::size_t n) {
  if (n == 0) return;
  const Mapping& m = *mappings().all()[d[0] % sample_kinds];
  alignas(16) std::byte value[sizeof(JointState)];
  std::string why;
  if (!m.from_text(std::string_view(reinterpret_cast<const char*>(d + 1), n - 1), value, why) && why.empty())
    defect("text rejected without a reason");
}

}  // namespace
}  // namespace saw::gateway

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace saw::gateway;
  if (size == 0) return 0;
  const std::size_t what = data[0], kinds = sample_kinds;
  if (what < kinds)
    run_sample(what, data + 1, size - 1);
  else if (what == kinds)
    query(data + 1, size - 1);
  else if (what == kinds + 1)
    reply_filter(data + 1, size - 1);
  else if (what == kinds + 2)
    from_text(data + 1, size - 1);
  return 0;
}
