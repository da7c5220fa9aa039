#include "imported_arm.hpp"

namespace saw::gateway {

ImportedArm::ImportedArm(DdsContext& dds, const ImportConfig& config)
    : Task(config.component, TaskConfig::periodic(std::chrono::milliseconds(1), 0)), dds_(dds) {
  const std::string prefix =
      "rt/" + (config.ros_namespace.empty() ? "" : config.ros_namespace + "/") + config.arm + "/";
  cp_ = reader("measured_cp", prefix + "measured_cp", *find_mapping(type_info_of<Pose>().name), Flow::state);
  cv_ = reader("measured_cv", prefix + "measured_cv", *find_mapping(type_info_of<Twist>().name), Flow::state);
  js_ = reader("measured_js", prefix + "measured_js", *find_mapping(type_info_of<JointState>().name),
               Flow::state);
  state_ = reader("operating_state", prefix + "operating_state",
                  *find_mapping(type_info_of<OperatingState>().name), Flow::event);
  const Mapping& joy = *find_mapping(type_info_of<ButtonEvent>().name);
  if (!config.clutch_topic.empty()) clutch_ = reader("clutch", config.clutch_topic, joy, Flow::event);
  if (!config.operator_present_topic.empty())
    operator_ = reader("operator_present", config.operator_present_topic, joy, Flow::event);

  auto& st = state_table();
  auto& arm = provide("arm");
  arm.add_command_read("measured_cp", st.add_column("measured_cp", &measured_cp_));
  arm.add_command_read("measured_cv", st.add_column("measured_cv", &measured_cv_));
  arm.add_command_read("measured_js", st.add_column("measured_js", &measured_js_));
  arm.add_command_read("operating_state", st.add_column("operating_state", &operating_state_));
  state_event_ = &arm.add_event_write<OperatingState>("operating_state");
  clutch_event_ = &arm.add_event_write<ButtonEvent>("clutch");
  operator_event_ = &arm.add_event_write<ButtonEvent>("operator_present");
}

fdds::DataReader* ImportedArm::reader(const std::string& name, const std::string& topic, const Mapping& m,
                                      Flow f) {
  EndpointInfo e;
  e.component = this->name();
  e.interface_name = "arm";
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
  const Mapping& m = *find_mapping(type_info_of<T>().name);
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
    const Mapping& m = *find_mapping(type_info_of<ButtonEvent>().name);
    std::string why;
    ButtonEvent b;
    for (auto t = m.take(*r, &b, why); t != Mapping::Take::none; t = m.take(*r, &b, why))
      if (t == Mapping::Take::ok) (void)(*e)(b);
  }
  // No measured_cp yet, or none for a while: the row keeps the last arrival, and ages.
  stamp_row(cp_arrival_);
}

}  // namespace saw::gateway
