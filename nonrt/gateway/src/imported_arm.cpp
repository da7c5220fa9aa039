#include "imported_arm.hpp"

#include <algorithm>
#include <cstdio>

#include "crtk_conversions.hpp"
#include "std_msgs/msg/StringPubSubTypes.h"

namespace saw::gateway {
namespace {

// The mapping of a CRTK member's value type (type_map.cpp has one for each).
template <class M>
const Mapping& mapping_of(const DdsContext& dds, M) {
  return *dds.mapping(type_info_of<typename M::value_type>().name);
}

}  // namespace

template <class M>
fdds::DataReader* ImportedArm::reader(M member, const std::string& topic, Flow f) {
  return reader(std::string(member.name), topic, mapping_of(dds_, member), f);
}

ImportedArm::ImportedArm(DdsContext& dds, const ImportConfig& config)
    : Task(config.component,
           [&] {
             auto c = TaskConfig::periodic(std::chrono::milliseconds(1), 0);
             c.offset = std::chrono::nanoseconds(config.offset);
             return c;
           }()),
      dds_(dds),
      config_(config),
      interface_(config.commands.empty() ? std::string(crtk::arm::interface_name) : "dvrk") {
  namespace arm = crtk::arm;
  const std::string prefix =
      "rt/" + (config.ros_namespace.empty() ? "" : config.ros_namespace + "/") + config.arm + "/";
  // The topics are the CRTK names under the arm's namespace, as the dVRK publishes them.
  const auto topic = [&](auto m) { return reader(m, prefix + std::string(m.name), Flow::state); };
  cp_ = topic(arm::measured_cp);
  cv_ = topic(arm::measured_cv);
  js_ = topic(arm::measured_js);
  // Where the arm publishes one (a dVRK MTM's body/measured_cf).
  cf_ = reader(arm::measured_cf, prefix + "body/measured_cf", Flow::state);
  // An MTM's gripper, a PSM's jaw: whichever the arm publishes.
  gripper_ = reader(arm::gripper_measured_js, prefix + "gripper/measured_js", Flow::state);
  jaw_ = reader(arm::jaw_measured_js, prefix + "jaw/measured_js", Flow::state);
  // The dVRK latches its operating state: a gateway started after the arm was enabled gets it at
  // once (a volatile reader would wait for the next change).
  state_ = reader(arm::operating_state_event, prefix + std::string(arm::operating_state_event.name),
                  Flow::latched);
  if (!config.clutch_topic.empty()) clutch_ = reader(arm::clutch, config.clutch_topic, Flow::event);
  if (!config.operator_present_topic.empty())
    operator_ = reader(arm::operator_present, config.operator_present_topic, Flow::event);

  auto& st = state_table();
  auto& p = provide(interface_);
  crtk::provide(p, arm::measured_cp, st, &measured_cp_);
  crtk::provide(p, arm::measured_cv, st, &measured_cv_);
  crtk::provide(p, arm::measured_js, st, &measured_js_);
  crtk::provide(p, arm::measured_cf, st, &measured_cf_);
  crtk::provide(p, arm::gripper_measured_js, st, &gripper_js_);
  crtk::provide(p, arm::jaw_measured_js, st, &jaw_js_);
  crtk::provide(p, arm::operating_state, st, &operating_state_);
  state_event_ = &crtk::provide(p, arm::operating_state_event);
  clutch_event_ = &crtk::provide(p, arm::clutch);
  operator_event_ = &crtk::provide(p, arm::operator_present);
  if (!config.commands.empty()) {
    provide_commands(p, prefix);
    // What the dVRK says (std_msgs/String, latched): printed, and errors counted for the device,
    // which faults on one while it drives the arm.
    error_ = text_reader(prefix + "error");
    warning_ = text_reader(prefix + "warning");
    p.add_command_read("errors", st.add_column("errors", &errors_));
  }
}

fdds::DataReader* ImportedArm::text_reader(const std::string& name) {
  fdds::TypeSupport type(new std_msgs::msg::StringPubSubType());
  type.register_type(dds_.participant);
  fdds::Topic* t = dds_.participant->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  if (t == nullptr) throw std::runtime_error("import: could not create topic " + name);
  auto* r = dds_.subscriber->create_datareader(t, DdsContext::reader_qos(Flow::log));
  if (r == nullptr) throw std::runtime_error("import: could not subscribe to " + name);
  return r;
}

// Another process's text, printed on a terminal: one line, printable, bounded.
void ImportedArm::take_text(fdds::DataReader* r, const char* kind, bool is_error) {
  if (r == nullptr) return;
  std_msgs::msg::String m;
  fdds::SampleInfo info;
  while (r->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    std::string text = m.data().substr(0, 240);
    for (char& ch : text)
      if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ch = ' ';
    std::fprintf(stderr, "saw-gateway: import %s: the arm's %s: %s\n", name().c_str(), kind, text.c_str());
    if (is_error) ++errors_;
  }
}

void ImportedArm::provide_commands(ProvidedInterface& p, const std::string& prefix) {
  namespace arm = crtk::arm;
  const auto allowed = [&](std::string_view c) {
    return std::find(config_.commands.begin(), config_.commands.end(), c) != config_.commands.end();
  };
  state_command_ = writer("state_command", prefix + "state_command", mapping_of(dds_, arm::state_command));
  crtk::provide(p, arm::state_command, [this](const StateCommand& c) {
    if (c == StateCommand::enable) gravity_sent_ = false;
    if (matched(state_command_))
      send(state_command_, &c);
    else
      pending_state_command_ = c;  // sent once the arm's subscription matches (run())
  });
  // The dVRK has no plain servo_cf: its Cartesian wrench is body/servo_cf.
  if (allowed("servo_cf")) {
    servo_cf_ = writer("servo_cf", prefix + "body/servo_cf", mapping_of(dds_, arm::servo_cf));
    // A wrench-commanded MTM floats only with the dVRK's gravity compensation on (its own
    // teleoperation turns it on as it engages): sent once matched, again after each enable.
    gravity_ = writer("use_gravity_compensation", prefix + "use_gravity_compensation",
                      *dds_.mapping(type_info_of<bool>().name));
    crtk::provide(p, arm::servo_cf, [this](const Wrench& w) {
      const bool zero = w.force == Vec3{} && w.torque == Vec3{};
      command(servo_cf_, &w, /*motion=*/!zero);
    });
  }
  if (allowed("servo_cp")) {
    servo_cp_ = writer("servo_cp", prefix + "servo_cp", mapping_of(dds_, arm::servo_cp));
    crtk::provide(p, arm::servo_cp, [this](const Pose& x) { command(servo_cp_, &x, true); });
  }
  if (allowed("jaw_servo_jp")) {
    jaw_servo_jp_ = writer("jaw_servo_jp", prefix + "jaw/servo_jp", mapping_of(dds_, arm::jaw_servo_jp));
    crtk::provide(p, arm::jaw_servo_jp, [this](const JointState& j) { command(jaw_servo_jp_, &j, true); });
  }
  if (allowed("servo_jp")) {
    servo_jp_ = writer("servo_jp", prefix + "servo_jp", mapping_of(dds_, arm::servo_jp));
    crtk::provide(p, arm::servo_jp, [this](const JointState& j) { command(servo_jp_, &j, true); });
  }
  // A move is a trajectory the dVRK plans and ends at a checked goal: not a stream whose silence
  // means its client died (no watchdog); the exit path stops one still under way.
  if (allowed("move_cp")) {
    move_cp_ = writer("move_cp", prefix + "move_cp", mapping_of(dds_, arm::move_cp));
    crtk::provide(p, arm::move_cp, [this](const Pose& x) { command(move_cp_, &x, false, true); });
  }
  if (allowed("move_jp")) {
    move_jp_ = writer("move_jp", prefix + "move_jp", mapping_of(dds_, arm::move_jp));
    crtk::provide(p, arm::move_jp, [this](const JointState& j) { command(move_jp_, &j, false, true); });
  }
  if (allowed("hold")) {
    hold_ = writer("hold", prefix + "hold", empty_mapping());
    p.add_command_void("hold", [this] { command(hold_, nullptr, false); });
  }
  if (allowed("free")) {
    free_ = writer("free", prefix + "free", empty_mapping());
    p.add_command_void("free", [this] { command(free_, nullptr, false); });
  }
}

void ImportedArm::add_endpoint(const std::string& name, const std::string& topic, const Mapping& m,
                               const char* kind) {
  EndpointInfo e;
  e.component = this->name();
  e.interface_name = interface_;
  e.name = name;
  e.kind = kind;
  e.saw_type = m.saw_type();
  e.saw_size = static_cast<std::uint32_t>(m.size());
  e.saw_version = m.saw_version();
  e.dds_type = m.dds_type();
  e.topic = topic;
  endpoints_.push_back(std::move(e));
}

ImportedArm::Writer ImportedArm::writer(const std::string& name, const std::string& topic, const Mapping& m) {
  add_endpoint(name, topic, m, "import_command");
  // Reliable: the dVRK's subscriptions are (a best-effort writer would match none of them).
  auto qos = DdsContext::writer_qos(Flow::command);
  // Acknowledgments asked for every 5 ms (not 50): a hold waits for the motion commands before it
  // to be acknowledged, and a stop path's safe command should not wait a heartbeat for that.
  qos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 5'000'000);
  auto* w = dds_.publisher->create_datawriter(dds_.topic(topic, m), qos);
  if (w == nullptr) throw std::runtime_error("import: could not publish " + topic);
  return {w, &m};
}

