#include "imported_arm.hpp"

namespace saw::gateway {
namespace {

// The mapping of a CRTK member's value type (type_map.cpp has one for each).
template <class M>
const Mapping& mapping_of(M) {
  return *find_mapping(type_info_of<typename M::value_type>().name);
}

}  // namespace

template <class M>
fdds::DataReader* ImportedArm::reader(M member, const std::string& topic, Flow f) {
  return reader(std::string(member.name), topic, mapping_of(member), f);
}

ImportedArm::ImportedArm(DdsContext& dds, const ImportConfig& config)
    : Task(config.component, TaskConfig::periodic(std::chrono::milliseconds(1), 0)), dds_(dds) {
  namespace arm = crtk::arm;
  const std::string prefix =
      "rt/" + (config.ros_namespace.empty() ? "" : config.ros_namespace + "/") + config.arm + "/";
  // The topics are the CRTK names under the arm's namespace, as the dVRK publishes them.
  const auto topic = [&](auto m) { return reader(m, prefix + std::string(m.name), Flow::state); };
  cp_ = topic(arm::measured_cp);
  cv_ = topic(arm::measured_cv);
  js_ = topic(arm::measured_js);
  state_ =
      reader(arm::operating_state_event, prefix + std::string(arm::operating_state_event.name), Flow::event);
  if (!config.clutch_topic.empty()) clutch_ = reader(arm::clutch, config.clutch_topic, Flow::event);
  if (!config.operator_present_topic.empty())
    operator_ = reader(arm::operator_present, config.operator_present_topic, Flow::event);

  auto& st = state_table();
  auto& p = provide(std::string(arm::interface_name));
  crtk::provide(p, arm::measured_cp, st, &measured_cp_);
  crtk::provide(p, arm::measured_cv, st, &measured_cv_);
  crtk::provide(p, arm::measured_js, st, &measured_js_);
  crtk::provide(p, arm::operating_state, st, &operating_state_);
  state_event_ = &crtk::provide(p, arm::operating_state_event);
  clutch_event_ = &crtk::provide(p, arm::clutch);
  operator_event_ = &crtk::provide(p, arm::operator_present);
}

fdds::DataReader* ImportedArm::reader(const std::string& name, const std::string& topic, const Mapping& m,
                                      Flow f) {
  EndpointInfo e;
  e.component = this->name();
  e.interface_name = crtk::arm::interface_name;
  e.name = name;
  e.kind = "import";
  e.saw_type = m.saw_type();
  e.saw_size = static_cast<std::uint32_t>(m.size());
  e.saw_version = m.saw_version();
  e.dds_type = m.dds_type();
  e.topic = topic;
  endpoints_.push_back(std::move(e));
  // State streams: best effort matches both best-effort and reliable publishers (ROS 2's default).
  auto* r = dds_.subscriber->create_datareader(dds_.topic(topic, m), DdsContext::reader_qos(f));
  if (r == nullptr) throw std::runtime_error("import: could not subscribe to " + topic);
  return r;
}

template <class T>
bool ImportedArm::take_newest(fdds::DataReader* r, T& out) {
  if (r == nullptr) return false;
  const Mapping& m = *find_mapping(type_info_of<T>().name);  // every CRTK value type has one
  bool got = false;
  std::string why;
  T v{};
  for (;;) {
    const auto t = m.take(*r, &v, why);
    if (t == Mapping::Take::none) break;
    if (t == Mapping::Take::rejected) {
      rejected_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    out = v;
    got = true;
    samples_.fetch_add(1, std::memory_order_relaxed);
  }
  return got;
}

void ImportedArm::run() {
  if (take_newest(cp_, measured_cp_)) cp_arrival_ = now();
  (void)take_newest(cv_, measured_cv_);
  (void)take_newest(js_, measured_js_);
  OperatingState s;
  if (take_newest(state_, s)) {
    const bool changed = s.state != operating_state_.state;
    operating_state_ = s;
    if (changed) (void)(*state_event_)(s);
  }
  // Buttons are events: every press and release, in order.
  for (auto [r, e] : {std::pair{clutch_, clutch_event_}, std::pair{operator_, operator_event_}}) {
    if (r == nullptr) continue;
    const Mapping& m = mapping_of(crtk::arm::clutch);
    std::string why;
    ButtonEvent b;
    for (auto t = m.take(*r, &b, why); t != Mapping::Take::none; t = m.take(*r, &b, why))
      if (t == Mapping::Take::ok) (void)(*e)(b);
  }
  // No measured_cp yet, or none for a while: the row keeps the last arrival, and ages.
  stamp_row(cp_arrival_);
}

}  // namespace saw::gateway