bool ImportedArm::matched(const Writer& w) {
  fdds::PublicationMatchedStatus status;
  return w.writer != nullptr &&
         w.writer->get_publication_matched_status(status) == ReturnCode_t::RETCODE_OK &&
         status.current_count > 0;
}

bool ImportedArm::send(const Writer& w, const void* value) {
  // Stamped when written (not at the cycle's start): the arm side sees how long DDS took.
  const bool ok = w.mapping->write(*w.writer, value, wall_from_monotonic(monotonic_now()), config_.arm);
  if (ok) sent_.fetch_add(1, std::memory_order_relaxed);
  return ok;
}

void ImportedArm::command(const Writer& w, const void* value, bool motion, bool move) {
  last_command_ = now();
  cycles_since_command_ = 0;
  // A safe command on a topic of its own (hold) goes after every motion command: one of those
  // repaired by DDS after it would reach the arm last, and the arm would act on it.
  if (!motion && &w == &hold_) settle_motion(monotonic_now() + 50'000'000);
  if (send(w, value)) {
    moving_ = motion;
    move_sent_ = move;
  }
}

bool ImportedArm::acknowledged(const Writer& w, TimeNs deadline) {
  if (w.writer == nullptr) return true;
  const TimeNs left = std::max<TimeNs>(deadline - monotonic_now(), 0);
  return w.writer->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(
             static_cast<std::int32_t>(left / 1'000'000'000),
             static_cast<std::uint32_t>(left % 1'000'000'000))) == ReturnCode_t::RETCODE_OK;
}

void ImportedArm::settle_motion(TimeNs deadline) {
  for (const Writer* w : {&servo_cf_, &servo_cp_, &servo_jp_, &jaw_servo_jp_, &move_cp_, &move_jp_})
    (void)acknowledged(*w, deadline);
}

bool ImportedArm::send_safe_command() {
  bool ok = false;
  if (config_.safe_command == "zero_wrench") {
    const Wrench zero{};
    ok = send(servo_cf_, &zero);
  } else if (config_.safe_command == "hold") {
    settle_motion(monotonic_now() + 50'000'000);
    ok = send(hold_, nullptr);
  } else if (config_.safe_command == "servo_cp_measured" && has_cp_) {
    ok = send(servo_cp_, &measured_cp_);
  }
  if (ok) {
    moving_ = move_sent_ = false;
    safe_sent_.fetch_add(1, std::memory_order_relaxed);
  }
  return ok;
}

// The client (saw-rt's device) sends a command every cycle while it moves the arm, and its safe
// command when it stops: silence while moving means it hangs or died. Counted in this task's
// own cycles too, so that a stall of the gateway (whose client's commands then wait in the ring)
// is not taken for the client's.
void ImportedArm::watch_client() {
  if (!moving_) return;
  const int cycles = static_cast<int>(config_.command_timeout / 1'000'000);
  if (++cycles_since_command_ < cycles || now() - last_command_ < config_.command_timeout) return;
  if (send_safe_command())
    std::fprintf(
        stderr, "saw-gateway: import %s: its client sent nothing for %lld ms while moving the arm: %s sent\n",
        name().c_str(), static_cast<long long>(config_.command_timeout / 1'000'000),
        config_.safe_command.c_str());
}

void ImportedArm::leave_safely(TimeNs deadline) {
  if (config_.commands.empty()) return;
  // A move of the client's still under way (the arm busy) is stopped too.
  const bool move_running = move_sent_ && operating_state_.is_busy;
  if ((moving_ || move_running) && send_safe_command())
    std::fprintf(stderr, "saw-gateway: import %s: exiting while its client moved the arm: %s sent\n",
                 name().c_str(), config_.safe_command.c_str());
  // Whoever sent the last command (the client's own safe command, just before it stopped us, or
  // ours): it reaches the arm before our participant goes, or a loss could not be repaired.
  for (const Writer* w : {&servo_cf_, &servo_cp_, &servo_jp_, &jaw_servo_jp_, &move_cp_, &move_jp_, &hold_,
                          &free_, &state_command_})
    (void)acknowledged(*w, deadline);
}

fdds::DataReader* ImportedArm::reader(const std::string& name, const std::string& topic, const Mapping& m,
                                      Flow f) {
  add_endpoint(name, topic, m, "import");
  // State streams: best effort matches both best-effort and reliable publishers (ROS 2's default).
  auto* r = dds_.subscriber->create_datareader(dds_.topic(topic, m), DdsContext::reader_qos(f));
  if (r == nullptr) throw std::runtime_error("import: could not subscribe to " + topic);
  return r;
}

template <class T>
bool ImportedArm::take_newest(fdds::DataReader* r, T& out) {
  if (r == nullptr) return false;
  const Mapping& m = *dds_.mapping(type_info_of<T>().name);  // every CRTK value type has one
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

// measured_cp also by its header stamp, as the dVRK sends it: stamp 0 is its "no valid data"
// (cisst-ros sends an invalid sample so), and a stamp not newer than the last one's is a source
// that repeats itself. Neither is a new sample: the row's arrival stamp then ages, and the
// device faults at its stale_timeout, as it does when the stream stops.
bool ImportedArm::take_cp() {
  geometry_msgs::msg::PoseStamped m;
  fdds::SampleInfo info;
  bool got = false;
  while (cp_->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    const auto& t = m.header().stamp();
    const std::int64_t stamp = static_cast<std::int64_t>(t.sec()) * 1'000'000'000 + t.nanosec();
    if (stamp == 0) {
      invalid_stamps_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    if (stamp <= last_cp_stamp_) {
      repeated_stamps_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    Pose p;
    std::string why;
    if (!conversions::PoseConv::from_msg(m, p, why)) {
      rejected_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    last_cp_stamp_ = stamp;
    measured_cp_ = p;
    got = true;
    samples_.fetch_add(1, std::memory_order_relaxed);
  }
  return got;
}

void ImportedArm::run() {
  if (take_cp()) {
    cp_arrival_ = now();
    has_cp_ = true;
  }
  (void)take_newest(cv_, measured_cv_);
  (void)take_newest(js_, measured_js_);
  (void)take_newest(cf_, measured_cf_);
  (void)take_newest(gripper_, gripper_js_);
  (void)take_newest(jaw_, jaw_js_);
  OperatingState s;
  if (take_newest(state_, s)) {
    const bool changed = s.state != operating_state_.state;
    operating_state_ = s;
    if (changed) (void)(*state_event_)(s);
  }
  // Buttons are events: every press and release, in order.
  for (auto [r, e] : {std::pair{clutch_, clutch_event_}, std::pair{operator_, operator_event_}}) {
    if (r == nullptr) continue;
    const Mapping& m = mapping_of(dds_, crtk::arm::clutch);
    std::string why;
    ButtonEvent b;
    for (auto t = m.take(*r, &b, why); t != Mapping::Take::none; t = m.take(*r, &b, why))
      if (t == Mapping::Take::ok) (void)(*e)(b);
  }
  if (pending_state_command_ && matched(state_command_)) {
    send(state_command_, &*pending_state_command_);
    pending_state_command_.reset();
  }
  if (gravity_.writer != nullptr && !gravity_sent_ && matched(gravity_)) {
    const bool on = true;
    gravity_sent_ = send(gravity_, &on);
  }
  take_text(error_, "error", true);
  take_text(warning_, "warning", false);
  watch_client();
  // No measured_cp yet, or none for a while: the row keeps the last arrival, and ages.
  stamp_row(cp_arrival_);
}

}  // namespace saw::gateway
